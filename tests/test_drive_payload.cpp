// The payload identified on the drive (issue 44): the simulated cobot7 drive of a CTest fixture (a
// real libmodbus server on loopback, tests/data/scenarios/cobot7_payload.json: a 1.5 kg load on
// the last link of its plant) runs the identify_payload command with the arm's true model in its
// table. Its estimate must give the load (the scenario's, the ground truth), agree with the host's
// payload identification (payload.hpp) on the samples the same run streamed, within the drive's
// std, and its active table must then hold the loaded model: a fresh run with it needs the PD loop's
// effort of the true loaded model (within 10 %, or the load's torque explained to 1 % of its power),
// not the load's.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <random>

#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/payload/payload.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "support/drive_uri.hpp"
#include "support/dyncal_cli.hpp"
#include "support/payload_load.hpp"
#include "support/simulated_log.hpp"
#include "support/test_paths.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using namespace dyncal::host;
using dyncal::linux_port::ModbusDrive;

/// The arm's model as a parameter set (the table's values; Eq. 7 friction).
ParameterSet parameter_set_of(const RobotDescription& robot, const dyncal::ParameterTable& t) {
  ParameterSet p;
  p.robot = robot.name;
  p.model = "eq7";
  p.source = "the drive's table";
  const ModelSpec spec = parse_model_spec(p.model, robot.num_joints);
  p.terms = spec.terms;
  p.names = term_set_model(compiled_robot_for(robot), p.terms).names;
  p.values.resize(t.count);
  for (int i = 0; i < t.count; ++i) p.values[i] = t.values[i];
  return p;
}

/// The arm's calibrated model: the robot file's rigid body and the scenario's Eq. 7 friction.
dyncal::ParameterTable arm_table(const RobotDescription& robot, const Scenario& sc) {
  JointArray Fc{}, beta{};
  for (int j = 0; j < robot.num_joints; ++j) {
    Fc[j] = sc.friction[j].Fc;
    beta[j] = sc.friction[j].beta;
  }
  return nominal_table(robot.name, Fc, beta);
}

/// The scenario's payload as a body (mass, centre of mass, inertia about it).
dyncal::test::Body scenario_load(const Scenario& sc) {
  const auto& pl = sc.payload;
  dyncal::test::Body b;
  b.m = pl.mass;
  b.c = Eigen::Vector3d(pl.com[0], pl.com[1], pl.com[2]);
  const auto& I = pl.inertia;
  b.Ic << I[0], I[1], I[2], I[1], I[3], I[4], I[2], I[4], I[5];
  return b;
}

/// `load` in the scenario (the plant's payload).
void set_scenario_load(Scenario& sc, const dyncal::test::Body& load) {
  sc.payload.mass = load.m;
  for (int k = 0; k < 3; ++k) sc.payload.com[static_cast<size_t>(k)] = load.c[k];
  const double I[6] = {load.Ic(0, 0), load.Ic(0, 1), load.Ic(0, 2), load.Ic(1, 1), load.Ic(1, 2), load.Ic(2, 2)};
  for (int k = 0; k < 6; ++k) sc.payload.inertia[static_cast<size_t>(k)] = I[k];
}

/// The true loaded model: `arm` with `load`'s standard parameters on the last link (K_N dphi).
dyncal::ParameterTable loaded_table(const CompiledRobot& c, dyncal::ParameterTable arm,
                                    const dyncal::test::Body& load) {
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(c.num_standard);
  phi.tail(10) = dyncal::test::standard_parameters(load);
  const Eigen::VectorXd delta = c.standard_to_base(phi);
  for (int i = 0; i < c.num_base; ++i) arm.values[i] = static_cast<float>(arm.values[i] + delta[i]);
  return arm;
}

/// An in-process drive of `sc` (the SimulatedDrive the Modbus server runs) holding `table`, set to
/// play `trajectory` twice, recorded at 500 Hz; its flash at `flash`.
std::unique_ptr<SimulatedDrive> drive_with_table(const RobotDescription& robot, const Scenario& sc,
                                                 const std::string& flash, const dyncal::ParameterTable& table,
                                                 const DriveTrajectory& trajectory) {
  std::filesystem::remove(flash);
  auto drive = std::make_unique<SimulatedDrive>(robot, sc, flash);
  const auto bytes = encoded_table(table);
  EXPECT_EQ(drive->commit(bytes.data(), static_cast<int>(bytes.size())), dyncal::TableStatus::ok);
  drive->trajectory = trajectory;
  drive->periods = 2;
  drive->sample_rate_hz = 500.0;
  return drive;
}

