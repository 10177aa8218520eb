// Drive faults over Modbus TCP on loopback (fixture-started drive): a table that throws the arm off
// its path trips the drive on the robot's own limits; the host reports which joint and limit, keeps
// the samples recorded before the trip in a CSV that dyncal identify reads, and flashes the table
// that was active before back.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/joint_log.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "support/drive_uri.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using namespace dyncal::host;
using dyncal::linux_port::ModbusDrive;

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

TEST_F(DriveFault, RunawayTableTripsKeepsTheSamplesFlashesTheTableBeforeBackAndAStartClearsIt) {
  const std::vector<std::uint8_t> before = active_bytes();
  dyncal::ParameterTable runaway;
  dyncal::TableStatus reason;
  ASSERT_EQ(drive_->read(runaway, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  for (int i = 0; i < runaway.count; ++i) runaway.values[i] *= 100.0f;  // a table off by a unit
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
  // The drive says which joint and which limit; the host passes it on.
  dyncal::linux_port::DriveInfo info;
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
  EXPECT_EQ(info.state, mm::DriveState::fault);
  ASSERT_TRUE(info.fault == mm::DriveFault::position_limit || info.fault == mm::DriveFault::velocity_limit);
  ASSERT_GE(info.fault_joint, 1);
  ASSERT_LE(info.fault_joint, 6);
  const int j = info.fault_joint - 1;
  if (info.fault == mm::DriveFault::velocity_limit) {
    EXPECT_GT(std::fabs(info.fault_value), robot_.qd_max[j] * (1 - 1e-6));
  } else {
    EXPECT_TRUE(info.fault_value < robot_.q_min[j] || info.fault_value > robot_.q_max[j]);
  }
  EXPECT_NE(message.find("drive fault: joint " + std::to_string(info.fault_joint) + " " + mm::to_string(info.fault)),
            std::string::npos)
      << message;
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
  // A start clears the fault: with that table the same trajectory plays to its end, no fault log.
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
  for (int i = 0; i < runaway.count; ++i) runaway.values[i] *= 100.0f;
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
  ASSERT_EQ(drive_->write(previous, &reason), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_FALSE(message.empty()) << "calibrate did not stop on the trip";
  EXPECT_EQ(message.find("with the new table"), std::string::npos) << message;  // nothing was flashed
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex("\\(excitation run\\) are in (\\S+\\.csv)"))) << message;
  EXPECT_GT(read_csv_log(m[1].str(), 6).samples(), 2);
}

}  // namespace
