#pragma once
// ScenarioArm<Robot>: the Linux simulated drive's arm, one generated robot model as the scenario
// makes it (scenario.hpp): forward dynamics of M(q) + the motors' rotor inertia (RK4, zero-order
// hold of the command), friction per motor through the transmission, the scenario's effects,
// couplings, static friction and external contacts, a payload on the last link, encoder
// quantisation and torque noise. It is the port::Joints (dyncal/port.hpp) lib/'s drive application
// drives (DrivePlantOf, drive_plant_of.hpp): the test's independent truth, written apart from the
// drive's models (the firmware drive's arm is port/replay/simulated_arm.hpp).

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "dyncal/inertial_parameters.hpp"
#include "dyncal/port.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/contact_force.hpp"
#include "dyncal_host/drive/drive_plant.hpp"
#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

template <class Robot>
class ScenarioArm final : public port::Joints<double> {
 public:
  static constexpr int N = Robot::kNumJoints;
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  using StdVec = Eigen::Matrix<double, Robot::kNumStandard, 1>;

  /// The arm of `robot` (its joint origins `origins`, CAD standard parameters `nominal_standard`)
  /// in `scenario`, one control period dt [s] per actuate().
  ScenarioArm(const double* nominal_standard, const JointOrigins& origins, const RobotDescription& robot,
              const Scenario& scenario)
      : origins_(origins), scenario_(scenario), dt_(1.0 / scenario.control_rate_hz), rng_(scenario.seed) {
    for (int j = 0; j < N; ++j) {
      for (int k = 0; k < N; ++k) motor_(j, k) = scenario.motor_map[static_cast<size_t>(j)][static_cast<size_t>(k)];
      quantum_[j] =
          scenario.encoder_counts > 0 ? 2.0 * M_PI / (scenario.encoder_counts * std::fabs(robot.gear_ratios[j])) : 0.0;
    }
    // The rotor inertias at their motors' accelerations: sum_m Ia_m T_m^T T_m (diag(Ia) without
    // coupled motors).
    for (int m = 0; m < N; ++m) rotor_ += scenario.effects[m].rotor_inertia * motor_.row(m).transpose() * motor_.row(m);
    // The scenario's payload on the last link, added to the nominal standard parameters.
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_[i] = nominal_standard[i];
    const auto& pl = scenario.payload;
    if (pl.mass > 0) add_rigid_load(phi_.data() + Robot::kNumStandard - 10, pl.mass, pl.com.data(), pl.inertia.data());
  }

  /// The plant's standard parameters (kNumStandard, generated order). Throws InputError on a size
  /// mismatch.
  void set_standard(const std::vector<double>& phi_standard) {
    if (static_cast<int>(phi_standard.size()) != Robot::kNumStandard)
      throw InputError("plant parameters: expected " + std::to_string(Robot::kNumStandard) + " standard parameters");
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_[i] = phi_standard[static_cast<size_t>(i)];
  }

  /// The plant's standard parameters [kNumStandard] (the payload included).
  const double* standard() const { return phi_.data(); }

  /// Which periods' measured torque the drive reads: every `every`-th from place() (its recorded
  /// samples), or every one (`always`: its collision monitor watches). The sensor's noise is drawn
  /// for those only (the others measure the command exactly and nothing reads them): a seed gives
  /// the same noise on the recorded samples at any control rate, watched or not.
  void read_measurements(long every, bool always) {
    read_every_ = every > 0 ? every : 1;
    read_always_ = always;
  }

  /// The arm at q moving at qd: the run's time starts at 0 (the contacts' clock), the motors move.
  void place(const double* q, const double* qd) noexcept override {
    for (int j = 0; j < N; ++j) {
      q_[j] = q[j];
      qd_[j] = qd[j];
    }
    stuck_.fill(false);
    run_time_ = 0;
    periods_ = 0;
    anchors_.assign(scenario_.contacts.size(), std::nullopt);
  }

  /// The encoders: q quantised to the encoder's quantum on the joint side.
  void sense(double* q) noexcept override {
    for (int j = 0; j < N; ++j) q[j] = quantum_[j] > 0 ? quantum_[j] * std::round(q_[j] / quantum_[j]) : q_[j];
  }

  /// One control period of tau_command (plus the contacts' torques, held over it); the measured
  /// torque is the command with the sensor's noise (scenario tau_noise_std).
  void actuate(const double* tau_command, double* tau_measured) noexcept override {
    Vec tau;
    for (int j = 0; j < N; ++j) tau[j] = tau_command[j];
    last_.t = run_time_;
    const bool read = read_always_ || periods_ % read_every_ == 0;
    for (int j = 0; j < N; ++j) {
      last_.q[j] = q_[j];
      last_.qd[j] = qd_[j];
      last_.tau_cmd[j] = tau[j];
      tau_measured[j] = read ? tau[j] + scenario_.tau_noise_std[j] * normal_(rng_) : tau[j];
      last_.tau_measured[j] = tau_measured[j];
    }
    Vec qdd0;
    integrate(scenario_.contacts.empty() ? tau : (tau + contact_torques(run_time_)).eval(), qdd0);
    for (int j = 0; j < N; ++j) last_.qdd[j] = qdd0[j];
    run_time_ += dt_;
    clock_ += dt_;
    ++periods_;
  }

