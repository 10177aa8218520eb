// dyncal diagnose: on the real TX40 logs it finds the wrist coupling without being told; on
// simulated-drive data it names an undeclared effect on the right joint, and adds nothing when
// there is none.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "dyncal_host/calibrate.hpp"
#include "dyncal_host/diagnose.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/input_error.hpp"

namespace {

using namespace dyncal::host;

TEST(Diagnose, Tx40FindsTheWristCouplingAndLiftsJoint5) {
  const auto robot = load_robot(default_robots_dir(), "tx40");
  const auto log = read_tx40_log(DYNCAL_TX40_DATA, robot.transmission, robot.joint_offsets);
  DiagnoseOptions o;
  o.identify.terms = parse_model("eq7");
  o.max_effects = 3;
  const auto r = diagnose(robot, log, o);
  print_diagnose_report(std::cout, r);
  ASSERT_FALSE(r.effects.empty());
  // The first effect: a motor turning with q5 + q6 (motor 6 drives both), shared by joints 5 and 6.
  EXPECT_EQ(r.effects[0].kind, "coupling");
  EXPECT_EQ(r.effects[0].joints, (std::vector<int>{5, 6}));
  EXPECT_LT(r.joints[4].r2_validation_before, 0.7);
  EXPECT_GE(r.joints[4].r2_validation_after, 0.9);
  EXPECT_GE(r.joints[5].r2_validation_after, 0.9);
}

/// A log recorded from the simulated drive in process: `seconds` of the default excitation.
JointLog simulated_log(const Scenario& s, const RobotDescription& robot, double seconds) {
  const std::string table = std::filesystem::temp_directory_path() / ("dyncal_diag_" + std::to_string(getpid()));
  std::filesystem::remove(table);
  SimulatedDrive d(robot, s, table);
  d.trajectory = default_excitation(robot, 0.1, 5, 4, 11, nullptr);
  d.periods = static_cast<int>(std::ceil(seconds * 0.1));
  d.sample_rate_hz = 500;
  d.start();
  std::vector<dyncal::port::DriveSample> samples;
  while (d.state() == dyncal::modbus_map::DriveState::playing) {
    d.step();
    for (const auto& x : d.ring()) samples.push_back(x);
    if (!d.ring().empty()) d.ack(d.ring().back().seq + 1);
  }
  JointLog log;
  const Eigen::Index S = static_cast<Eigen::Index>(samples.size());
  log.t.resize(S);
  log.q.resize(S, 6);
  log.tau.resize(S, 6);
  for (Eigen::Index k = 0; k < S; ++k) {
    log.t[k] = samples[static_cast<size_t>(k)].seq / 500.0;
    for (int j = 0; j < 6; ++j) {
      log.q(k, j) = samples[static_cast<size_t>(k)].q[j];
      log.tau(k, j) = samples[static_cast<size_t>(k)].tau[j];
    }
  }
  return log;
}

DiagnoseOptions sim_options() {
  DiagnoseOptions o;
  o.identify.terms = parse_model("eq7,rotor_inertia");
  o.identify.min_speed_fraction = 0.02;  // the simulated joints stick at reversals
  o.max_effects = 2;
  return o;
}

TEST(Diagnose, NamesUndeclaredCoggingOnTheRightJoint) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  Scenario s = default_scenario(robot);
  s.effects[1].cogging_amplitude = 15.0;  // Nm, against 10 Nm torque noise
  s.effects[1].cogging_cycles = 12;
  const auto r = diagnose(robot, simulated_log(s, robot, 20), sim_options());
  print_diagnose_report(std::cout, r);
  ASSERT_FALSE(r.effects.empty());
  EXPECT_EQ(r.effects[0].kind, "position_periodic");
  EXPECT_EQ(r.effects[0].joints, (std::vector<int>{2}));
  EXPECT_NE(r.effects[0].explanation.find("12 cycles per revolution"), std::string::npos) << r.effects[0].explanation;
  EXPECT_LE(r.joints[1].rms_validation_after, 0.5 * r.joints[1].rms_validation_before);
}

TEST(Diagnose, AddsNothingWithoutAnUndeclaredEffect) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  const auto r = diagnose(robot, simulated_log(default_scenario(robot), robot, 20), sim_options());
  print_diagnose_report(std::cout, r);
  EXPECT_TRUE(r.effects.empty()) << r.effects.front().explanation;
}

TEST(Diagnose, BadInputGetsAClearMessage) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  JointLog log;
  const int S = 4000;
  log.t = Eigen::VectorXd::LinSpaced(S, 0.0, (S - 1) / 500.0);
  log.q = Eigen::MatrixXd::Zero(S, 6);
  log.tau = Eigen::MatrixXd::Random(S, 6);
  for (int j = 0; j < 6; ++j) log.q.col(j) = 0.5 * (log.t.array() * (j + 1)).sin();
  log.q.col(3).setConstant(0.2);  // joint 4 never moves
  try {
    diagnose(robot, log, sim_options());
    FAIL() << "no error for a joint that does not move";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 4 does not move"), std::string::npos) << e.what();
  }
  log.q.col(3) = 0.3 * log.t;  // constant velocity
  try {
    diagnose(robot, log, sim_options());
    FAIL() << "no error for constant velocity";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("constant velocity"), std::string::npos) << e.what();
  }
}

}  // namespace
