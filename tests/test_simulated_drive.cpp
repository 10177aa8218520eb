// The simulated drive in process (no transport): deterministic for a seed, and every scenario
// effect shows up in the torque it records.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"

namespace {

using namespace dyncal::host;

std::vector<dyncal::port::DriveSample> run(const Scenario& s, const RobotDescription& robot, double seconds) {
  const std::string table = std::filesystem::temp_directory_path() / ("dyncal_sim_" + std::to_string(getpid()));
  std::filesystem::remove(table);
  SimulatedDrive d(robot, s, table);
  d.trajectory = default_excitation(robot, 0.1, 5, 1, 3, nullptr);
  d.periods = 1;
  std::vector<dyncal::port::DriveSample> out;
  d.start();
  const long steps = std::lround(seconds / d.control_period());
  for (long k = 0; k < steps; ++k) {
    d.step();
    for (const auto& x : d.ring()) out.push_back(x);
    if (!d.ring().empty()) d.ack(d.ring().back().seq + 1);
  }
  return out;
}

double rms_tau_difference(const std::vector<dyncal::port::DriveSample>& a,
                          const std::vector<dyncal::port::DriveSample>& b, int joint) {
  double ss = 0;
  const size_t n = std::min(a.size(), b.size());
  for (size_t i = 0; i < n; ++i) ss += std::pow(a[i].tau[joint] - b[i].tau[joint], 2);
  return std::sqrt(ss / static_cast<double>(n));
}

class SimulatedDriveTest : public ::testing::Test {
 protected:
  RobotDescription robot = load_robot(default_robots_dir(), "er20");
  Scenario base() const {
    Scenario s = default_scenario(robot);
    s.tau_noise_std.fill(0.0);
    return s;
  }
};

TEST_F(SimulatedDriveTest, DeterministicForASeedAndNoiseFollowsTheSeed) {
  Scenario s = default_scenario(robot);  // Table 7 noise
  const auto a = run(s, robot, 2.0), b = run(s, robot, 2.0);
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.size(), 2000u);
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].seq, i);
    for (int j = 0; j < 6; ++j) ASSERT_EQ(a[i].tau[j], b[i].tau[j]);
  }
  s.seed += 1;
  const auto c = run(s, robot, 2.0);
  // Another seed: different noise with the Table 7 standard deviation (difference of two draws: sqrt(2) sigma).
  EXPECT_NEAR(rms_tau_difference(a, c, 0), std::sqrt(2.0) * 10.0, 1.5);
  EXPECT_NEAR(rms_tau_difference(a, c, 4), std::sqrt(2.0) * 1.78, 0.3);
}

TEST_F(SimulatedDriveTest, EveryEffectChangesTheRecordedTorque) {
  const auto reference = run(base(), robot, 3.0);
  auto changed = [&](const char* what, const Scenario& s, int joint) {
    const double d = rms_tau_difference(reference, run(s, robot, 3.0), joint);
    EXPECT_GT(d, 0.1) << what << " left joint " << joint + 1 << "'s torque unchanged";
    return d;
  };
  Scenario s = base();
  s.friction[2].model = FrictionModel::eq4;  // Stribeck: Fs = 60 > Fc = 50 near zero speed
  changed("Stribeck (Eq. 4)", s, 2);
  s = base();
  s.effects[1].cogging_amplitude = 2.0;
  s.effects[1].cogging_cycles = 36;
  changed("cogging", s, 1);
  s = base();
  s.effects[1].load_friction = 0.05;
  changed("load-dependent friction", s, 1);
  s = base();
  s.effects[0].viscous_drift = 0.5;
  s.effects[0].drift_time_constant = 1.0;
  changed("viscous drift", s, 0);
  s = base();
  s.effects[3].offset = 2.0;
  changed("torque offset", s, 3);
  s = base();
  s.effects[4].rotor_inertia *= 3.0;
  changed("rotor inertia", s, 4);
  s = base();
  s.friction[5].model = FrictionModel::eq6;
  s.friction[5].f1 = 8;
  s.friction[5].f2 = 2;
  s.friction[5].f3 = 10;
  s.friction[5].f4 = 50;
  changed("Eq. 6 friction", s, 5);
}

