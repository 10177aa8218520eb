// ROS 2 bags as logs (docs/cli.md, "Logs"): the shipped TX40 log written as JointState bags by an
// independent writer (tests/tools/write_ros2_bag.py: MCAP with zstd chunks and rosbag2's SQLite3
// storage; joints shuffled with an extra one, gripper-only messages and another topic mixed in)
// identifies bit-identically to the CSV of the same samples; lz4 chunks, zstd file and message
// compression, a bag's file or its folder read alike;
// corrupt, truncated and ambiguous bags are refused with one line and exit 2.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/logs/joint_log.hpp"
#include "support/dyncal_cli.hpp"
#include "support/test_paths.hpp"

namespace {

namespace fs = std::filesystem;
using dyncal::test::read_json;

const std::string kWriter = std::string(dyncal::test::source_dir()) + "/tests/tools/write_ros2_bag.py";
const std::string kModel = " --robot tx40 --model eq7,rotor_inertia,offset";

struct CliRun {
  int code = -1;
  std::string out, err;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// `dyncal ARGS` with stdout and stderr captured.
CliRun dyncal(const std::string& args, const fs::path& dir) {
  const std::string cmd = std::string(dyncal::test::dyncal_binary()) + " " + args + " >" + (dir / "out.txt").string() +
                          " 2>" + (dir / "err.txt").string();
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(dir / "out.txt"), slurp(dir / "err.txt")};
}

void write_bag(const fs::path& csv, const fs::path& out, const std::string& options) {
  const std::string cmd = "/usr/bin/python3 " + kWriter + " " + csv.string() + " " + out.string() + " " + options;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

/// The report's lines but the fit's wall time and the bag's own notes, with the log's path `data` as LOG.
std::string without_path(const std::string& report, const std::string& data) {
  std::istringstream in(report);
  std::string line, out;
  while (std::getline(in, line)) {
    if (line.find("fit in") != std::string::npos) continue;
    for (auto at = line.find(data); at != std::string::npos; at = line.find(data)) line.replace(at, data.size(), "LOG");
    if (line.rfind("note: LOG: ", 0) == 0) continue;  // a bag's reading (checked below); a CSV has none
    out += line + "\n";
  }
  return out;
}

class Ros2Bags : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("dyncal_bags_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// The TX40 log on the joint side as dyncal's CSV, its first `rows` samples (0: all).
  fs::path tx40_csv(Eigen::Index rows = 0) {
    const auto robot = dyncal::host::load_robot(dyncal::host::default_robots_dir(), "tx40");
    dyncal::host::JointLog log =
        dyncal::host::read_tx40_log(dyncal::test::tx40_data(), robot.transmission, robot.joint_offsets);
    if (rows > 0) {
      log.t.conservativeResize(rows);
      log.q.conservativeResize(rows, Eigen::NoChange);
      log.qd.conservativeResize(rows, Eigen::NoChange);
      log.qdd.conservativeResize(rows, Eigen::NoChange);
      log.tau.conservativeResize(rows, Eigen::NoChange);
    }
    const fs::path csv = dir_ / "tx40.csv";
    dyncal::host::write_csv_log(csv.string(), log);
    return csv;
  }

  fs::path dir_;
};

TEST_F(Ros2Bags, Tx40LogIdentifiesAsItsCsvToTheLastDigit) {
  const fs::path csv = tx40_csv();
  struct Variant {
    std::string name, options, data;  // data: the bag's file, or "" for its folder
  };
  const std::vector<Variant> variants{
      {"mcap_zstd", "--storage mcap --chunk-compression zstd", "bag_0.mcap"},
      {"db3", "--storage sqlite3", ""},
  };
  std::string reference_report;
  nlohmann::json reference;
  for (const Variant& v : variants) {
    SCOPED_TRACE(v.name);
    const fs::path bag = dir_ / v.name;
    write_bag(csv, bag, v.options);
    if (reference.is_null()) {
      // The CSV of the same samples, time as the integer stamps give it.
      const std::string data = (bag / "reference.csv").string();
      const CliRun r =
          dyncal("identify" + kModel + " --data " + data + " --report " + (dir_ / "reference.json").string(), dir_);
      ASSERT_EQ(r.code, 0) << r.err;
      reference_report = without_path(r.out, data);
      reference = read_json(dir_ / "reference.json");
    }
    const std::string data = (v.data.empty() ? bag : bag / v.data).string();
    const CliRun r = dyncal(
        "identify" + kModel + " --data " + data + " --effort torque --report " + (bag / "bag.json").string(), dir_);
    ASSERT_EQ(r.code, 0) << r.err;
    EXPECT_EQ(without_path(r.out, data), reference_report);
    const nlohmann::json got = read_json(bag / "bag.json");
    // Every parameter, its standard deviation and verdict, every joint's metrics: the same doubles.
    EXPECT_EQ(got["params"], reference["params"]);
    EXPECT_EQ(got["joints"], reference["joints"]);
    // What the reading found is reported: the topic, the joints ignored, the skipped messages, both clocks.
    const std::string notes = got["notes"].dump();
    EXPECT_NE(notes.find("topic /joint_states, 45000 JointState samples"), std::string::npos) << notes;
    EXPECT_NE(notes.find("ignored: gripper_finger"), std::string::npos) << notes;
    EXPECT_NE(notes.find("900 messages without them skipped"), std::string::npos) << notes;
    EXPECT_NE(notes.find("clock header stamps"), std::string::npos) << notes;
    EXPECT_NE(notes.find("log times: period 0.2"), std::string::npos) << notes;
  }
}

TEST_F(Ros2Bags, EveryStorageAndCompressionReadsAlike) {
  // 3 s of the log (the Done-when above runs the whole log through MCAP with zstd chunks and .db3).
  const fs::path csv = tx40_csv(15000);
  const auto identify = [&](const std::string& name, const std::string& options, const std::string& file) {
    write_bag(csv, dir_ / name, options);
    const fs::path data = file.empty() ? dir_ / name : dir_ / name / file;
    const CliRun r = dyncal("identify" + kModel + " --data " + data.string() + " --effort torque --report " +
                                (dir_ / (name + ".json")).string(),
                            dir_);
    EXPECT_EQ(r.code, 0) << name << ": " << r.err;
    return read_json(dir_ / (name + ".json"));
  };
  const nlohmann::json reference = identify("mcap_zstd", "--storage mcap --chunk-compression zstd", "");
  for (const auto& [name, options, file] : std::vector<std::array<std::string, 3>>{
           {"mcap_lz4", "--storage mcap --chunk-compression lz4", "bag_0.mcap"},
           {"mcap_plain_in_zstd_file", "--storage mcap --chunk-compression none --file-compression file", ""},
           {"db3_zstd_messages", "--storage sqlite3 --file-compression message", ""},
           {"db3_file", "--storage sqlite3", "bag_0.db3"}}) {
    SCOPED_TRACE(name);
    const nlohmann::json got = identify(name, options, file);
    EXPECT_EQ(got["params"], reference["params"]);
    EXPECT_EQ(got["joints"], reference["joints"]);
  }
}

TEST_F(Ros2Bags, CorruptTruncatedAndAmbiguousBagsAreRefusedOnOneLine) {
  const fs::path csv = tx40_csv(15000);
  write_bag(csv, dir_ / "good", "--storage mcap --chunk-compression zstd");
  write_bag(csv, dir_ / "db", "--storage sqlite3");
  const fs::path mcap = dir_ / "good" / "bag_0.mcap";
  const std::string bytes = slurp(mcap);
  const auto refused = [&](const std::string& args, const std::string& says) {
    SCOPED_TRACE(args);
    const CliRun r = dyncal("identify" + kModel + " " + args + " --report " + (dir_ / "no.json").string(), dir_);
    EXPECT_EQ(r.code, 2) << r.err;
    EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << r.err;
    EXPECT_NE(r.err.find(says), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir_ / "no.json"));
  };
  // The good bag reads, with the clock of the recorder too.
  const CliRun good = dyncal("identify" + kModel + " --data " + mcap.string() + " --effort torque --clock log", dir_);
  EXPECT_EQ(good.code, 0) << good.err;
  // Cut off mid-file (a recorder killed): the record and offset are named.
  const fs::path cut = dir_ / "cut.mcap";
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  refused("--data " + cut.string() + " --effort torque", "left in the file (truncated)");
  // Cut after the data section, before the footer.
  std::ofstream(dir_ / "nofooter.mcap", std::ios::binary) << bytes.substr(0, bytes.size() - 28);
  refused("--data " + (dir_ / "nofooter.mcap").string() + " --effort torque", "byte ");
  // A flipped byte inside a chunk's compressed records.
  std::string flipped = bytes;
  flipped[bytes.size() / 3] = static_cast<char>(flipped[bytes.size() / 3] ^ 0x5A);
  std::ofstream(dir_ / "flipped.mcap", std::ios::binary) << flipped;
  refused("--data " + (dir_ / "flipped.mcap").string() + " --effort torque", "Chunk (0x06)");
  // A file that is not a bag's storage, in a bag folder.
  std::ofstream(dir_ / "db" / "bag_0.db3") << "not a database\n";
  refused("--format ros2-bag --data " + (dir_ / "db").string() + " --effort torque", "neither an MCAP nor a SQLite3");
  // What effort holds is declared, never guessed.
  refused("--data " + mcap.string(), "--effort torque|current");
  // A topic that is not there, or not a JointState.
  refused("--data " + mcap.string() + " --effort torque --topic /nope", "no topic /nope; the bag has /joint_states");
  refused("--data " + mcap.string() + " --effort torque --topic /diagnostics", "not a sensor_msgs/msg/JointState");
  // The robot's joints are not in the bag (another naming).
  write_bag(csv, dir_ / "renamed", "--storage mcap --joint-prefix axis");
  refused("--data " + (dir_ / "renamed").string() + " --effort torque", "with the robot's joints (joint_1");
  // Motor currents without torque constants.
  refused("--data " + mcap.string() + " --effort current", "no transmission.torque_constants");
  // Issue 67: the real cause, named. A text file named .mcap (it was read as a CSV, and refused for
  // its columns, even without --effort).
  std::ofstream(dir_ / "text.mcap") << "t,q1\n0,1\n";
  refused("--data " + (dir_ / "text.mcap").string(), "named .mcap but not an MCAP file");
  // A metadata.yaml entry that is a FIFO (it "was missing").
  fs::copy(dir_ / "good", dir_ / "fifo_bag");
  fs::remove(dir_ / "fifo_bag" / "bag_0.mcap");
  ASSERT_EQ(::mkfifo((dir_ / "fifo_bag" / "bag_0.mcap").c_str(), 0644), 0);
  refused("--data " + (dir_ / "fifo_bag").string() + " --effort torque", "is not a regular file (a folder, FIFO");
  // A .db3 message whose timestamp is text (it was read as 0).
  write_bag(csv, dir_ / "db_text", "--storage sqlite3");
  const std::string db3 = (dir_ / "db_text" / "bag_0.db3").string();
  ASSERT_EQ(std::system(("/usr/bin/python3 -c \"import sqlite3; c = sqlite3.connect('" + db3 +
                         "'); c.execute(\\\"UPDATE messages SET timestamp = 'abc'\\\"); c.commit()\"")
                            .c_str()),
            0);
  refused("--data " + db3 + " --effort torque", "its timestamp is not an integer number of nanoseconds ('abc')");
}

}  // namespace
