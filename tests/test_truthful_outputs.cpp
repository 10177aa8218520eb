// Issue 67: writes that cannot lie, one check of every robot description, and decoders whose memory
// is bounded by their input, each through the dyncal command as a user runs it.
// - A full disk (a 4 KiB tmpfs; where mounting is not allowed, the same failure through RLIMIT_FSIZE)
//   ends identify with one line and exit 2, and leaves the previous parameter and report files.
// - An output that is not a regular file (a FIFO, a character device, a folder) or lies in a missing
//   folder is refused before any work and left as it was; new files get 0666 less the umask.
// - A robot.json the tools would misread is refused by identify, by robot check and by Python
//   alike, with the same first line; an MDH robot's link edited since the build is named.
// - An MCAP file whose zstd chunk expands to 2 GiB (stated size and CRC right) is refused with a
//   bounded peak memory.
#include <gtest/gtest.h>
#include <sys/mount.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "dyncal_host/logs/joint_log.hpp"
#include "support/dyncal_cli.hpp"
#include "support/simulated_log.hpp"
#include "support/test_paths.hpp"

namespace {

namespace fs = std::filesystem;
using namespace dyncal::host;
using namespace dyncal::test;

std::string slurp_file(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

struct Outcome {
  int code = -1;
  std::string err;
};

/// `PREFIX dyncal ARGS` through the shell, stdout discarded: its exit code and stderr.
Outcome dyncal_run(const std::string& args, const fs::path& dir, const std::string& prefix = "") {
  const std::string cmd =
      prefix + std::string(dyncal_binary()) + " " + args + " >/dev/null 2>" + (dir / "err.txt").string();
  const int status = std::system(("bash -c '" + cmd + "'").c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp_file(dir / "err.txt")};
}

long lines_of(const std::string& s) {
  return std::count(s.begin(), s.end(), '\n');
}

class TruthfulOutputs : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dyncal_outputs_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    if (mounted_) ::umount((dir_ / "full").c_str());
    fs::remove_all(dir_);
  }
  /// A 10 s simulated log of the test arm arm3 (robots under tests/robots).
  std::string arm3_log() {
    const std::string path = (dir_ / "arm3.csv").string();
    write_csv_log(path, simulate(test_robot("arm3"), uniform_times(200.0, 10.0), MotionClock{}, 5, 3).log);
    return path;
  }
  std::string arm3_robots() const { return " --robots-dir " + std::string(source_dir()) + "/tests/robots"; }

  fs::path dir_;
  bool mounted_ = false;
};

TEST_F(TruthfulOutputs, AFullDiskEndsIdentifyWithOneLineAndLeavesThePreviousFiles) {
  const std::string log = arm3_log();
  const fs::path full = dir_ / "full";
  fs::create_directories(full);
  // A small tmpfs, filled, where this process may mount one (root, as in CI); else the same failure
  // of write(2) from a file-size limit of 1 KiB on the dyncal process.
  mounted_ = ::mount("tmpfs", full.c_str(), "tmpfs", 0, "size=64k") == 0;
  const std::string prefix = mounted_ ? "" : "ulimit -f 1; trap \"\" XFSZ; ";
  std::ofstream(full / "p.json") << "previous parameters\n";
  std::ofstream(full / "r.json") << "previous report\n";
  if (mounted_) {
    std::ofstream filler(full / "filler", std::ios::binary);
    const std::string block(4096, '\0');
    for (int k = 0; k < 64 && filler.write(block.data(), 4096).flush(); ++k) {
    }
  }
  const Outcome o = dyncal_run("identify --robot arm3" + arm3_robots() + " --data " + log + " --params " +
                                   (full / "p.json").string() + " --report " + (full / "r.json").string(),
                               dir_, prefix);
  EXPECT_EQ(o.code, 2) << o.err;
  EXPECT_EQ(lines_of(o.err), 1) << o.err;
  EXPECT_NE(o.err.find(mounted_ ? "No space left on device" : "File too large"), std::string::npos) << o.err;
  EXPECT_EQ(slurp_file(full / "p.json"), "previous parameters\n");
  EXPECT_EQ(slurp_file(full / "r.json"), "previous report\n");
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(full)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left.size(), mounted_ ? 3u : 2u) << "a temporary file was left behind";
  // With room, the same command writes both files whole.
  if (mounted_) {
    ::umount(full.c_str());
    mounted_ = false;
  }
  const Outcome ok = dyncal_run("identify --robot arm3" + arm3_robots() + " --data " + log + " --params " +
                                    (full / "p.json").string() + " --report " + (full / "r.json").string(),
                                dir_);
  ASSERT_EQ(ok.code, 0) << ok.err;
  EXPECT_NO_THROW((void)nlohmann::json::parse(slurp_file(full / "p.json")));
  EXPECT_NO_THROW((void)nlohmann::json::parse(slurp_file(full / "r.json")));
}