TEST(FrictionModels, MatchTheSurveyEquations) {
  JointFriction f;
  f.Fc = 50;
  f.beta = 40;
  f.Fs = 60;
  f.qds = 0.1;
  f.model = FrictionModel::eq4;
  EXPECT_NEAR(friction_torque(f, 0.1, 0), (50 + 10 * std::exp(-1.0)) + 4.0, 1e-12);
  EXPECT_NEAR(friction_torque(f, -0.1, 0), -(50 + 10 * std::exp(-1.0)) - 4.0, 1e-12);
  f.model = FrictionModel::eq7;
  EXPECT_DOUBLE_EQ(friction_torque(f, 0.5, 0), 50 + 20);
  f.model = FrictionModel::eq8;
  f.fp = 3;
  EXPECT_NEAR(friction_torque(f, 8.0, 0), 50 + 320 + 6, 1e-12);
  f.model = FrictionModel::eq9;
  f.fl = 0.1;
  EXPECT_NEAR(friction_torque(f, -1.0, -200), -50 - 40 - 20, 1e-12);
  f.model = FrictionModel::eq5;
  f.f1 = 50, f.f2 = 5, f.f3 = 0.2, f.f4 = 3, f.f5 = 2;
  EXPECT_NEAR(friction_torque(f, 0.4, 0), 50 - 5 * std::exp(-2.0) - 3 * std::exp(-1.0 / 0.8) + 16, 1e-12);
  f.model = FrictionModel::eq6;
  f.f1 = 50, f.f2 = 10, f.f3 = 5, f.f4 = 20;
  EXPECT_NEAR(friction_torque(f, 0.1, 0), (50 + 10 / std::cosh(0.5)) * std::tanh(2.0) + 4, 1e-12);
}

/// The drive's active table with `change` applied to its decoded values, encoded.
template <class Change>
std::vector<std::uint8_t> changed_table(const SimulatedDrive& d, Change change) {
  dyncal::ParameterTable t;
  const auto& bytes = d.active_table_bytes();
  EXPECT_EQ(dyncal::decode_table(bytes.data(), static_cast<int>(bytes.size()), t), dyncal::TableStatus::ok);
  change(t);
  std::vector<std::uint8_t> out(dyncal::kTableMaxBytes);
  int size = 0;
  EXPECT_EQ(dyncal::encode_table(t, out.data(), static_cast<int>(out.size()), &size), dyncal::TableStatus::ok);
  out.resize(static_cast<size_t>(size));
  return out;
}

// The factory table (nominal base parameters, Eq. 7 friction) with every base parameter times `factor`.
std::vector<std::uint8_t> scaled_rigid_body(const SimulatedDrive& d, float factor) {
  return changed_table(d, [&](dyncal::ParameterTable& t) {
    for (int i = 0; i < dyncal::generated::er20::Robot::kNumBase; ++i) t.values[i] *= factor;
  });
}

// A table a plausibility check cannot tell from a real one (Coulomb friction 5 x each joint's tau_max,
// within the 10 x bound; a unit slip in the friction) whose feed-forward throws the arm off its path:
// the drive must stop on its own limits instead of recording a runaway.
std::vector<std::uint8_t> runaway_table(const SimulatedDrive& d, const RobotDescription& robot) {
  return changed_table(d, [&](dyncal::ParameterTable& t) {
    using Model = dyncal::IdentificationModel<dyncal::generated::er20::Robot, dyncal::kFrictionEq7>;
    for (int i = 0; i < t.count; ++i) {
      const dyncal::ParamInfo info = Model::info(i);
      if (info.kind == dyncal::ParamKind::term && info.term == dyncal::term::coulomb)
        t.values[i] = 5.0f * static_cast<float>(robot.tau_max[static_cast<Eigen::Index>(info.joint - 1)]);
    }
  });
}

// Table plausibility of the rigid body (table_check.hpp): base parameters 100 times the arm's demand
// far more than 10 x tau_max at the rated states and are refused before they play; 5 times the
// arm's stay within it and are taken (a table's values are never refused for size alone).
TEST_F(SimulatedDriveTest, RefusesATableWhoseRigidBodyDemandsTenTimesItsRatings) {
  const std::string path = std::filesystem::temp_directory_path() / ("dyncal_rb_" + std::to_string(getpid()));
  std::filesystem::remove(path);
  SimulatedDrive d(robot, base(), path);
  const std::vector<std::uint8_t> factory = d.active_table_bytes();
  const std::vector<std::uint8_t> absurd = scaled_rigid_body(d, 100.0f);
  EXPECT_EQ(d.commit(absurd.data(), static_cast<int>(absurd.size())), dyncal::TableStatus::out_of_range);
  EXPECT_EQ(d.active_table_bytes(), factory);
  const std::vector<std::uint8_t> heavy = scaled_rigid_body(d, -5.0f);
  EXPECT_EQ(d.commit(heavy.data(), static_cast<int>(heavy.size())), dyncal::TableStatus::ok);
  std::filesystem::remove(path);
}

