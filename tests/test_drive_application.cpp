// lib/'s drive application (dyncal/drive/drive_application.hpp) over the drive image's simulated er20
// (port/cortex_m/app/simulated_arm.hpp), against independent references: the generated inverse
// dynamics for the table dispatch (term_sets.hpp), the arm's own physics for the control law (with
// the arm's true table the drive's model error is the loop's noise, with the factory table the
// friction and rotor inertia it lacks), the run's arithmetic for lockstep recording, the robot's
// ratings for the trips, the store for commits. The same application runs in the Cortex-M drive
// images (tests/firmware_drive.sh calibrates it over Modbus RTU).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "support/er20_drive_in_memory.hpp"

namespace {
namespace drive_application_suite {

using namespace dyncal::test::er20_drive;
namespace mm = dyncal::modbus_map;
using Vec = Eigen::Matrix<double, 6, 1>;

/// Model error RMS per joint from the input registers.
template <class Drive>
Vec model_error(const Drive& d) {
  static std::uint16_t in[mm::kInputWords];
  d.publish_inputs(in);
  Vec e;
  for (int j = 0; j < 6; ++j) e[j] = mm::get_f32(in + mm::kModelErrorReg + 2 * j);
  return e;
}

TEST(TermSets, TorqueOfATableIsTheInverseDynamicsOfItsModel) {
  // The standard parameters' inverse dynamics plus Eq. 7 friction and the rotor inertias: the
  // generated Newton-Euler code, not the base regressor the table goes through.
  const dyncal::ParameterTable t = true_table();
  ASSERT_EQ(Models::check(t, dyncal::replay::ratings()), dyncal::TableStatus::ok);
  Eigen::Matrix<double, Robot::kNumStandard, 1> standard;
  for (int i = 0; i < Robot::kNumStandard; ++i) standard[i] = dyncal::generated::er20::kNominalStandard[i];
  for (int s = 0; s < 20; ++s) {
    const Vec q = Vec::Random(), qd = 2.0 * Vec::Random(), qdd = 5.0 * Vec::Random();
    Vec expected;
    Robot::inverse_dynamics(q, qd, qdd, standard, expected);
    for (int j = 0; j < 6; ++j)
      expected[j] +=
          data::kCoulomb[j] * (qd[j] > 0 ? 1 : -1) + data::kViscous[j] * qd[j] + data::kRotorInertia[j] * qdd[j];
    Vec tau;
    ASSERT_TRUE(Models::torque(t, q, qd, qdd, tau));
    for (int j = 0; j < 6; ++j)
      EXPECT_NEAR(tau[j], expected[j], 1e-4 * (1 + std::fabs(expected[j]))) << "joint " << j + 1;
  }
  dyncal::ParameterTable other = t;
  other.model_id = dyncal::kFrictionEq8;
  Vec tau = Vec::Constant(7);
  EXPECT_FALSE(Models::torque(other, Vec::Zero().eval(), Vec::Zero().eval(), Vec::Zero().eval(), tau));
  EXPECT_EQ(tau[0], 7);
  EXPECT_EQ(Models::check(other), dyncal::TableStatus::wrong_model);
  other = t;
  other.robot_id ^= 1u;
  EXPECT_EQ(Models::check(other), dyncal::TableStatus::wrong_robot);
}

template <typename Scalar>
void check_true_table_leaves_only_noise() {
  MemoryStore store;
  auto a = arm<Scalar>();
  static Application<Scalar> d(store, a, settings<Scalar>());
  const dyncal::drive::RunSettings r = run(0.5, 2, 100);
  Vec error[2];
  for (int k = 0; k < 2; ++k) {
    ASSERT_EQ(d.activate(k == 0 ? factory_table() : true_table()), dyncal::TableStatus::ok);
    ASSERT_TRUE(d.start(mm::Command::start, r, dyncal::drive::MonitorSettings{}));
    const long periods = play(d);
    EXPECT_EQ(d.state(), mm::DriveState::finished);
    // 4 s at 1 kHz, a sample every 10th period from the first: every one recorded, none dropped.
    EXPECT_EQ(periods, 4001);
    EXPECT_EQ(static_cast<long>(d.produced()), d.run_samples(2, 2.0, 100));
    EXPECT_EQ(d.produced(), 400u);
    static std::uint16_t window[mm::kRingWords];
    d.publish_window(window);
    EXPECT_EQ(dyncal::drive::decode_ring_header(window).overruns, 0u);
    error[k] = model_error(d);
  }
  for (int j = 0; j < 6; ++j) {
    // The factory table lacks friction of Fc_j at least wherever the joint moves.
    EXPECT_GT(error[0][j], 0.5 * data::kCoulomb[j]) << "joint " << j + 1;
    // The true table: what is left is the loop's answer to quantisation and the float arithmetic.
    EXPECT_LT(error[1][j], 0.02 * error[0][j]) << "joint " << j + 1;
  }
}

TEST(DriveApplication, TheArmsTrueTableLeavesOnlyTheLoopsNoiseInDouble) {
  check_true_table_leaves_only_noise<double>();
}
TEST(DriveApplication, TheArmsTrueTableLeavesOnlyTheLoopsNoiseInFloat) {
  check_true_table_leaves_only_noise<float>();
}

TEST(DriveApplication, APositionBeyondTheRatingTripsTheRun) {
  MemoryStore store;
  auto a = arm<double>();
  static Application<double> d(store, a, settings<double>());
  ASSERT_EQ(d.activate(true_table()), dyncal::TableStatus::ok);
  dyncal::drive::RunSettings r = run(0.1, 1, 100);
  r.trajectory.q0[2] = 2.7;  // joint 3 starts 0.09 rad below q_max and swings past it
  ASSERT_TRUE(d.start(mm::Command::start, r, dyncal::drive::MonitorSettings{}));
  play(d);
  EXPECT_EQ(d.state(), mm::DriveState::fault);
  EXPECT_EQ(d.fault(), mm::DriveFault::position_limit);
  EXPECT_EQ(d.fault_joint(), 3);
  EXPECT_GT(d.fault_value(), dyncal::replay::ratings().q_max[2]);
  const std::uint32_t recorded = d.produced();
  d.period();  // a tripped run records nothing more
  EXPECT_EQ(d.produced(), recorded);
  d.reset();
  EXPECT_EQ(d.state(), mm::DriveState::idle);
  EXPECT_EQ(d.fault(), mm::DriveFault::none);
}

TEST(DriveApplication, CommitChecksTheTableAndKeepsTheActiveOneOnRefusal) {
  MemoryStore store;
  auto a = arm<double>();
  static Application<double> d(store, a, settings<double>());
  EXPECT_EQ(d.load(), dyncal::TableStatus::bad_magic);  // an empty store
  ASSERT_EQ(d.activate(factory_table()), dyncal::TableStatus::ok);
  static std::uint8_t bytes[dyncal::kTableMaxBytes];
  int size = 0;
  dyncal::ParameterTable other = true_table();
  other.robot_id ^= 1u;
  ASSERT_EQ(dyncal::encode_table(other, bytes, dyncal::kTableMaxBytes, &size), dyncal::TableStatus::ok);
  EXPECT_EQ(d.commit(bytes, size), dyncal::TableStatus::wrong_robot);
  // Eq. 8 friction: a valid table of a model this drive does not run.
  using Eq8 = dyncal::IdentificationModel<Robot, dyncal::kFrictionEq8>;
  Eigen::Matrix<double, Eq8::kNumParams, 1> phi = Eigen::Matrix<double, Eq8::kNumParams, 1>::Zero();
  phi.head<Robot::kNumBase>() = nominal_base();
  dyncal::make_table<Eq8>(phi, other);
  ASSERT_EQ(dyncal::encode_table(other, bytes, dyncal::kTableMaxBytes, &size), dyncal::TableStatus::ok);
  EXPECT_EQ(d.commit(bytes, size), dyncal::TableStatus::wrong_model);
  EXPECT_EQ(store.writes, 0);
  EXPECT_EQ(d.active_table().model_id, dyncal::kFrictionEq7);
  ASSERT_EQ(dyncal::encode_table(true_table(), bytes, dyncal::kTableMaxBytes, &size), dyncal::TableStatus::ok);
  bytes[20] ^= 0x40;  // the CRC-32 no longer holds
  EXPECT_EQ(d.commit(bytes, size), dyncal::TableStatus::bad_crc);
  bytes[20] ^= 0x40;
  EXPECT_EQ(d.commit(bytes, size), dyncal::TableStatus::ok);
  EXPECT_EQ(store.writes, 1);
  EXPECT_EQ(d.active_table().model_id, kFullTerms);
  EXPECT_EQ(d.active_table().values[0], store.table.values[0]);
  // The registers show the stored table, byte for byte.
  static std::uint16_t in[mm::kInputWords];
  d.publish_inputs(in);
  EXPECT_EQ(in[mm::kActiveTableSizeReg], size);
  static std::uint8_t shown[dyncal::kTableMaxBytes];
  mm::regs_to_bytes(in + mm::kActiveTableReg, size, shown);
  for (int i = 0; i < size; ++i) ASSERT_EQ(shown[i], bytes[i]) << "byte " << i;
}

/// The arm with an external torque on one joint from a given period on (a collision the drive does
/// not measure: its torque sensor sees its own command only).
struct StruckArm final : dyncal::port::Joints<double> {
  dyncal::replay::SimulatedArm<Robot, double> arm = dyncal::test::er20_drive::arm<double>();
  int joint = 0;
  long from = -1, period = 0;
  double torque = 0;
  void place(const double* q, const double* qd) noexcept override { arm.place(q, qd); }
  void sense(double* q) noexcept override { arm.sense(q); }
  void actuate(const double* tau, double* measured) noexcept override {
    double applied[6];
    for (int j = 0; j < 6; ++j) applied[j] = tau[j] + (from >= 0 && period >= from && j == joint ? torque : 0.0);
    arm.actuate(applied, measured);
    if (from >= 0 && period >= from) measured[joint] -= torque;
    ++period;
  }
};

TEST(DriveApplication, TheCollisionMonitorTripsOnAStrikeAndNotOnFreeMotion) {
  MemoryStore store;
  static StruckArm a;
  static Application<double> d(store, a, settings<double>());
  ASSERT_EQ(d.activate(true_table()), dyncal::TableStatus::ok);
  const dyncal::drive::RunSettings r = run(0.5, 1, 100);
  // A free run with the thresholds off: the largest residual the motion itself leaves.
  dyncal::drive::MonitorSettings m;
  m.gain = 50;
  ASSERT_TRUE(d.start(mm::Command::start, r, m));
  EXPECT_EQ(d.monitor().state(), mm::MonitorState::watching);
  Vec largest = Vec::Zero();
  while (d.state() == mm::DriveState::playing) {
    if (!d.wants_period()) d.ack(d.produced());
    d.period();
    largest = largest.cwiseMax(d.monitor().residual().cwiseAbs());
  }
  ASSERT_EQ(d.state(), mm::DriveState::finished);
  ASSERT_GT(largest.minCoeff(), 0.0);
  // Thresholds at twice that: the same free run (same noise) does not trip.
  for (int j = 0; j < 6; ++j) m.threshold[static_cast<std::size_t>(j)] = 2 * largest[j];
  a.arm = dyncal::test::er20_drive::arm<double>();
  a.period = 0;
  ASSERT_TRUE(d.start(mm::Command::start, r, m));
  play(d);
  EXPECT_EQ(d.state(), mm::DriveState::finished) << "fault " << static_cast<int>(d.fault());
  // 10 thresholds' worth of torque on joint 2 from 1 s on: a collision on joint 2 soon after.
  a.arm = dyncal::test::er20_drive::arm<double>();
  a.period = 0;
  a.joint = 1;
  a.from = 1000;
  a.torque = 10 * m.threshold[1];
  ASSERT_TRUE(d.start(mm::Command::start, r, m));
  play(d);
  ASSERT_EQ(d.state(), mm::DriveState::fault);
  EXPECT_EQ(d.fault(), mm::DriveFault::collision);
  EXPECT_EQ(d.fault_joint(), 2);
  EXPECT_GT(d.time(), 1.0);
  EXPECT_LT(d.time(), 1.1);
  // Refused settings start nothing (the register server refuses them before).
  d.reset();
  m.gain = -1;
  EXPECT_FALSE(d.start(mm::Command::start, r, m));
  EXPECT_EQ(d.state(), mm::DriveState::idle);
}

TEST(DriveApplication, APayloadRunIdentifiesTheLoadAndWritesItIntoTheTable) {
  // The arm carries 5 kg 0.1 m along the last link's z axis, which the table does not know.
  static double standard[Robot::kNumStandard];
  for (int i = 0; i < Robot::kNumStandard; ++i) standard[i] = dyncal::generated::er20::kNominalStandard[i];
  const double m = 5, c = 0.1, Ic = 0.01;
  const double load[10] = {Ic + m * c * c, 0, 0, Ic + m * c * c, 0, Ic, 0, 0, m * c, m};
  for (int i = 0; i < 10; ++i) standard[Robot::kNumStandard - 10 + i] += load[i];
  dyncal::replay::SimulatedArmPhysics physics = dyncal::replay::arm_physics(7);
  physics.standard = standard;
  static dyncal::replay::SimulatedArm<Robot, double> a{physics};
  MemoryStore store;
  static Application<double> d(store, a, settings<double>());
  ASSERT_EQ(d.activate(true_table()), dyncal::TableStatus::ok);
  ASSERT_TRUE(d.start(mm::Command::identify_payload, run(0.2, 2, 100, 0.6), dyncal::drive::MonitorSettings{}));
  EXPECT_EQ(d.payload_state(), mm::PayloadState::running);
  play(d);
  ASSERT_EQ(d.state(), mm::DriveState::finished);
  const dyncal::drive::PayloadVerdict& v = d.payload();
  ASSERT_EQ(d.payload_state(), mm::PayloadState::written);
  ASSERT_TRUE(v.mass_determined);
  // The truth inside the 95 % interval the drive reports (and the interval within 5 % of the mass).
  EXPECT_LT(std::fabs(v.value[9] - m), 1.96 * v.std[9]) << v.value[9] << " +- " << v.std[9];
  EXPECT_LT(1.96 * v.std[9], 0.05 * m);
  if (std::isfinite(v.value[8])) EXPECT_LT(std::fabs(v.value[8] - m * c), 1.96 * v.std[8] + 1e-9);
  EXPECT_EQ(store.writes, 1);
  // The table holds the load: its torque at rest grows by the load's gravity.
  const dyncal::ParameterTable loaded = d.active_table();
  Vec q = Vec::Zero(), tau_before, tau_after, zero = Vec::Zero();
  q[1] = 0.5;
  ASSERT_TRUE(Models::torque(true_table(), q, zero, zero, tau_before));
  ASSERT_TRUE(Models::torque(loaded, q, zero, zero, tau_after));
  EXPECT_GT(std::fabs(tau_after[1] - tau_before[1]), 1.0);
  // A stopped payload run leaves the table as it is.
  ASSERT_TRUE(d.start(mm::Command::identify_payload, run(0.2, 2, 100, 0.6), dyncal::drive::MonitorSettings{}));
  for (int k = 0; k < 100; ++k) d.period();
  d.stop();
  EXPECT_EQ(d.payload_state(), mm::PayloadState::not_written);
  EXPECT_EQ(store.writes, 1);
}

}  // namespace drive_application_suite
}  // namespace
