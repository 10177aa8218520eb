// The simulated drive's collision monitor (issue 45, docs/monitor.md "On the drive") on every arm
// of tests/robots, in process (the Modbus registers: test_drive_modbus):
// - contact torques: J_p^T F of the drive's forward kinematics against the generated inverse
//   dynamics' gravity torque of a point mass at the same point (an independent path: SymPy's);
// - each arm is calibrated on its own drive (its plant with static friction): a 20 s excitation
//   recorded from the ring, identify as calibrate does (WLS, Eq. 7, sign-constrained, rows slower
//   than 2 % of the joint's top speed left out), the observer's residual statistics of that log and
//   the thresholds for 0.01 false alarms per hour (contact_monitor.hpp); the table committed, the
//   monitor set from them;
// - contact-free runs on excitations the calibration never saw (every other one point-to-point,
//   scenario stop_and_go, the plant with static friction): no collision fault at 0.01 false
//   alarms per hour, and at a stated 100 per hour the alarms within a factor 2 of the rate
//   (20 minutes per arm, an hour over the three; DYNCAL_LONG_MONITOR=1: an hour per arm);
// - 20 contacts per arm of 5-20 % of a joint's tau_max (the joint the force loads most) on random
//   links, points, directions and times, 100 ms long: at least 95 % stop the drive within 20 ms
//   of their onset (fault collision, or a velocity trip where the contact throws a light wrist
//   over its qd_max first; at least 85 % by the monitor), none before it; reaction times printed;
// - a stiff obstacle in the path of a link: the drive stops on it.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <random>

#include "dyncal/inertial_parameters.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/drive_table.hpp"
#include "dyncal_host/monitoring/contact_monitor.hpp"
#include "support/random_physical.hpp"
#include "support/simulated_log.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using namespace dyncal::host;

constexpr double kOnsetWindow = 0.020;  // the issue's detection time [s]
constexpr double kContactSeconds = 0.1;

std::string flash_path(const std::string& robot) {
  return std::filesystem::temp_directory_path() / ("dyncal_collision_" + robot + "_" + std::to_string(getpid()));
}

/// Plays the drive's trajectory from its start until it finishes, faults or `until` [s]; the ring's
/// samples into `samples` when given; `each_period` after every control period when given.
void play(SimulatedDrive& d, double until = 1e30, std::vector<dyncal::port::DriveSample>* samples = nullptr,
          const std::function<void()>& each_period = {}) {
  d.start();
  while (d.state() == mm::DriveState::playing && d.time() < until) {
    d.step();
    if (samples) samples->insert(samples->end(), d.ring().begin(), d.ring().end());
    if (!d.ring().empty()) d.ack(d.ring().back().seq + 1);
    if (each_period) each_period();
  }
}

struct DriveCalibration {
  RobotDescription robot;
  Scenario scenario;
  std::string flash;
  ResidualStatistics stats;
  MonitorSettings monitor;
  JointArray kp{}, kd{};  ///< the PD gains of the calibration run, fixed for every later run
};

/// A drive of the calibrated arm with its table, the calibration's PD gains and the monitor set.
/// The gains stay those of the calibration, as a real drive's: the simulated drive would otherwise
/// set them from each start pose, and the residual's noise moves with kd (the PD loop's reaction
/// to the encoder's quantisation is torque the slope of q cannot follow; docs/monitor.md).
std::unique_ptr<SimulatedDrive> monitored_drive(const DriveCalibration& c, const Scenario& sc,
                                                const MonitorSettings& m) {
  auto d = std::make_unique<SimulatedDrive>(c.robot, sc, c.flash);
  d->fix_gains(c.kp, c.kd);
  EXPECT_EQ(d->set_monitor(m), "");
  return d;
}