TEST_F(SimulatedDriveTest, StopsOnTheRobotsLimitsWhenATableThrowsTheArmOffItsPathAndRestartsClean) {
  const std::string path = std::filesystem::temp_directory_path() / ("dyncal_trip_" + std::to_string(getpid()));
  std::filesystem::remove(path);
  SimulatedDrive d(robot, base(), path);
  const std::vector<std::uint8_t> factory = d.active_table_bytes();
  const std::vector<std::uint8_t> runaway = runaway_table(d, robot);
  ASSERT_EQ(d.commit(runaway.data(), static_cast<int>(runaway.size())), dyncal::TableStatus::ok);
  d.trajectory = default_excitation(robot, 0.1, 5, 1, 3, nullptr);
  d.periods = 1;
  d.sample_rate_hz = 1000;
  d.start();
  std::uint32_t last_seq = 0;
  while (d.state() == dyncal::modbus_map::DriveState::playing) {
    d.step();
    if (!d.ring().empty()) {
      last_seq = d.ring().back().seq;
      d.ack(last_seq + 1);
    }
  }
  ASSERT_EQ(d.state(), dyncal::modbus_map::DriveState::fault);
  ASSERT_NE(d.fault(), dyncal::modbus_map::DriveFault::none);
  ASSERT_NE(d.fault(), dyncal::modbus_map::DriveFault::non_finite_state);
  const int j = d.fault_joint() - 1;
  ASSERT_GE(j, 0);
  ASSERT_LT(j, 6);
  if (d.fault() == dyncal::modbus_map::DriveFault::velocity_limit) {
    EXPECT_GT(std::fabs(d.fault_value()), robot.qd_max[j]);
  } else {
    EXPECT_TRUE(d.fault_value() < robot.q_min[j] || d.fault_value() > robot.q_max[j]) << d.fault_value();
  }
  // Stopped early (the trajectory is 10 s) and recorded nothing after the trip.
  EXPECT_LT(d.time(), 5.0);
  EXPECT_EQ(d.produced(), last_seq + 1);
  d.step();
  EXPECT_EQ(d.produced(), last_seq + 1);
  // The factory table back, a start clears the fault and the trajectory plays to its end.
  ASSERT_EQ(d.commit(factory.data(), static_cast<int>(factory.size())), dyncal::TableStatus::ok);
  d.start();
  EXPECT_EQ(d.fault(), dyncal::modbus_map::DriveFault::none);
  while (d.state() == dyncal::modbus_map::DriveState::playing) {
    d.step();
    if (!d.ring().empty()) d.ack(d.ring().back().seq + 1);
  }
  EXPECT_EQ(d.state(), dyncal::modbus_map::DriveState::finished);
  EXPECT_EQ(d.produced(), 10000u);
  std::filesystem::remove(path);
}

TEST_F(SimulatedDriveTest, StopsOnANonFiniteState) {
  const std::string path = std::filesystem::temp_directory_path() / ("dyncal_nan_" + std::to_string(getpid()));
  std::filesystem::remove(path);
  Scenario s = base();
  s.friction[2].beta = std::numeric_limits<double>::quiet_NaN();  // the plant's integration fails
  SimulatedDrive d(robot, s, path);
  d.trajectory = default_excitation(robot, 0.1, 5, 1, 3, nullptr);
  d.periods = 1;
  d.start();
  for (int k = 0; k < 10 && d.state() == dyncal::modbus_map::DriveState::playing; ++k) d.step();
  ASSERT_EQ(d.state(), dyncal::modbus_map::DriveState::fault);
  EXPECT_EQ(d.fault(), dyncal::modbus_map::DriveFault::non_finite_state);
  EXPECT_TRUE(std::isnan(d.fault_value()));
  EXPECT_EQ(d.produced(), 1u);  // the sample before the plant diverged
  std::filesystem::remove(path);
}

}  // namespace
