#pragma once
// Simulated logs of a compiled robot for the tests: the designed excitation played on a motion
// clock (with or without rests), exact inverse dynamics of robot.json's inertials, Coulomb +
// viscous friction with sgn(0) = 0 at rest, optional extra torque (an effect the model may lack),
// Gaussian torque noise, encoder quantisation; and a logger's time stamps (jitter, missing samples).
#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "dyncal/drive/stop_and_go.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/logs/joint_log.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "support/test_paths.hpp"

namespace dyncal::test {

using host::JointLog;
using host::RobotDescription;

/// A test robot from tests/robots/ with its tau_max derived when robot.json gives none.
inline RobotDescription test_robot(const std::string& name) {
  RobotDescription r = host::load_robot(std::string(dyncal::test::source_dir()) + "/tests/robots", name);
  host::derive_tau_max(r);
  return r;
}

/// Torque [Nm] an effect adds at (q, qd, qdd), written into tau (N entries, added).
using ExtraTorque = std::function<void(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                                       Eigen::VectorXd& tau)>;

/// The arm's motion clock: u(t) = t without rests; with rests, point-to-point operation
/// (lib's drive::StopAndGo, as the simulated drive plays it): the designed trajectory is played for
/// `move` seconds, then held still for `rest` seconds, repeatedly, with ramps of constant
/// deceleration and acceleration of the clock (0.4 s) between, as a robot stops and starts.
/// rate: the trajectory's speed without rests (0.1: a tenth of the designed speed, a slow log).
struct MotionClock {
  bool rests = false;
  double move = 3.0, rest = 1.5, ramp = 0.4;
  double rate = 1.0;
  /// Speed w(t) = du/dt and its derivative.
  void speed(double t, double& w, double& wd) const {
    w = rate, wd = 0;
    if (!rests) return;
    double u = 0;
    drive::StopAndGo{move, rest, ramp}.at(t, u, w, wd);
  }
};

/// A 20-bit absolute encoder on every joint [rad].
inline constexpr double kEncoderStep = 2 * M_PI / (1 << 20);

struct SimulatedLog {
  JointLog log;
  Eigen::VectorXd phi, sigma;
  std::vector<char> at_rest;  ///< per sample: every joint's true velocity is 0
};

/// Samples at times `times` of the designed excitation played on `clock`: tau = ID + Fc sgn(qd) +
/// Fv qd + noise (Fc 2 %, Fv qd_max 1 %, noise 0.5 % of tau_max); q read by kEncoderStep encoders.
/// extra: an effect's torque added before the noise (none if empty). encoder_step: 0 for exact q.
/// held: joints (0-based) held still at the trajectory's start position (a log that leaves their
/// friction and the inertials only they move undetermined).
inline SimulatedLog simulate(const RobotDescription& robot, const std::vector<double>& times, const MotionClock& clock,
                             unsigned seed, unsigned trajectory_seed = 3, const ExtraTorque& extra = {},
                             double encoder_step = kEncoderStep, const std::vector<int>& held = {}) {
  const host::CompiledRobot& c = host::compiled_robot_for(robot);
  host::ExciteOptions xo;
  xo.seed = trajectory_seed;
  const host::ExcitationTrajectory traj = host::design_excitation(robot, xo).trajectory;
  const int n = robot.num_joints;
  SimulatedLog s;
  const Eigen::VectorXd phi_std = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  const Eigen::VectorXd Fc = 0.02 * robot.tau_max, Fv = (0.01 * robot.tau_max).cwiseQuotient(robot.qd_max);
  s.sigma = 0.005 * robot.tau_max;
  s.phi.resize(c.num_base + 2 * n);
  s.phi.head(c.num_base) = c.standard_to_base(phi_std);
  for (int j = 0; j < n; ++j) {
    s.phi[c.num_base + 2 * j] = Fc[j];
    s.phi[c.num_base + 2 * j + 1] = Fv[j];
  }
  const Eigen::Index S = static_cast<Eigen::Index>(times.size());
  JointLog& log = s.log;
  log.t.resize(S);
  log.q.resize(S, n);
  log.qd.resize(S, n);
  log.qdd.resize(S, n);
  log.tau.resize(S, n);
  s.at_rest.assign(times.size(), 0);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  double u = 0, t_prev = 0;
  for (Eigen::Index k = 0; k < S; ++k) {
    const double t = times[static_cast<size_t>(k)];
    // u = integral of w: Simpson on each interval (w is a polynomial in t between its breaks).
    if (k > 0) {
      double w0, w1, wm, d;
      clock.speed(t_prev, w0, d);
      clock.speed(0.5 * (t_prev + t), wm, d);
      clock.speed(t, w1, d);
      u += (t - t_prev) / 6.0 * (w0 + 4 * wm + w1);
    } else {
      u = t;
    }
    t_prev = t;
    double w, wd;
    clock.speed(t, w, wd);
    Eigen::Matrix<double, 7, 1> q7, qd7, qdd7;
    traj.evaluate(u, q7, qd7, qdd7);
    Eigen::VectorXd q = q7.head(n), qd = w * qd7.head(n), qdd = w * w * qdd7.head(n) + wd * qd7.head(n);
    for (int j : held) {
      Eigen::Matrix<double, 7, 1> q0, qd0, qdd0;
      traj.evaluate(0.0, q0, qd0, qdd0);
      q[j] = q0[j], qd[j] = 0.0, qdd[j] = 0.0;
    }
    s.at_rest[static_cast<size_t>(k)] = w == 0.0;
    Eigen::VectorXd tau = c.inverse_dynamics(q, qd, qdd, phi_std);
    if (extra) extra(q, qd, qdd, tau);
    for (int j = 0; j < n; ++j)
      tau[j] += Fc[j] * (qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0)) + Fv[j] * qd[j] + s.sigma[j] * normal(rng);
    log.t[k] = t;
    log.q.row(k) = encoder_step > 0 ? Eigen::VectorXd((q / encoder_step).array().round().matrix() * encoder_step) : q;
    log.qd.row(k) = qd.transpose();
    log.qdd.row(k) = qdd.transpose();
    log.tau.row(k) = tau.transpose();
  }
  log.has_qd = log.has_qdd = false;
  log.source = "simulated " + robot.name;
  return s;
}