/// Calibrates `name` on its own simulated drive (header comment) and commits the table.
DriveCalibration calibrate(const std::string& name) {
  DriveCalibration c;
  c.robot = dyncal::test::test_robot(name);
  c.scenario = default_scenario(c.robot);
  c.scenario.encoder_counts = 1 << 20;  // 20-bit joint encoders, as test_contact_monitor's logs
  c.scenario.stiction = true;           // a joint at rest sticks (at reversals, and in the point-to-point runs' stops)
  // Friction as tests/support/simulated_log.hpp's: Fc 2 % of tau_max, beta qd_max 1 % (Eq. 7).
  for (int j = 0; j < c.robot.num_joints; ++j) {
    c.scenario.friction[static_cast<size_t>(j)].Fc = 0.02 * c.robot.tau_max[j];
    c.scenario.friction[static_cast<size_t>(j)].beta = 0.01 * c.robot.tau_max[j] / c.robot.qd_max[j];
  }
  c.flash = flash_path(name);
  std::filesystem::remove(c.flash);
  SimulatedDrive d(c.robot, c.scenario, c.flash);
  d.trajectory = default_excitation(c.robot, 0.1, 5, 1, 3, nullptr);
  d.periods = 2;
  std::vector<dyncal::port::DriveSample> samples;
  play(d, 1e30, &samples);
  EXPECT_EQ(d.state(), mm::DriveState::finished);
  c.kp = d.kp();
  c.kd = d.kd();
  // No velocity in the log: the observer takes the slope of q, as the drive does.
  const JointLog log = samples_to_log(samples, d.sample_rate_hz, c.robot.num_joints);
  IdentifyOptions options;
  options.terms = dyncal::kFrictionEq7;
  options.sign_constraints = true;    // as calibrate: a drive table holds friction >= 0
  options.min_speed_fraction = 0.02;  // as calibrate: rows where a joint sticks at a reversal left out
  const ParameterSet params = parameter_set(identify(c.robot, log, options));
  const ObserverRun run = run_observer(c.robot, log, params);
  c.stats = residual_statistics(run, "drive calibration");
  const std::vector<ContactThreshold> th = contact_thresholds(c.stats, 0.01);
  const auto bytes = encoded_table(parameter_table(params, c.robot, nullptr));
  EXPECT_EQ(d.commit(bytes.data(), static_cast<int>(bytes.size())), dyncal::TableStatus::ok);
  c.monitor.gain = c.stats.gain;
  for (int j = 0; j < c.robot.num_joints; ++j) {
    const auto i = static_cast<size_t>(j);
    c.monitor.threshold[i] = th[i].value;
    c.monitor.mean[i] = c.stats.mean[i];
    c.monitor.band[i] = c.stats.band[i];
  }
  return c;
}

/// One period of `trajectory` on the calibrated drive with contact `e` in its scenario, played until
/// it ends, faults or `until` [s].
std::unique_ptr<SimulatedDrive> play_with_contact(const DriveCalibration& c, const ExcitationTrajectory& trajectory,
                                                  const ExternalContact& e, double until) {
  Scenario sc = c.scenario;
  sc.contacts.push_back(e);
  auto d = monitored_drive(c, sc, c.monitor);
  d->trajectory = trajectory;
  d->periods = 1;
  play(*d, until);
  return d;
}

class DriveCollision : public ::testing::TestWithParam<std::string> {};

TEST_P(DriveCollision, ContactTorqueIsTheGravityTorqueOfAPointMassThere) {
  const RobotDescription robot = dyncal::test::test_robot(GetParam());
  const CompiledRobot& c = compiled_robot_for(robot);
  SimulatedDrive d(robot, default_scenario(robot), flash_path(robot.name));
  const int n = robot.num_joints;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::VectorXd phi = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(n);
  const double g = 9.81, m = 1.0;
  for (int trial = 0; trial < 20; ++trial) {
    JointArray q{};
    Eigen::VectorXd qv(n);
    for (int j = 0; j < n; ++j) qv[j] = q[static_cast<size_t>(j)] = 3.0 * u(rng);
    const int link = 1 + trial % n;
    const std::array<double, 3> point{0.3 * u(rng), 0.3 * u(rng), 0.3 * u(rng)};
    // A point mass m at `point` of the link.
    Eigen::VectorXd dphi = phi;
    const double point_mass[6] = {};
    dyncal::add_rigid_load(dphi.data() + 10 * (link - 1), m, point.data(), point_mass);
    // The motors hold the mass: tau_id gains -J^T (m g_vec); the force the mass puts on the arm is m g_vec.
    const Eigen::VectorXd held = c.inverse_dynamics(qv, zero, zero, dphi) - c.inverse_dynamics(qv, zero, zero, phi);
    const JointArray tau = d.contact_torque(q, link, point, {0.0, 0.0, -m * g});
    for (int j = 0; j < n; ++j) EXPECT_NEAR(tau[static_cast<size_t>(j)], -held[j], 1e-9 * (1 + std::abs(held[j])));
  }
}