  /// The exact state at the last actuate()'s period start and what it commanded and measured.
  const PlantSample& last() const { return last_; }

 private:
  /// The velocity a motor's friction is evaluated at while its velocity is zero or against its
  /// direction: its sign alone matters (a Stribeck law's value at 0+).
  static constexpr double kStartVelocity = 1e-12;
  /// The stuck motors' holding forces f_m and their friction's values at -0 and +0.
  struct Hold {
    Vec force = Vec::Zero();
    Vec lo = Vec::Zero(), hi = Vec::Zero();
  };

  void integrate(const Vec& tau_cmd, Vec& qdd0);
  int stable_substeps() const;
  Eigen::MatrixXd stuck_rows() const;
  void accel(const Vec& tau_cmd, const Vec& q, const Vec& qd, Vec& qdd, Hold* hold) const;
  void release_stuck(const Vec& tau_cmd, Vec& a1);
  void catch_stuck();

  /// The external contacts' joint torques at the period's start, held over it as the command is
  /// (ExternalContact: a fixed force, or a stiff obstacle anchored where the point was when the
  /// contact began).
  Vec contact_torques(double time) {
    Vec tau = Vec::Zero();
    for (size_t c = 0; c < scenario_.contacts.size(); ++c) {
      const ExternalContact& e = scenario_.contacts[c];
      if (time < e.start || time >= e.start + e.duration) continue;
      const Eigen::Vector3d p = link_point_position(origins_, N, q_.data(), e.link, e.point);
      if (!anchors_[c]) anchors_[c] = p;
      Eigen::Vector3d F(e.force[0], e.force[1], e.force[2]);
      if (e.stiffness > 0) {
        const Eigen::Vector3d n = F.normalized();
        const double depth = (p - *anchors_[c]).dot(n);
        F = depth < 0 ? Eigen::Vector3d(-e.stiffness * depth * n) : Eigen::Vector3d::Zero();
      }
      const auto t = contact_joint_torque(origins_, N, q_.data(), e.link, e.point, F);
      for (int j = 0; j < N; ++j) tau[j] += t[static_cast<size_t>(j)];
    }
    return tau;
  }

