// Drive faults over Modbus TCP on loopback (fixture-started drive): a table that throws the arm off
// its path trips the drive on the robot's own limits; the host reports which joint and limit, keeps
// the samples recorded before the trip in a CSV that dyncal identify reads, and flashes the table
// that was active before back.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/logs/joint_log.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "support/drive_uri.hpp"
#include "support/test_paths.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using namespace dyncal::host;
using dyncal::linux_port::ModbusDrive;

// A table off by a unit in its rigid-body part (base parameters x100): plausible term by term
// (friction and offsets untouched, check_table's ratings), but it throws the arm off its path.
// A table the drive's plausibility check takes (Coulomb friction 5 x each joint's tau_max, within its
// 10 x bound: a unit slip in the friction) whose feed-forward throws the arm off its path.
void make_runaway(dyncal::ParameterTable& t, const RobotDescription& robot) {
  using Model = dyncal::IdentificationModel<dyncal::generated::er20::Robot, dyncal::kFrictionEq7>;
  ASSERT_EQ(t.model_id, Model::kTerms);
  for (int i = 0; i < t.count; ++i) {
    const dyncal::ParamInfo info = Model::info(i);
    if (info.kind == dyncal::ParamKind::term && info.term == dyncal::term::coulomb)
      t.values[i] = 5.0f * static_cast<float>(robot.tau_max[static_cast<Eigen::Index>(info.joint - 1)]);
  }
}

class DriveFault : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string uri = fixture_drive_uri("DYNCAL_DRIVE_FAULT_READY");
    ASSERT_FALSE(uri.empty()) << "DYNCAL_DRIVE_FAULT_READY not set or empty: run through ctest";
    std::string error;
    drive_ = ModbusDrive::connect(uri, &error);
    ASSERT_TRUE(drive_) << error;
    dir_ = std::filesystem::temp_directory_path() / ("dyncal_fault_" + std::to_string(getpid()));
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::vector<std::uint8_t> active_bytes() {
    std::vector<std::uint8_t> b(dyncal::kTableMaxBytes);
    int size = 0;
    EXPECT_EQ(drive_->read_active_bytes(b.data(), static_cast<int>(b.size()), &size), dyncal::port::PortStatus::ok)
        << drive_->error();
    b.resize(static_cast<size_t>(size));
    return b;
  }
  RobotDescription robot_ = load_robot(default_robots_dir(), "er20");
  std::unique_ptr<ModbusDrive> drive_;
  std::filesystem::path dir_;
};