TEST_P(DriveCollision, ContactsStopTheDriveWithin20msAndUnseenMotionRaisesNoAlarm) {
  const DriveCalibration cal = calibrate(GetParam());
  const RobotDescription& robot = cal.robot;
  const int n = robot.num_joints;
  ASSERT_EQ(cal.monitor.gain, 200.0);
  std::cout << robot.name << ": thresholds [Nm]";
  for (int j = 0; j < n; ++j) std::cout << " " << cal.monitor.threshold[static_cast<size_t>(j)];
  std::cout << " (" << (100.0 * cal.monitor.threshold[0] / robot.tau_max[0]) << " % of tau_max on joint 1); std";
  for (int j = 0; j < n; ++j) std::cout << " " << cal.stats.std[static_cast<size_t>(j)];
  std::cout << "; difference std";
  for (int j = 0; j < n; ++j) std::cout << " " << cal.stats.difference_std[static_cast<size_t>(j)];
  std::cout << "\n";

  // Contact-free motion on excitations the calibration never saw: no trip at 0.01 per hour; and the
  // alarms thresholds for a stated 100 per hour would raise, counted on the same residual (an alarm:
  // a joint's |r - mean| above its threshold with the drive's widening, crossings within the
  // observer's time constant 1 / K one alarm, as dyncal monitor merges them).
  const bool long_run = std::getenv("DYNCAL_LONG_MONITOR") != nullptr;
  const double quiet_seconds = long_run ? 3600.0 : 1200.0;
  const std::vector<ContactThreshold> stated = contact_thresholds(cal.stats, 100.0);
  std::cout << "  at 100 per hour:";
  for (const auto& t : stated)
    std::cout << " " << t.value << (t.peak_bound ? " (peak)" : "") << " [gaussian " << t.gaussian << "]";
  std::cout << "\n";
  double quiet = 0, last_above = -1e30, stop_and_go_seconds = 0;
  int alarms = 0;
  long stated_alarms = 0, stop_and_go_alarms = 0;
  for (unsigned i = 0; quiet < quiet_seconds; ++i) {
    Scenario sc = cal.scenario;
    sc.seed = 100 + i;  // each run its own noise and its own excitation
    // Every other run point-to-point (moves of 3 s, stops of 1.5 s, braking and starting over 0.4 s
    // without a jerk limit), where the plant's static friction holds the resting joints.
    if (i % 2 == 1) sc.stop_and_go = drive::StopAndGo{3.0, 1.5, 0.4};
    auto dp = monitored_drive(cal, sc, cal.monitor);
    SimulatedDrive& d = *dp;
    d.trajectory = default_excitation(robot, 0.1, 5, 1, 11 + i, nullptr);
    d.periods = 6;
    play(d, 1e30, nullptr, [&] {
      const JointArray r = d.monitor_residual(), widening = d.monitor_widening();
      bool above = false;
      for (int j = 0; j < n; ++j) {
        const auto J = static_cast<size_t>(j);
        above = above || std::abs(r[J]) > stated[J].value + widening[J];
      }
      if (!above) return;
      const double t = quiet + d.time();
      if (t - last_above >= 1.0 / cal.monitor.gain) {
        ++stated_alarms;
        if (sc.stop_and_go.on()) ++stop_and_go_alarms;
      }
      last_above = t;
    });
    EXPECT_EQ(d.monitor_state(), mm::MonitorState::watching);
    if (d.state() == mm::DriveState::fault) {
      ++alarms;
      std::cout << "  false alarm: " << to_string(d.fault()) << " joint " << d.fault_joint() << " value "
                << d.fault_value() << " (widened by " << d.monitor_widening()[static_cast<size_t>(d.fault_joint() - 1)]
                << ") at " << d.time() << " s\n";
    }
    quiet += d.time();
    if (sc.stop_and_go.on()) stop_and_go_seconds += d.time();
  }
  EXPECT_EQ(alarms, 0) << "over " << quiet << " s of contact-free motion";
  const double expected = 100.0 * quiet / 3600.0;
  std::cout << "  " << alarms << " trips at 0.01 per hour over " << quiet << " s of contact-free motion ("
            << stop_and_go_seconds << " s stop-and-go); at a stated 100 per hour " << stated_alarms << " alarms ("
            << expected << " expected; " << stop_and_go_alarms << " in the stop-and-go runs)\n";
  EXPECT_GE(static_cast<double>(stated_alarms), expected / 2);
  EXPECT_LE(static_cast<double>(stated_alarms), expected * 2);

  // Contacts.
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  int detected = 0, other_trip = 0, early = 0;
  std::vector<double> reaction;
  constexpr int kContacts = 20;
  for (int i = 0; i < kContacts; ++i) {
    ExternalContact e;
    e.link = 1 + static_cast<int>(unit(rng) * n) % n;
    e.point = {0.2 * (unit(rng) - 0.5), 0.2 * (unit(rng) - 0.5), 0.2 * (unit(rng) - 0.5)};
    Eigen::Vector3d dir = dyncal::test::draws_last_first<3>(rng, normal);
    dir.normalize();
    e.start = 1.0 + 8.0 * unit(rng);
    e.duration = kContactSeconds;
    const ExcitationTrajectory traj = default_excitation(robot, 0.1, 5, 1, 11 + i % 2, nullptr);
    // The size: fraction f of tau_max on the joint the force loads most, at the planned pose.
    Eigen::Matrix<double, 7, 1> q7, qd7, qdd7;
    traj.evaluate(e.start, q7, qd7, qdd7);
    JointArray q{};
    for (int j = 0; j < n; ++j) q[static_cast<size_t>(j)] = q7[j];
    SimulatedDrive probe(robot, cal.scenario, cal.flash);
    const JointArray unit_tau = probe.contact_torque(q, e.link, e.point, {dir[0], dir[1], dir[2]});
    double load = 0;
    for (int j = 0; j < n; ++j) load = std::max(load, std::abs(unit_tau[static_cast<size_t>(j)]) / robot.tau_max[j]);
    if (load < 1e-6) {  // a point on the axes of every joint that moves it: draw again
      --i;
      continue;
    }
    const double fraction = 0.05 + 0.15 * unit(rng);
    const Eigen::Vector3d F = dir * (fraction / load);
    e.force = {F[0], F[1], F[2]};
    const auto dp = play_with_contact(cal, traj, e, e.start + e.duration + 0.05);
    const SimulatedDrive& d = *dp;
    const bool fault = d.state() == mm::DriveState::fault;
    const bool collision = fault && d.fault() == mm::DriveFault::collision;
    const double after = d.time() - e.start;
    if (fault && after < 0) {
      ++early;
    } else if (fault && after <= kOnsetWindow + 1e-9) {
      // Stopped in time: by the monitor, or first by a rating the contact threw a light joint over.
      (collision ? detected : other_trip) += 1;
      reaction.push_back(after);
      if (!collision)
        std::cout << "  link " << e.link << ", " << 100 * fraction << " % of tau_max: " << to_string(d.fault())
                  << " of joint " << d.fault_joint() << " after " << 1e3 * after << " ms, before the monitor\n";
    } else {
      std::cout << "  missed: link " << e.link << ", " << 100 * fraction << " % of tau_max, "
                << (fault ? std::string(to_string(d.fault())) + " after " + std::to_string(1e3 * after) + " ms"
                          : std::string("no fault"))
                << "\n";
    }
  }
  std::sort(reaction.begin(), reaction.end());
  std::cout << "  " << detected << " of " << kContacts << " contacts detected within 20 ms by the monitor, "
            << other_trip << " stopped first by a rating";
  if (!reaction.empty())
    std::cout << ", reaction " << 1e3 * reaction.front() << " / " << 1e3 * reaction[reaction.size() / 2] << " / "
              << 1e3 * reaction.back() << " ms (min / median / max)";
  std::cout << "\n";
  EXPECT_EQ(early, 0);
  EXPECT_GE(detected + other_trip, 19);  // 95 % stopped within 20 ms
  EXPECT_GE(detected, 17);               // and at least 85 % by the monitor itself

  // A stiff obstacle in the path of the last link's origin: it stops the drive.
  {
    const ExcitationTrajectory traj = default_excitation(robot, 0.1, 5, 1, 11, nullptr);
    ExternalContact e;
    e.link = n;
    e.start = 2.0;
    e.duration = 1.0;
    e.stiffness = 1e5;  // [N/m]
    // The point's velocity at the start, by a difference of the planned poses: the obstacle faces it.
    Eigen::Matrix<double, 7, 1> q7, qd7, qdd7, q7b;
    traj.evaluate(e.start, q7, qd7, qdd7);
    traj.evaluate(e.start + 1e-3, q7b, qd7, qdd7);
    const Eigen::VectorXd qa = q7.head(n), qb = q7b.head(n);
    JointArray q{};
    for (int j = 0; j < n; ++j) q[static_cast<size_t>(j)] = qa[j];
    // The point's Jacobian from the contact torques of three unit forces: tau = J^T F.
    SimulatedDrive probe(robot, cal.scenario, cal.flash);
    Eigen::Matrix3Xd J(3, n);
    for (int k = 0; k < 3; ++k) {
      std::array<double, 3> f{0, 0, 0};
      f[static_cast<size_t>(k)] = 1.0;
      const JointArray t = probe.contact_torque(q, e.link, e.point, f);
      for (int j = 0; j < n; ++j) J(k, j) = t[static_cast<size_t>(j)];
    }
    const Eigen::Vector3d v = J * (qb - qa) / 1e-3;
    ASSERT_GT(v.norm(), 0.01) << "the link's origin hardly moves there";
    const Eigen::Vector3d facing = -v.normalized();
    e.force = {facing[0], facing[1], facing[2]};
    const auto dp = play_with_contact(cal, traj, e, e.start + e.duration);
    const SimulatedDrive& d = *dp;
    EXPECT_EQ(d.fault(), mm::DriveFault::collision);
    std::cout << "  obstacle at " << v.norm() << " m/s: " << to_string(d.fault()) << " after "
              << 1e3 * (d.time() - e.start) << " ms, joint " << d.fault_joint() << " r - mean " << d.fault_value()
              << " Nm\n";
  }
  std::filesystem::remove(cal.flash);
}