  JointOrigins origins_;
  Scenario scenario_;
  double dt_;
  StdVec phi_;                              // the plant's standard parameters (the payload added)
  Mat motor_ = Mat::Identity();             // Scenario::motor_map: motor velocities v = T qd
  Mat rotor_ = Mat::Zero();                 // the motors' rotor inertia on the joints: sum_m Ia_m T_m^T T_m
  Vec quantum_ = Vec::Zero();               // encoder resolution on the joint side [rad]
  Vec q_ = Vec::Zero(), qd_ = Vec::Zero();  // plant state
  std::array<bool, N> stuck_{};             // Scenario::stiction: motor m held at rest by its static friction
  // With stiction, each moving motor's direction over a substep (its velocity's sign at the start,
  // a released motor's the way it starts; 0 for a stuck one and without stiction): its friction
  // keeps that sign in every RK4 stage (a stage that crosses zero would otherwise flip it and throw
  // a light joint back), and a velocity that ends the substep against it crossed zero.
  std::array<double, N> direction_{};
  Eigen::MatrixXd stuck_T_;                              // rows T_m of the stuck motors
  std::vector<std::optional<Eigen::Vector3d>> anchors_;  // per scenario contact: where its obstacle sits
  double run_time_ = 0;                                  // since place() [s]: the contacts' clock
  double clock_ = 0;                                     // since the drive started [s]: warm-up effects
  long periods_ = 0;                                     // since place()
  long read_every_ = 1;                                  // read_measurements
  bool read_always_ = true;
  PlantSample last_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

/// Plant: (M(q) + sum_m Ia_m T_m^T T_m) qdd = tau - h(q, qd) - T^T f(T qd) - effects, RK4 with
/// zero-order hold (T the motor map, f the motors' friction; the identity without coupled motors).
/// qdd0: the acceleration at the period's start (the first RK4 stage).
/// With scenario.stiction the motors in stuck_ are held: their velocities v_S = T_S qd stay zero by
/// a holding torque T_S^T f_S in place of their friction, f_S = (T_S M^-1 T_S^T)^-1 T_S M^-1 rhs
/// (the constraint's force, Gauss's principle). At each substep's start a motor whose f_m leaves
/// [friction(-0), friction(+0)] is released (release_stuck); within a substep each moving motor's
/// friction keeps the sign of its direction at the start; after the substep a motor whose velocity
/// ended against that direction is caught (catch_stuck), and the next substep's start decides if it
/// holds.
template <class Robot>
void ScenarioArm<Robot>::integrate(const Vec& tau_cmd, Vec& qdd0) {
  direction_.fill(0.0);
  stuck_T_ = scenario_.stiction ? stuck_rows() : Eigen::MatrixXd();
  const int substeps = stable_substeps();
  const double hstep = dt_ / substeps;
  for (int k = 0; k < substeps; ++k) {
    Vec a1, a2, a3, a4;
    if (scenario_.stiction) {
      release_stuck(tau_cmd, a1);
    } else {
      accel(tau_cmd, q_, qd_, a1, nullptr);
    }
    if (k == 0) qdd0 = a1;
    accel(tau_cmd, q_ + 0.5 * hstep * qd_, qd_ + 0.5 * hstep * a1, a2, nullptr);
    accel(tau_cmd, q_ + 0.5 * hstep * (qd_ + 0.5 * hstep * a1), qd_ + 0.5 * hstep * a2, a3, nullptr);
    accel(tau_cmd, q_ + hstep * (qd_ + 0.5 * hstep * a2), qd_ + hstep * a3, a4, nullptr);
    q_ += hstep * qd_ + hstep * hstep / 6.0 * (a1 + a2 + a3);
    qd_ += hstep / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    if (scenario_.stiction) catch_stuck();
  }
}

/// Explicit RK4 is stable for a damping rate lambda while h lambda < 2.78. The viscous friction of
/// a light link (no rotor inertia, or a light plant under test) can exceed that at the nominal
/// substep: substeps grow with lambda_max(M^-1 B), B = T^T diag(beta) T, at the period's start.
template <class Robot>
int ScenarioArm<Robot>::stable_substeps() const {
  int substeps = scenario_.substeps;
  Mat M;
  Robot::mass_matrix(q_, phi_, M);
  M += rotor_;
  const Eigen::LLT<Mat> llt(M);
  if (llt.info() != Eigen::Success) return substeps;
  Vec beta_m;
  for (int j = 0; j < N; ++j) {
    const JointEffects& e = scenario_.effects[j];
    double beta = scenario_.friction[j].beta;
    if (e.viscous_drift != 0) beta *= 1.0 + e.viscous_drift;
    beta_m[j] = std::max(beta, 0.0);
  }
  const Mat B = motor_.transpose() * beta_m.asDiagonal() * motor_;  // T^T diag(beta) T
  // lambda_max(M^-1 B) = lambda_max(L^-1 B L^-T), bounded by its largest row sum.
  const Mat A = llt.matrixL().solve(llt.matrixL().solve(B).transpose());
  const double lambda = A.cwiseAbs().rowwise().sum().maxCoeff();
  return std::max(substeps, static_cast<int>(std::ceil(dt_ * lambda / 2.0)));
}

/// Rows T_m of the stuck motors.
template <class Robot>
Eigen::MatrixXd ScenarioArm<Robot>::stuck_rows() const {
  int k = 0;
  for (int m = 0; m < N; ++m) k += stuck_[m] ? 1 : 0;
  Eigen::MatrixXd T(k, N);
  for (int m = 0, r = 0; m < N; ++m) {
    if (stuck_[m]) T.row(r++) = motor_.row(m);
  }
  return T;
}

/// qdd at (q, qd) under tau_cmd: the motors' friction (at their direction's sign while their
/// velocity is zero or against it), the effects and couplings; the stuck motors held (hold: their
/// holding forces and friction(-0), friction(+0)).
template <class Robot>
void ScenarioArm<Robot>::accel(const Vec& tau_cmd, const Vec& q, const Vec& qd, Vec& qdd, Hold* hold) const {
  const double warm = clock_;
  Mat M;
  Robot::mass_matrix(q, phi_, M);
  M += rotor_;
  Vec h;
  Robot::inverse_dynamics(q, qd, Vec::Zero().eval(), phi_, h);
  Vec rhs = tau_cmd - h;
  const Vec v_motor = motor_ * qd;
  for (int j = 0; j < N; ++j) {
    const JointEffects& e = scenario_.effects[j];
    JointFriction f = scenario_.friction[j];
    if (e.viscous_drift != 0) f.beta *= 1.0 + e.viscous_drift * (1.0 - std::exp(-warm / e.drift_time_constant));
    const bool held = scenario_.stiction && stuck_[j];
    double friction = 0;  // motor j's, at its velocity (held: its share of the holding torque)
    if (!held) {
      double v = v_motor[j];
      if (direction_[j] != 0 && v * direction_[j] <= 0) v = direction_[j] * kStartVelocity;
      friction = friction_torque(f, v, h[j]);
    }
    for (int k = 0; k < N; ++k) {
      if (k != j && motor_(j, k) != 0.0) rhs[k] -= motor_(j, k) * friction;
    }
    double tf = motor_(j, j) * friction + e.offset;
    if (e.load_friction != 0 && !held) {
      const double sg = direction_[j] != 0 ? direction_[j] : (qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0));
      tf += e.load_friction * std::fabs(h[j]) * sg;
    }
    if (e.cogging_amplitude != 0) tf += e.cogging_amplitude * std::sin(e.cogging_cycles * q[j] + e.cogging_phase);
    rhs[j] -= tf;
    if (hold != nullptr) {
      hold->hi[j] = friction_torque(f, kStartVelocity, h[j]) + e.load_friction * std::fabs(h[j]);
      hold->lo[j] = friction_torque(f, -kStartVelocity, h[j]) - e.load_friction * std::fabs(h[j]);
    }
  }
  for (const CoupledFriction& c : scenario_.couplings) {
    const double v = qd[c.joint_i] + c.sign * qd[c.joint_j];
    const double f = c.Fc * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0)) + c.beta * v;
    rhs[c.joint_i] -= f;
    rhs[c.joint_j] -= c.sign * f;
  }
  const Eigen::LDLT<Mat> ldlt(M);
  qdd = ldlt.solve(rhs);
  if (stuck_T_.rows() == 0) return;
  const Eigen::MatrixXd& T = stuck_T_;
  const Eigen::MatrixXd MinvTt = ldlt.solve(T.transpose());  // M^-1 T_S^T
  const Eigen::VectorXd f = (T * MinvTt).ldlt().solve(T * qdd);
  qdd -= MinvTt * f;
  if (hold != nullptr) {
    for (int m = 0, r = 0; m < N; ++m) {
      if (stuck_[m]) hold->force[m] = f[r++];
    }
  }
}