inline std::vector<double> uniform_times(double fs, double seconds) {
  std::vector<double> t;
  for (long k = 0; k < std::lround(seconds * fs); ++k) t.push_back(static_cast<double>(k) / fs);
  return t;
}

/// A logger's time stamps: nominal period 1 / fs, each stamp off by a uniform jitter of RMS
/// `jitter` periods (never reordering), a fraction `drop` of the samples missing.
inline std::vector<double> logger_times(double fs, double seconds, double jitter, double drop, unsigned seed) {
  std::mt19937_64 rng(seed);
  const double half = jitter * std::sqrt(3.0);  // uniform on [-half, half] has RMS `jitter`
  std::uniform_real_distribution<double> u(-half, half), keep(0, 1);
  std::vector<double> t;
  for (long k = 0; k < std::lround(seconds * fs); ++k) {
    if (k > 0 && keep(rng) < drop) continue;
    t.push_back((static_cast<double>(k) + u(rng)) / fs);
  }
  return t;
}

/// A PC logger that stamps samples on arrival: the robot samples on its own regular clock (period
/// 1 / fs, a fraction `drop` of the samples lost on the way), and each stamp is off its sampling
/// instant by a uniform error in [-half_width, half_width] periods. Returns the sampling instants
/// (simulate() at these) and writes the stamps (the log's t) into `stamps`.
inline std::vector<double> arrival_stamped_times(double fs, double seconds, double half_width, double drop,
                                                 unsigned seed, std::vector<double>& stamps) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half_width, half_width), keep(0, 1);
  std::vector<double> t;
  stamps.clear();
  for (long k = 0; k < std::lround(seconds * fs); ++k) {
    if (k > 0 && keep(rng) < drop) continue;
    t.push_back(static_cast<double>(k) / fs);
    stamps.push_back((static_cast<double>(k) + u(rng)) / fs);
  }
  return t;
}

}  // namespace dyncal::test