TEST_F(DriveFault, RunawayTableTripsKeepsTheSamplesAndTheTableBeforeIsFlashedBackAfterAReset) {
  const std::vector<std::uint8_t> before = active_bytes();
  dyncal::ParameterTable runaway;
  dyncal::TableStatus reason;
  ASSERT_EQ(drive_->read(runaway, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  make_runaway(runaway, robot_);
  const auto trajectory = default_excitation(robot_, 0.1, 5, 1, 3, nullptr);
  std::string message;
  try {
    flash_and_verify(*drive_, runaway, [&] {
      stream_run(*drive_, trajectory, {"verification", 1, 1000, dir_.string()}, nullptr, nullptr, nullptr, nullptr);
    });
  } catch (const DriveFaultError& e) {
    message = e.what();
  }
  ASSERT_FALSE(message.empty()) << "the runaway table did not trip the drive";
  // The drive said which joint and which limit; the host passed it on. To flash the previous table
  // back, the host reset the fault (a drive in fault takes no table): the drive is idle again.
  std::smatch trip;
  ASSERT_TRUE(std::regex_search(message, trip,
                                std::regex("drive fault: joint ([1-6]) (position limit|velocity limit): q(d?) = "
                                           "([-0-9.e+]+)")))
      << message;
  const int j = std::stoi(trip[1].str()) - 1;
  const double value = std::stod(trip[4].str());
  if (trip[2].str() == "velocity limit") {
    EXPECT_GT(std::fabs(value), robot_.qd_max[j] * (1 - 1e-3));
  } else {
    EXPECT_TRUE(value < robot_.q_min[j] * (1 - 1e-3) || value > robot_.q_max[j] * (1 - 1e-3));
  }
  dyncal::linux_port::DriveInfo info;
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
  EXPECT_EQ(info.state, mm::DriveState::idle);
  EXPECT_EQ(info.fault, mm::DriveFault::none);
  // The samples before the trip are in the file the message names, readable as a log.
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m,
                                std::regex("the ([0-9]+) samples recorded before it \\(verification run\\) "
                                           "are in (\\S+dyncal-fault-verification-[0-9T]+\\.csv)")))
      << message;
  const JointLog log = read_csv_log(m[2].str(), 6);
  EXPECT_EQ(log.samples(), std::stol(m[1].str()));
  EXPECT_EQ(log.samples(), static_cast<long>(info.produced));
  EXPECT_GT(log.samples(), 2);
  EXPECT_LT(log.samples(), 10000);  // stopped before the trajectory's end
  // The table active before the runaway one is back.
  EXPECT_NE(message.find("The previous table was flashed back."), std::string::npos) << message;
  EXPECT_EQ(active_bytes(), before);
  // With that table the same trajectory plays to its end, no fault log.
  std::filesystem::remove(m[2].str());
  const JointLog full =
      stream_run(*drive_, trajectory, {"excitation", 1, 100, dir_.string()}, nullptr, nullptr, nullptr, nullptr);
  EXPECT_EQ(full.samples(), 1000);
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
  EXPECT_EQ(info.state, mm::DriveState::finished);
  EXPECT_EQ(info.fault, mm::DriveFault::none);
  EXPECT_EQ(info.fault_joint, 0);
  EXPECT_TRUE(std::filesystem::is_empty(dir_));
}