/// PD effort (model_error_rms) of a plain run of `drive` with the table it holds.
JointArray plain_run_effort(SimulatedDrive& drive) {
  drive.start();
  while (drive.state() == mm::DriveState::playing) {
    drive.step();
    if (!drive.ring().empty()) drive.ack(drive.ring().back().seq + 1);
  }
  return drive.model_error_rms();
}

/// The PD effort of an in-process run of `sc` with `table` (its flash removed after).
JointArray effort_with_table(const RobotDescription& robot, const Scenario& sc, const std::string& flash,
                             const dyncal::ParameterTable& table, const DriveTrajectory& trajectory) {
  const JointArray e = plain_run_effort(*drive_with_table(robot, sc, flash, table, trajectory));
  std::filesystem::remove(flash);
  return e;
}

/// Every parameter both determine: the drive's estimate within 2.58 of its std of the host's on the
/// same samples. Returns how many were compared.
/// (Values: the registers' std::array as port/linux reads them, or the in-process drive's arrays.)
template <class Values>
int expect_drive_agrees_with_host(const Values& value, const Values& std_, const PayloadResult& host) {
  int compared = 0;
  for (int i = 0; i < 10; ++i) {
    if (!std::isfinite(value[i]) || !std::isfinite(host.standard_std[i])) continue;
    ++compared;
    std::printf("parameter %d: drive %.5g (std %.2g), host %.5g (std %.2g)\n", i + 1, value[i], std_[i],
                host.standard[i], host.standard_std[i]);
    EXPECT_LE(std::abs(value[i] - host.standard[i]), 2.58 * std_[i]) << "parameter " << i + 1;
  }
  return compared;
}

/// Per joint, the PD effort with the drive's loaded table (`after`) within 10 % of the true loaded
/// model's; or, where the effort left is that small that the payload's least-determined parameters
/// (its inertia, on a wrist joint) dominate it, the load's torque explained but for at most 1 % of
/// its power: (after^2 - true^2) / (before^2 - true^2), `before` the arm's table's.
void expect_effort_of_the_true_model(const JointArray& after, const JointArray& truth, const JointArray& before,
                                     int joints) {
  for (int j = 0; j < joints; ++j) {
    std::printf("  joint %d: PD effort %.4g Nm (arm's table %.4g, true loaded model %.4g)\n", j + 1, after[j],
                before[j], truth[j]);
    const double a2 = after[j] * after[j], t2 = truth[j] * truth[j], b2 = before[j] * before[j];
    EXPECT_TRUE(after[j] <= 1.10 * truth[j] || a2 - t2 <= 0.01 * (b2 - t2)) << "joint " << j + 1;
  }
}

/// cobot7's payload drive of the CTest fixture, connected, and its scenario.
class DrivePayloadFixture : public ::testing::Test {
 protected:
  void SetUp() override {
    uri_ = fixture_drive_uri("DYNCAL_DRIVE_PAYLOAD_READY");
    ASSERT_FALSE(uri_.empty()) << "DYNCAL_DRIVE_PAYLOAD_READY not set or empty: run through ctest";
    std::string error;
    drive_ = ModbusDrive::connect(uri_, &error);
    ASSERT_TRUE(drive_) << error;
    sc_ = load_scenario(std::string(dyncal::test::source_dir()) + "/tests/data/scenarios/cobot7_payload.json", robot_);
  }
  const RobotDescription robot_ = dyncal::test::test_robot("cobot7");
  std::string uri_;
  std::unique_ptr<ModbusDrive> drive_;
  Scenario sc_;
};

using DrivePayload = DrivePayloadFixture;