/// A substep's start with stiction: each motor's direction (its velocity's sign; 0 when stuck),
/// then the stuck motors whose holding torque their static friction cannot give released, the
/// largest excess first and the rest re-solved, each starting in its force's direction. a1: the
/// acceleration with the motors left stuck.
template <class Robot>
void ScenarioArm<Robot>::release_stuck(const Vec& tau_cmd, Vec& a1) {
  const Vec v = motor_ * qd_;
  for (int m = 0; m < N; ++m) direction_[m] = stuck_[m] ? 0.0 : (v[m] > 0 ? 1.0 : (v[m] < 0 ? -1.0 : 0.0));
  Hold hold;
  for (;;) {
    accel(tau_cmd, q_, qd_, a1, &hold);
    int worst = -1;
    double excess = 0;
    for (int m = 0; m < N; ++m) {
      if (!stuck_[m]) continue;
      const double over = std::max(hold.force[m] - hold.hi[m], hold.lo[m] - hold.force[m]);
      if (over > excess) excess = over, worst = m;
    }
    if (worst < 0) return;
    stuck_[worst] = false;
    direction_[worst] = hold.force[worst] > hold.hi[worst] ? 1.0 : -1.0;
    stuck_T_ = stuck_rows();
  }
}

/// A substep's end with stiction: the motors whose velocity crossed or reached zero (a released
/// one: that did not move the way it started) caught, then every stuck one held exactly at rest: qd
/// projected onto v_S = 0 in the metric of M (the velocity change an impulse along T_S^T makes).
template <class Robot>
void ScenarioArm<Robot>::catch_stuck() {
  const Vec v_after = motor_ * qd_;
  for (int m = 0; m < N; ++m) {
    if (stuck_[m]) continue;
    const JointFriction& f = scenario_.friction[m];
    const bool sticks = friction_torque(f, kStartVelocity, 0.0) > friction_torque(f, -kStartVelocity, 0.0) ||
                        scenario_.effects[m].load_friction > 0;  // a frictionless motor never sticks
    if (sticks && direction_[m] * v_after[m] <= 0) stuck_[m] = true;
  }
  stuck_T_ = stuck_rows();
  const Eigen::MatrixXd& T = stuck_T_;
  if (T.rows() == 0) return;
  Mat M;
  Robot::mass_matrix(q_, phi_, M);
  M += rotor_;
  const Eigen::LDLT<Mat> ldlt(M);
  const Eigen::MatrixXd MinvTt = ldlt.solve(T.transpose());
  qd_ -= MinvTt * (T * MinvTt).ldlt().solve(T * qd_);
}

}  // namespace dyncal::host