INSTANTIATE_TEST_SUITE_P(TestRobots, DriveCollision, ::testing::Values("arm3", "arm6", "cobot7"));

// The point-to-point clock (stop_and_go.hpp): u is the integral of its speed w (Simpson on a fine
// grid), w the integral of w', u advances `move` per cycle, run_time inverts u; the scenario reads it
// and refuses a ramp longer than a phase with one line naming the field; and its stiction flag.
TEST(DriveCollisionSettings, StopAndGoClockAndTheScenarioFields) {
  const drive::StopAndGo clock{3.0, 1.5, 0.4};
  ASSERT_TRUE(clock.on() && clock.valid());
  double u_integral = 0, w_integral = 1, worst_u = 0, worst_w = 0;
  const double h = 1e-4;
  for (double t = 0; t < 20; t += h) {
    double u0, w0, wd0, um, wm, wdm, u1, w1, wd1;
    clock.at(t, u0, w0, wd0);
    clock.at(t + h / 2, um, wm, wdm);
    clock.at(t + h, u1, w1, wd1);
    u_integral += h / 6 * (w0 + 4 * wm + w1);
    w_integral += h / 6 * (wd0 + 4 * wdm + wd1);
    worst_u = std::max(worst_u, std::abs(u1 - u_integral));
    worst_w = std::max(worst_w, std::abs(w1 - w_integral));
    if (u1 > 0.1) {
      EXPECT_NEAR(clock.run_time(u1), t + h, w1 > 0.05 ? 1e-8 : 1.1 + 1e-6) << "u " << u1;
    }
  }
  EXPECT_LT(worst_u, 1e-6);
  EXPECT_LT(worst_w, 1e-2);  // w' steps inside a few grid steps
  double u, w, wd;
  clock.at(4.5 * 3, u, w, wd);
  EXPECT_NEAR(u, 3.0 * 3, 1e-12);
  const RobotDescription robot = dyncal::test::test_robot("arm3");
  const std::string path = flash_path("scenario") + ".json";
  {
    std::ofstream(path) << R"({"stop_and_go": {"move": 2, "rest": 1, "ramp": 0.5}})";
    const Scenario sc = load_scenario(path, robot);
    EXPECT_EQ(sc.stop_and_go.move, 2.0);
    EXPECT_EQ(sc.stop_and_go.rest, 1.0);
    EXPECT_EQ(sc.stop_and_go.ramp, 0.5);
  }
  std::ofstream(path) << R"({"stop_and_go": {"move": 2, "rest": 0.3, "ramp": 0.5}})";
  try {
    load_scenario(path, robot);
    ADD_FAILURE() << "a ramp longer than the rest was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stop_and_go"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
  EXPECT_FALSE(default_scenario(robot).stop_and_go.on());
  EXPECT_FALSE(default_scenario(robot).stiction);
  std::ofstream(path) << R"({"stiction": true})";
  EXPECT_TRUE(load_scenario(path, robot).stiction);
  std::ofstream(path) << R"({"stiction": 1})";
  try {
    load_scenario(path, robot);
    ADD_FAILURE() << "a stiction that is not a boolean was taken";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("stiction"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(DriveCollisionSettings, RefusedValuesLeaveTheMonitorAsItWas) {
  const RobotDescription robot = dyncal::test::test_robot("arm3");
  SimulatedDrive d(robot, default_scenario(robot), flash_path("arm3_settings"));
  MonitorSettings m;
  m.gain = 2000;  // K dt = 2 at 1 kHz
  EXPECT_NE(d.set_monitor(m), "");
  m.gain = 5;  // a window of 401 periods
  EXPECT_NE(d.set_monitor(m), "");
  m.gain = 200;
  m.threshold[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(d.set_monitor(m), "");
  m.threshold[0] = -1;
  EXPECT_NE(d.set_monitor(m), "");
  d.trajectory = default_excitation(robot, 0.1, 5, 1, 3, nullptr);
  play(d, 0.1);
  EXPECT_EQ(d.monitor_state(), mm::MonitorState::off);  // none was taken
  m.threshold[0] = 1;
  EXPECT_NE(d.set_monitor(m), "");  // while playing
  d.stop();
  EXPECT_EQ(d.set_monitor(m), "");
  play(d, 0.1);
  EXPECT_EQ(d.monitor_state(), mm::MonitorState::watching);
  d.stop();
  std::filesystem::remove(flash_path("arm3_settings"));
}

}  // namespace

// Scenario::stiction (drive_plant_of.hpp): half a second into a point-to-point run's rest every joint
// of cobot7 (its wrist light next to its friction) has stalled, its encoder reading one value;
// without static friction the same rest creeps (the Coulomb term flips sign every substep); a push
// of three times joint 1's Fc during the rest breaks it loose, and once the push ends the joints
// stall again.
TEST(DrivePlantStiction, RestingJointsStallUntilAPushExceedsTheirFriction) {
  const RobotDescription robot = dyncal::test::test_robot("cobot7");
  const int n = robot.num_joints;
  Scenario sc = default_scenario(robot);
  sc.encoder_counts = 1 << 20;
  for (int j = 0; j < n; ++j) {
    sc.friction[static_cast<size_t>(j)].Fc = 0.02 * robot.tau_max[j];
    sc.friction[static_cast<size_t>(j)].beta = 0.01 * robot.tau_max[j] / robot.qd_max[j];
  }
  sc.stop_and_go = drive::StopAndGo{3.0, 1.5, 0.4};  // at rest from 3.0 s to 4.1 s
  const std::string flash = flash_path("cobot7_stiction");
  // Per joint, the spread of the encoder reading over [from, to) s of a run of the scenario.
  auto spread = [&](const Scenario& s, double from, double to) {
    std::filesystem::remove(flash);
    SimulatedDrive d(robot, s, flash);
    d.trajectory = default_excitation(robot, 0.1, 5, 1, 3, nullptr);
    d.periods = 1;
    std::vector<dyncal::port::DriveSample> samples;
    play(d, to, &samples);
    EXPECT_EQ(d.state(), mm::DriveState::playing) << to_string(d.fault());
    std::vector<double> lo(static_cast<size_t>(n), 1e30), hi(static_cast<size_t>(n), -1e30);
    for (const auto& x : samples) {
      if (x.seq * d.control_period() < from) continue;
      for (int j = 0; j < n; ++j) {
        lo[static_cast<size_t>(j)] = std::min(lo[static_cast<size_t>(j)], static_cast<double>(x.q[j]));
        hi[static_cast<size_t>(j)] = std::max(hi[static_cast<size_t>(j)], static_cast<double>(x.q[j]));
      }
    }
    std::vector<double> out(static_cast<size_t>(n));
    for (int j = 0; j < n; ++j) out[static_cast<size_t>(j)] = hi[static_cast<size_t>(j)] - lo[static_cast<size_t>(j)];
    return std::make_pair(out, samples.empty() ? dyncal::port::DriveSample{} : samples.back());
  };
  Scenario kinetic = sc;
  kinetic.stiction = false;
  sc.stiction = true;
  const auto [still, at_rest] = spread(sc, 3.5, 4.1);
  const auto creep = spread(kinetic, 3.5, 4.1).first;
  double most_creep = 0;
  for (int j = 0; j < n; ++j) {
    EXPECT_EQ(still[static_cast<size_t>(j)], 0.0) << "joint " << j + 1 << " moved at rest with static friction";
    most_creep = std::max(most_creep, creep[static_cast<size_t>(j)]);
  }
  const double count = 2 * M_PI / (1 << 20) / robot.gear_ratios[0];  // joint 1's encoder count [rad]
  EXPECT_GT(most_creep, 10 * count) << "the kinetic plant's rest did not creep: the comparison shows nothing";

  // A push on link 1 at 3.6-3.7 s (it loads joint 1 alone): three times joint 1's Fc.
  JointArray q{};
  for (int j = 0; j < n; ++j) q[static_cast<size_t>(j)] = at_rest.q[j];
  const std::array<double, 3> point{0.1, 0.1, 0.0};
  std::filesystem::remove(flash);
  const SimulatedDrive probe(robot, sc, flash);
  std::array<double, 3> best{};
  double best_torque = 0;
  for (int axis = 0; axis < 3; ++axis) {
    std::array<double, 3> f{};
    f[static_cast<size_t>(axis)] = 1.0;
    const double t = probe.contact_torque(q, 1, point, f)[0];
    if (std::abs(t) > std::abs(best_torque)) best_torque = t, best = f;
  }
  ASSERT_GT(std::abs(best_torque), 1e-3);
  ExternalContact push;
  push.link = 1;
  push.point = point;
  for (int k = 0; k < 3; ++k)
    push.force[static_cast<size_t>(k)] = best[static_cast<size_t>(k)] * 3.0 * sc.friction[0].Fc / best_torque;
  push.start = 3.6;
  push.duration = 0.1;
  Scenario pushed = sc;
  pushed.contacts.push_back(push);
  EXPECT_GT(spread(pushed, 3.5, 3.8).first[0], 10 * count) << "a push of 3 Fc left joint 1 stuck";
  const auto after = spread(pushed, 3.95, 4.1).first;
  for (int j = 0; j < n; ++j)
    EXPECT_EQ(after[static_cast<size_t>(j)], 0.0) << "joint " << j + 1 << " did not stall again after the push";
  std::filesystem::remove(flash);
}