TEST_F(DrivePayload, TheDriveIdentifiesTheLoadAndWritesItIntoItsTable) {
  const dyncal::ParameterTable arm = arm_table(robot_, sc_);
  dyncal::TableStatus reason = dyncal::TableStatus::ok;
  ASSERT_EQ(drive_->write(arm, &reason), dyncal::port::PortStatus::ok) << drive_->error();

  const auto trajectory = default_excitation(robot_, 0.1, 5, 20, 1, nullptr);
  const std::string dir = std::filesystem::temp_directory_path().string();
  StreamRun run{"payload", 2, 500.0, dir, true};
  const JointLog log = stream_run(*drive_, trajectory, run, nullptr, nullptr, nullptr, {});
  dyncal::linux_port::DriveInfo before;
  ASSERT_EQ(drive_->read_info(before), dyncal::port::PortStatus::ok);
  dyncal::linux_port::DrivePayload p;
  ASSERT_EQ(drive_->read_payload(p), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(p.state, mm::PayloadState::written);

  // The load against the scenario's.
  const double m = sc_.payload.mass;
  std::printf("drive: mass %.5g kg (true %.5g, %+.2f %%), std %.2g\n", p.value[9], m, 100 * (p.value[9] / m - 1),
              p.std[9]);
  EXPECT_LE(std::abs(p.value[9] / m - 1), 0.03);
  for (int k = 0; k < 3; ++k) {
    const double c = p.value[6 + k] / p.value[9];
    std::printf("drive: com %d %.4g m (true %.4g, %+.2f mm)\n", k + 1, c, sc_.payload.com[k],
                1000 * (c - sc_.payload.com[k]));
    EXPECT_LE(std::abs(c - sc_.payload.com[k]), 0.005);
  }

  // The host's payload identification on the streamed samples, with the same arm model.
  IdentifyOptions o;
  o.terms = dyncal::kFrictionEq7;
  const PayloadResult host = identify_payload(robot_, log, parameter_set_of(robot_, arm), o);
  EXPECT_GE(expect_drive_agrees_with_host(p.value, p.std, host), 4);  // at least the mass and the first moments

  // The reference: the same loaded arm run with the true loaded model in its table (in process;
  // the loaded plant's PD gains, from its own mass matrix, are the same in both runs).
  const JointArray true_effort =
      effort_with_table(robot_, sc_, dir + "/dyncal_payload_ref_" + std::to_string(::getpid()) + ".table",
                        loaded_table(compiled_robot_for(robot_), arm, scenario_load(sc_)), trajectory);

  // The active table holds the loaded model: a fresh run needs the PD effort of the true loaded
  // model, not the load's.
  dyncal::ParameterTable now;
  ASSERT_EQ(drive_->read(now, &reason), dyncal::port::PortStatus::ok);
  bool changed = false;
  for (int i = 0; i < now.count; ++i) changed = changed || now.values[i] != arm.values[i];
  EXPECT_TRUE(changed);
  stream_run(*drive_, trajectory, {"after", 2, 500.0, dir, false}, nullptr, nullptr, nullptr, {});
  dyncal::linux_port::DriveInfo after;
  ASSERT_EQ(drive_->read_info(after), dyncal::port::PortStatus::ok);
  JointArray before_effort{}, after_effort{};
  for (int j = 0; j < robot_.num_joints; ++j) {
    before_effort[j] = before.model_error_rms[j];
    after_effort[j] = after.model_error_rms[j];
  }
  expect_effort_of_the_true_model(after_effort, true_effort, before_effort, robot_.num_joints);
}

using DrivePayloadCli = DrivePayloadFixture;

// dyncal payload --drive on the same fixture: with the arm's table the drive writes the load (exit
// 0, mass within 3 %); run again, its table now explains the load, the run shows none: exit 2 and
// "not written" (the table left as it is).
TEST_F(DrivePayloadCli, PayloadOnTheDriveFromTheCommandLine) {
  dyncal::TableStatus reason = dyncal::TableStatus::ok;
  ASSERT_EQ(drive_->write(arm_table(robot_, sc_), &reason), dyncal::port::PortStatus::ok) << drive_->error();
  drive_.reset();  // this connection closed before the command line's
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_payload_cli_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string base = "payload --robot cobot7 --robots-dir " + std::string(dyncal::test::source_dir()) +
                           "/tests/robots --drive " + uri_ + " --report ";
  ASSERT_EQ(dyncal::test::run_dyncal(base + (dir / "first.json").string()), 0);
  const nlohmann::json first = dyncal::test::read_json(dir / "first.json");
  EXPECT_EQ(first["state"], "written");
  EXPECT_LE(std::abs(first["standard"][9]["value"].get<double>() / sc_.payload.mass - 1), 0.03);
  EXPECT_EQ(dyncal::test::run_dyncal(base + (dir / "second.json").string()), 2);
  EXPECT_EQ(dyncal::test::read_json(dir / "second.json")["state"], "not written");
  std::filesystem::remove_all(dir);
}

/// One identify_payload run of `drive` (in process), its recorded samples as a log (t from seq).
JointLog play_payload_run(SimulatedDrive& drive, int joints) {
  drive.start_payload();
  std::vector<dyncal::port::DriveSample> samples;
  while (drive.state() == mm::DriveState::playing) {
    drive.step();
    for (const auto& s : drive.ring()) samples.push_back(s);
    if (!drive.ring().empty()) drive.ack(drive.ring().back().seq + 1);
  }
  JointLog log;
  const Eigen::Index S = static_cast<Eigen::Index>(samples.size());
  log.t.resize(S);
  log.q.resize(S, joints);
  log.tau.resize(S, joints);
  for (Eigen::Index k = 0; k < S; ++k) {
    const auto& d = samples[static_cast<size_t>(k)];
    log.t[k] = static_cast<double>(d.seq) / drive.sample_rate_hz;
    for (int j = 0; j < joints; ++j) {
      log.q(k, j) = d.q[j];
      log.tau(k, j) = d.tau[j];
    }
  }
  log.source = "simulated drive";
  return log;
}

class DrivePayloadLoads : public ::testing::TestWithParam<const char*> {};

// Every test robot's simulated drive (in process: the same SimulatedDrive the Modbus server runs)
// with four loads of 0.5-10 % of the arm's mass at random centres of mass and with random inertia:
// 20-bit encoders. From 2 % on the drive writes the load (mass within 3 %), from 5 % on each
// centre-of-mass coordinate its std fixes to 5 mm within 5 mm, every kept first moment within its
// 99 % interval; at 0.5 % it may find the mass undetermined and leave the table (then
// nothing is checked but that); the drive's estimate within 2.58 of its std of the host's on the
// same samples; the loaded table's PD effort that of the true loaded model (within 10 %, or the
// load's torque explained to 1 % of its power).
TEST_P(DrivePayloadLoads, EveryArmAndLoad) {
  const RobotDescription robot = dyncal::test::test_robot(GetParam());
  const CompiledRobot& c = compiled_robot_for(robot);
  const int n = robot.num_joints;
  std::mt19937 rng(51);
  const double fractions[4] = {0.005, 0.02, 0.05, 0.10};
  const auto trajectory = default_excitation(robot, 0.1, 5, 20, 1, nullptr);
  const std::string flash = std::filesystem::temp_directory_path().string() + "/dyncal_payload_" + robot.name +
                            std::to_string(::getpid()) + ".table";
  for (double fraction : fractions) {
    const dyncal::test::Body load = dyncal::test::random_load(rng, fraction * dyncal::test::arm_mass(c));
    SCOPED_TRACE(robot.name + ": load " + std::to_string(load.m) + " kg");
    Scenario sc = default_scenario(robot);
    sc.encoder_counts = 1048576;  // 20-bit encoders, as the host payload tests' logs and the scenarios
    set_scenario_load(sc, load);
    for (int j = 0; j < n; ++j) sc.friction[j].model = dyncal::host::FrictionModel::eq7;
    const dyncal::ParameterTable arm = arm_table(robot, sc);
    const auto drive = drive_with_table(robot, sc, flash, arm, trajectory);
    const std::uint32_t generation = drive->table_generation();  // with the test's own commit
    const JointLog log = play_payload_run(*drive, n);
    const auto& v = drive->payload().value;
    const auto& sd = drive->payload().std;
    std::printf("%s, %.1f %% load: payload_state %d, mass %.5g kg (true %.5g), std %.2g\n", robot.name.c_str(),
                100 * fraction, static_cast<int>(drive->payload_state()), v[9], load.m, sd[9]);
    if (drive->payload_state() != mm::PayloadState::written) {
      EXPECT_LT(fraction, 0.02) << "the drive left a load of 2 % or more undetermined";
      EXPECT_EQ(drive->table_generation(), generation);  // the run wrote nothing
      continue;
    }
    EXPECT_LE(std::abs(v[9] - load.m), 2.58 * sd[9]);
    if (fraction >= 0.02) {
      EXPECT_LE(std::abs(v[9] / load.m - 1), 0.03);
    }
    // A centre-of-mass coordinate the run determines (its first moment's 99 % interval, over the
    // mass, within 5 mm) within 5 mm from 5 % on; every kept one within its 99 % interval.
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(v[6 + k])) continue;
      const double com = v[6 + k] / v[9], com_std = sd[6 + k] / v[9];
      std::printf("  com %d: %.4g m (true %.4g), std %.2g\n", k + 1, com, load.c[k], com_std);
      EXPECT_LE(std::abs(v[6 + k] - load.m * load.c[k]), 2.58 * sd[6 + k]) << "first moment " << k + 1;
      if (fraction >= 0.05 && 2.58 * com_std <= 0.005) {
        EXPECT_LE(std::abs(com - load.c[k]), 0.005) << "centre of mass " << k + 1;
      }
    }
    IdentifyOptions o;
    o.terms = dyncal::kFrictionEq7;
    expect_drive_agrees_with_host(v, sd, identify_payload(robot, log, parameter_set_of(robot, arm), o));
    // The loaded table against the true loaded model, both on the loaded plant.
    const JointArray with_estimate = plain_run_effort(*drive);
    const JointArray without = effort_with_table(robot, sc, flash + ".arm", arm, trajectory);
    const JointArray true_effort = effort_with_table(robot, sc, flash + ".ref", loaded_table(c, arm, load), trajectory);
    expect_effort_of_the_true_model(with_estimate, true_effort, without, n);
  }
  std::filesystem::remove(flash);
}

INSTANTIATE_TEST_SUITE_P(TestRobots, DrivePayloadLoads, ::testing::Values("arm3", "arm6", "cobot7"));

}  // namespace