TEST_F(TruthfulOutputs, OutputsThatAreNotRegularFilesAreRefusedAndLeftAsTheyWere) {
  const fs::path fifo = dir_ / "fifo", device = dir_ / "full_device", folder = dir_ / "folder";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  fs::create_directories(folder);
  const bool have_device = ::mknod(device.c_str(), S_IFCHR | 0666, makedev(1, 7)) == 0;  // /dev/full's
  std::vector<std::pair<fs::path, std::string>> cases = {
      {fifo, "not a regular file"}, {folder, "is a folder"}, {dir_ / "missing" / "x.json", "no folder"}};
  if (have_device) cases.push_back({device, "not a regular file"});
  const std::string params = (dir_ / "params.json").string();
  std::ofstream(params) << "{}\n";
  for (const auto& [path, needle] : cases) {
    for (const std::string& args : {"identify --robot arm3" + arm3_robots() + " --data " +
                                        (dir_ / "none.csv").string() + " --params " + path.string(),
                                    "export urdf --params " + params + " --out " + path.string() + arm3_robots()}) {
      const Outcome o = dyncal_run(args, dir_);
      EXPECT_EQ(o.code, 2) << args << ": " << o.err;
      EXPECT_EQ(lines_of(o.err), 1) << o.err;
      EXPECT_NE(o.err.find(needle), std::string::npos) << args << ": " << o.err;
      EXPECT_EQ(o.err.find("internal error"), std::string::npos) << o.err;
    }
  }
  struct stat st {};
  ASSERT_EQ(::lstat(fifo.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  if (have_device) {
    ASSERT_EQ(::lstat(device.c_str(), &st), 0);
    EXPECT_TRUE(S_ISCHR(st.st_mode));
  }
  EXPECT_FALSE(fs::exists(dir_ / "missing"));
}

TEST_F(TruthfulOutputs, NewFilesTakeTheUmaskAndReplacedFilesKeepTheirMode) {
  const std::string log = arm3_log();
  for (const char* mask : {"022", "077"}) {
    const fs::path p = dir_ / (std::string("p") + mask + ".json");
    const Outcome o = dyncal_run("identify --robot arm3" + arm3_robots() + " --data " + log + " --params " + p.string(),
                                 dir_, std::string("umask ") + mask + "; ");
    ASSERT_EQ(o.code, 0) << o.err;
    struct stat st {};
    ASSERT_EQ(::stat(p.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0666u & ~std::stoul(mask, nullptr, 8)) << mask;
  }
  const fs::path kept = dir_ / "p022.json";
  fs::permissions(kept, fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read);
  ASSERT_EQ(dyncal_run("identify --robot arm3" + arm3_robots() + " --data " + log + " --params " + kept.string(), dir_,
                       "umask 077; ")
                .code,
            0);
  struct stat st {};
  ASSERT_EQ(::stat(kept.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0640u);
}

/// robots/er20 (an MDH robot) copied under dir with `edit` applied to its robot.json.
fs::path er20_edited(const fs::path& dir, const std::function<void(nlohmann::json&)>& edit) {
  const fs::path robots = dir / "robots";
  fs::remove_all(robots);
  fs::create_directories(robots);
  fs::copy(std::string(source_dir()) + "/robots/er20", robots / "er20");
  nlohmann::json j = nlohmann::json::parse(slurp_file(std::string(source_dir()) + "/robots/er20/robot.json"));
  edit(j);
  std::ofstream(robots / "er20" / "robot.json") << j.dump(2) << "\n";
  return robots;
}

TEST_F(TruthfulOutputs, ARobotDescriptionIsCheckedAlikeByEveryCommand) {
  struct Case {
    const char* what;
    std::function<void(nlohmann::json&)> edit;
    const char* needle;
  };
  const std::vector<Case> cases = {
      {"links missing", [](nlohmann::json& j) { j.erase("links"); }, "links: expected one"},
      {"mass a string", [](nlohmann::json& j) { j["links"][1]["mass"] = "60"; }, "links[2].mass: expected a number"},
      {"mass negative", [](nlohmann::json& j) { j["links"][1]["mass"] = -5; }, "links[2].mass: must be >= 0"},
      {"mass 0 with inertia", [](nlohmann::json& j) { j["links"][1]["mass"] = 0; }, "an inertia without mass"},
      {"inertia 1e308", [](nlohmann::json& j) { j["links"][2]["inertia"][0] = 1e308; }, "links[3].inertia[1] 1e+308"},
      {"mass edited since the build", [](nlohmann::json& j) { j["links"][1]["mass"] = 41.0; },
       "links[2].mass 41 differs from the compiled model's 40"},
      {"five joint names", [](nlohmann::json& j) { j["joint_names"].erase(5); }, "joint_names: expected a list of 6"},
      {"a row missing", [](nlohmann::json& j) { j["kinematics"]["joints"][0].erase("d"); },
       "kinematics.joints[1].d: missing"},
  };
  for (const Case& c : cases) {
    const fs::path robots = er20_edited(dir_, c.edit);
    const std::string r = " --robots-dir " + robots.string();
    for (const std::string& args : {"identify --robot er20" + r + " --data " + (dir_ / "none.csv").string(),
                                    "robot check er20" + r, "drive --robot er20" + r + " --tcp 127.0.0.1:0"}) {
      const Outcome o = dyncal_run(args, dir_, "timeout 20 ");
      EXPECT_EQ(o.code, 2) << c.what << ": " << args << ": " << o.err;
      EXPECT_EQ(lines_of(o.err), 1) << c.what << ": " << args << ": " << o.err;
      EXPECT_NE(o.err.find(c.needle), std::string::npos) << c.what << ": " << args << ": " << o.err;
    }
  }
  // The unedited copy passes all three checks' first step (robot check says valid).
  const fs::path robots = er20_edited(dir_, [](nlohmann::json&) {});
  const Outcome o = dyncal_run("robot check er20 --robots-dir " + robots.string(), dir_);
  EXPECT_EQ(o.code, 0) << o.err;
}

// A log that cannot carry the model (3 s, and joint 2's torque pure noise, unrelated to the motion):
// the fit predicts joint 2's unseen samples worse than a constant (validation R^2 < 0). It used to
// exit 0 with R^2 -2e7 and no word; the report now says so in a note naming the joint.
TEST_F(TruthfulOutputs, AJointTheFitPredictsWorseThanAConstantIsNamed) {
  JointLog log = simulate(test_robot("arm3"), uniform_times(200.0, 3.0), MotionClock{}, 5, 3).log;
  std::mt19937_64 rng(67);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (Eigen::Index k = 0; k < log.samples(); ++k) log.tau(k, 1) = noise(rng);
  const std::string path = (dir_ / "noise.csv").string(), report = (dir_ / "r.json").string();
  write_csv_log(path, log);
  const Outcome o =
      dyncal_run("identify --robot arm3" + arm3_robots() + " --data " + path + " --report " + report, dir_);
  ASSERT_EQ(o.code, 0) << o.err;
  const nlohmann::json r = nlohmann::json::parse(slurp_file(report));
  std::string notes;
  for (const auto& n : r["notes"]) notes += n.get<std::string>() + "\n";
  double r2 = 0;
  for (const auto& j : r["joints"])
    if (j["joint"] == 2) r2 = j["r2_validation"].get<double>();
  ASSERT_LT(r2, 0) << "the test's log does not produce the case";
  EXPECT_NE(notes.find("joint 2: validation R^2"), std::string::npos) << notes;
  EXPECT_NE(notes.find("predicts unseen data worse than a constant"), std::string::npos) << notes;
  for (const auto& j : r["joints"])
    if (j["r2_validation"].get<double>() >= 0)
      EXPECT_EQ(notes.find("joint " + std::to_string(j["joint"].get<int>()) + ": validation R^2"), std::string::npos);
}

TEST_F(TruthfulOutputs, ABagWhoseChunkExpandsToGigabytesIsRefusedWithBoundedMemory) {
  const fs::path bomb = dir_ / "bomb.mcap";
  const std::string writer = std::string(source_dir()) + "/tests/tools/write_mcap_bomb.py";
  ASSERT_EQ(std::system(("/usr/bin/python3 " + writer + " " + bomb.string() + " --expands-to 2147483648").c_str()), 0);
  const auto [rss, code] =
      peak_rss_and_exit_code({"identify", "--robot", "tx40", "--effort", "torque", "--data", bomb.string()});
  EXPECT_EQ(code, 2);
  EXPECT_GT(rss, 0);
  EXPECT_LT(rss, 100L << 20) << "peak RSS " << rss << " bytes for a " << fs::file_size(bomb) << "-byte file";
  const Outcome o = dyncal_run("identify --robot tx40 --effort torque --data " + bomb.string(), dir_);
  EXPECT_NE(o.err.find("decompresses to more than the"), std::string::npos) << o.err;
  EXPECT_EQ(lines_of(o.err), 1) << o.err;
}

}  // namespace