TEST_F(DriveFault, CalibrateStopsOnATripInTheExcitationRunWithItsSamplesKept) {
  dyncal::ParameterTable previous, runaway;
  dyncal::TableStatus reason;
  ASSERT_EQ(drive_->read(previous, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  runaway = previous;
  make_runaway(runaway, robot_);
  ASSERT_EQ(drive_->write(runaway, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  CalibrateOptions o;
  o.uri = fixture_drive_uri("DYNCAL_DRIVE_FAULT_READY");
  o.terms = parse_model("eq7");
  o.progress = false;
  o.candidates = 1;
  o.fault_dir = dir_.string();
  std::ostringstream progress;
  std::string message;
  try {
    calibrate(robot_, o, progress);
  } catch (const DriveFaultError& e) {
    message = e.what();
  }
  ASSERT_EQ(drive_->reset(), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->write(previous, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_FALSE(message.empty()) << "calibrate did not stop on the trip";
  EXPECT_EQ(message.find("with the new table"), std::string::npos) << message;  // nothing was flashed
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex("\\(excitation run\\) are in (\\S+\\.csv)"))) << message;
  EXPECT_GT(read_csv_log(m[1].str(), 6).samples(), 2);
}

// The state rules (docs/modbus.md "Access and states"): a drive in fault refuses start and any
// table (device failure) until the reset command; the whole table that made it trip is refused
// only by plausibility when it is absurd term by term (every value x100: friction far above tau_max).
TEST_F(DriveFault, InFaultOnlyAResetIsTakenAndAnAbsurdTableIsRefusedBeforeItPlays) {
  dyncal::ParameterTable previous, runaway;
  dyncal::TableStatus reason;
  ASSERT_EQ(drive_->read(previous, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  dyncal::ParameterTable absurd = previous;
  for (int i = 0; i < absurd.count; ++i) absurd.values[i] = 1e5f;
  EXPECT_EQ(drive_->write(absurd, &reason), dyncal::port::PortStatus::rejected);
  EXPECT_EQ(reason, dyncal::TableStatus::out_of_range);
  runaway = previous;
  make_runaway(runaway, robot_);
  ASSERT_EQ(drive_->write(runaway, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  const auto trajectory = default_excitation(robot_, 0.1, 5, 1, 3, nullptr);
  try {
    stream_run(*drive_, trajectory, {"excitation", 1, 1000, dir_.string()}, nullptr, nullptr, nullptr, nullptr);
    ADD_FAILURE() << "the runaway table did not trip the drive";
  } catch (const DriveFaultError&) {
  }
  dyncal::linux_port::DriveInfo info;
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
  ASSERT_EQ(info.state, mm::DriveState::fault);
  EXPECT_EQ(drive_->start(), dyncal::port::PortStatus::rejected);  // only reset clears a fault
  EXPECT_NE(drive_->error().find("failure"), std::string::npos) << drive_->error();
  EXPECT_NE(drive_->write(previous, &reason), dyncal::port::PortStatus::ok);
  EXPECT_NE(drive_->error().find("in fault"), std::string::npos) << drive_->error();
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
  EXPECT_EQ(info.state, mm::DriveState::fault);  // still, and the runaway table still active
  ASSERT_EQ(drive_->reset(), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
  EXPECT_EQ(info.state, mm::DriveState::idle);
  ASSERT_EQ(drive_->write(previous, &reason), dyncal::port::PortStatus::ok) << drive_->error();
}

}  // namespace

namespace {

// Issue 67: SIGINT or SIGTERM to `dyncal calibrate` mid-run stops the drive's trajectory before the
// program exits (it used to play on until the drive's 2 s watchdog tripped fault 4); measured from
// the signal to the drive's state leaving playing, over Modbus from this test's own connection. The
// fixture's drive runs in lockstep: with no host reading, it holds "playing" until its watchdog; the
// excitation (20 periods of 10 s) lasts far longer than the 0.5 s it plays before the signal.
TEST_F(DriveFault, ASignalToCalibrateStopsTheDriveWithinHalfASecond) {
  for (const int signal : {SIGINT, SIGTERM}) {
    dyncal::linux_port::DriveInfo info;
    ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
    if (info.state == mm::DriveState::fault) ASSERT_EQ(drive_->reset(), dyncal::port::PortStatus::ok);
    const std::string err = (dir_ / "err.txt").string();
    const std::string uri = fixture_drive_uri("DYNCAL_DRIVE_FAULT_READY");
    const pid_t pid = fork();
    if (pid == 0) {
      if (!freopen("/dev/null", "w", stdout) || !freopen(err.c_str(), "w", stderr)) _exit(127);
      execl(dyncal::test::dyncal_binary(), "dyncal", "calibrate", "--drive", uri.c_str(), "--no-flash", "--periods",
            "20", "--stream", "live", "--fault-dir", dir_.c_str(), static_cast<char*>(nullptr));
      _exit(127);
    }
    ASSERT_GT(pid, 0);
    // Wait until the excitation plays, then let it play a while.
    bool playing = false;
    for (int k = 0; k < 6000 && !playing; ++k) {
      ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
      playing = info.state == mm::DriveState::playing;
      if (!playing) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    ASSERT_TRUE(playing) << "calibrate never started the excitation";
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
    ASSERT_EQ(info.state, mm::DriveState::playing) << "the excitation ended before the signal: the test tests nothing";
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(::kill(pid, signal), 0);
    double stopped_after = -1;
    for (int k = 0; k < 2000; ++k) {
      ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
      if (info.state != mm::DriveState::playing) {
        stopped_after = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    std::ifstream in(err);
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::printf("%s: the drive left playing %.3f s after the signal\n", strsignal(signal), stopped_after);
    EXPECT_GE(stopped_after, 0) << "still playing 2 s after the signal";
    EXPECT_LT(stopped_after, 0.5);
    EXPECT_EQ(info.state, mm::DriveState::finished) << "stopped by the host, not by its watchdog (fault 4)";
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 128 + signal) << text;
    EXPECT_NE(text.find("interrupted by " + std::string(signal == SIGINT ? "SIGINT" : "SIGTERM")), std::string::npos)
        << text;
    EXPECT_NE(text.find("the drive was stopped"), std::string::npos) << text;
  }
}

}  // namespace
