#pragma once
// DrivePlantOf<Robot>: the simulated drive's plant for one generated robot model (drive_plant.hpp).
// Included by the robots' registration units (host_sim/robots/robot_drive.cpp.in) only: each robot
// compiles its own fixed-size copy.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "dyncal/drive/collision_monitor.hpp"
#include "dyncal/drive/term_sets.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/drive/contact_force.hpp"
#include "dyncal_host/drive/drive_plant.hpp"

namespace dyncal::host {

/// The generated model's namespace-level data a plant needs besides the Robot type.
struct GeneratedRobotData {
  const double* nominal_standard;                    ///< kNominalStandard [kNumStandard]
  const double* rotor_inertia_absorbed_coefficient;  ///< kRotorInertiaAbsorbedCoefficient [kNumJoints]
  JointOrigins origins;                              ///< kJointOrigins (contact forces)
};

template <class Robot>
class DrivePlantOf final : public DrivePlant {
 public:
  static constexpr int N = Robot::kNumJoints;
  static_assert(N >= 1 && N <= kMaxDriveJoints, "the simulated drive runs 1 to kMaxDriveJoints joints");
  using Vec = Eigen::Matrix<double, N, 1>;
  using Mat = Eigen::Matrix<double, N, N>;
  using StdVec = Eigen::Matrix<double, Robot::kNumStandard, 1>;

  explicit DrivePlantOf(const GeneratedRobotData& data) : data_(data) {
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_true_[i] = data_.nominal_standard[i];
  }

  std::uint32_t robot_id() const override { return Robot::kRobotId; }
  int num_joints() const override { return N; }
  int num_standard() const override { return Robot::kNumStandard; }

  TableStatus check(const ParameterTable& t) const override {
    if (t.robot_id != Robot::kRobotId) return TableStatus::wrong_robot;
    const std::optional<ModelOps> ops = find_ops(t.model_id);
    return ops ? ops->check(t, ratings_) : TableStatus::wrong_model;
  }

  ParameterTable nominal_table(const JointArray& Fc, const JointArray& beta) const override {
    using Model = IdentificationModel<Robot, kFrictionEq7>;
    StdVec phi_std;
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_std[i] = data_.nominal_standard[i];
    Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
    Robot::standard_to_base(phi_std, phi_b);
    typename Model::template ParamVector<double> phi = Model::template ParamVector<double>::Zero();
    phi.template head<Robot::kNumBase>() = phi_b;
    for (int i = Robot::kNumBase; i < Model::kNumParams; ++i) {
      const ParamInfo info = Model::info(i);
      const size_t j = static_cast<size_t>(info.joint - 1);
      phi[i] = info.term == term::coulomb ? Fc[j] : beta[j];
    }
    ParameterTable t;
    make_table<Model>(phi, t);
    return t;
  }

  std::vector<TrueParameter> true_parameters(const Scenario& s, unsigned terms) const override {
    return with_term_set<Truth>(terms, s, data_);
  }

  void configure(const RobotDescription& robot, const Scenario& scenario) override {
    q_min_ = robot.q_min;
    q_max_ = robot.q_max;
    qd_max_ = robot.qd_max;
    for (int j = 0; j < N; ++j) {
      ratings_.tau_max[j] = robot.tau_max.size() == N ? static_cast<float>(robot.tau_max[j]) : 0.0f;
      ratings_.qd_max[j] = static_cast<float>(robot.qd_max[j]);
      ratings_.qdd_max[j] = static_cast<float>(robot.qdd_max[j]);
      ratings_.q_min[j] = static_cast<float>(robot.q_min[j]);
      ratings_.q_max[j] = static_cast<float>(robot.q_max[j]);
      for (int k = 0; k < N; ++k) motor_(j, k) = scenario.motor_map[static_cast<size_t>(j)][static_cast<size_t>(k)];
      quantum_[j] =
          scenario.encoder_counts > 0 ? 2.0 * M_PI / (scenario.encoder_counts * std::fabs(robot.gear_ratios[j])) : 0.0;
    }
    // The rotor inertias at their motors' accelerations: sum_m Ia_m T_m^T T_m (diag(Ia) without
    // coupled motors).
    rotor_.setZero();
    for (int m = 0; m < N; ++m) rotor_ += scenario.effects[m].rotor_inertia * motor_.row(m).transpose() * motor_.row(m);
    // The scenario's payload on the last link: its standard parameters about the link origin
    // (first moments m c; inertia by the parallel-axis theorem) added to the nominal ones.
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_true_[i] = data_.nominal_standard[i];
    const auto& pl = scenario.payload;
    if (pl.mass > 0) {
      const Eigen::Vector3d c(pl.com[0], pl.com[1], pl.com[2]);
      Eigen::Matrix3d I;
      I << pl.inertia[0], pl.inertia[1], pl.inertia[2], pl.inertia[1], pl.inertia[3], pl.inertia[4], pl.inertia[2],
          pl.inertia[4], pl.inertia[5];
      const Eigen::Matrix3d Io = I + pl.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
      const double d[10] = {Io(0, 0), Io(0, 1),       Io(0, 2),       Io(1, 1),       Io(1, 2),
                            Io(2, 2), pl.mass * c[0], pl.mass * c[1], pl.mass * c[2], pl.mass};
      for (int i = 0; i < 10; ++i) phi_true_[Robot::kNumStandard - 10 + i] += d[i];
    }
  }

  void set_plant_parameters(const std::vector<double>& phi_standard) override {
    if (static_cast<int>(phi_standard.size()) != Robot::kNumStandard) {
      throw InputError("plant parameters: expected " + std::to_string(Robot::kNumStandard) + " standard parameters");
    }
    for (int i = 0; i < Robot::kNumStandard; ++i) phi_true_[i] = phi_standard[static_cast<size_t>(i)];
  }

  void set_active(const ParameterTable& table) override {
    ops_ = *find_ops(table.model_id);
    active_ = table;
  }

  void begin(const DriveTrajectory& trajectory, const Scenario& scenario, bool gains_fixed, double dt) override {
    payload_running_ = false;  // begin_payload() after begin() turns it on for the run
    Vec q_d, qd_d, qdd_d;
    trajectory.evaluate(0.0, q_d, qd_d, qdd_d);  // the simulation starts on the trajectory
    q_ = q_d;
    qd_ = qd_d;
    stuck_.fill(false);
    q_meas_prev_ = quantise(q_) - qd_d * dt;
    anchors_.assign(scenario.contacts.size(), std::nullopt);
    begin_monitor(dt);
    if (gains_fixed) return;
    // PD gains from the arm's inertia at the start pose, M_jj(q0) + Ia_j: natural frequency
    // bandwidth_hz, damping zeta. Capped for stability where the arm is light: the loop closes on
    // a backward-difference velocity, and the discrete velocity loop needs kd dt / m_eff < 2 at
    // every pose, m_eff = 1 / (M + Ia)^-1_jj the joint's effective inertia (the diagonal of M
    // ignores the coupling of the links). With half that margin, kd dt / min m_eff <= 1, the
    // inertia the gains are set for is at most min_trajectory m_eff / (2 zeta w dt).
    const double w = 2.0 * M_PI * scenario.bandwidth_hz;
    Mat M;
    Robot::mass_matrix(q_, phi_true_, M);
    const Vec m_eff = lightest_effective_inertia(trajectory);
    M += rotor_;
    for (int j = 0; j < N; ++j) {
      const double m = std::min(M(j, j), m_eff[j] / (2.0 * scenario.damping * w * dt));
      kp_[j] = m * w * w;
      kd_[j] = 2.0 * scenario.damping * m * w;
    }
  }

  /// Per joint, the smallest 1 / (M + rotor inertia)^-1_jj on 400 points of one period of `trajectory`.
  Vec lightest_effective_inertia(const DriveTrajectory& trajectory) const {
    constexpr int kGrid = 400;
    Vec m = Vec::Constant(std::numeric_limits<double>::infinity());
    for (int k = 0; k < kGrid; ++k) {
      Vec q, qd, qdd;
      trajectory.evaluate(trajectory.period() * k / kGrid, q, qd, qdd);
      Mat M;
      Robot::mass_matrix(q, phi_true_, M);
      M += rotor_;
      m = m.cwiseMin(M.ldlt().solve(Mat::Identity()).diagonal().cwiseInverse());
    }
    return m;
  }

  PlantStep step(const DriveTrajectory& trajectory, const Scenario& scenario, const ParameterTable& active, double time,
                 double clock, double dt) override {
    PlantStep out;
    // Measurement: quantised encoder position, velocity by backward difference.
    const Vec q_meas = quantise(q_);
    const Vec qd_meas = (q_meas - q_meas_prev_) / dt;
    q_meas_prev_ = q_meas;
    out.trip = check_limits(q_meas, qd_meas);
    if (out.trip.fault != modbus_map::DriveFault::none) return out;
    // Control law (survey Fig. 3): feed-forward from the active table plus PD on the tracking error.
    Vec q_d, qd_d, qdd_d, tau_ff;
    if (scenario.stop_and_go.on()) {  // the trajectory on the point-to-point clock u(time)
      double u = 0, w = 1, wd = 0;
      scenario.stop_and_go.at(time, u, w, wd);
      trajectory.evaluate(u, q_d, qd_d, qdd_d);
      qdd_d = w * w * qdd_d + wd * qd_d;
      qd_d *= w;
    } else {
      trajectory.evaluate(time, q_d, qd_d, qdd_d);
    }
    ops_.feedforward(active, q_d, qd_d, qdd_d, tau_ff);
    const Vec tau_cmd = tau_ff + kp_.cwiseProduct(q_d - q_meas) + kd_.cwiseProduct(qd_d - qd_meas);
    for (int j = 0; j < N; ++j) {
      out.q_meas[j] = q_meas[j];
      out.qd_meas[j] = qd_meas[j];
      out.tau_ff[j] = tau_ff[j];
      out.tau_cmd[j] = tau_cmd[j];
      out.q[j] = q_[j];
      out.qd[j] = qd_[j];
      out.q_d[j] = q_d[j];
      out.qd_d[j] = qd_d[j];
      out.qdd_d[j] = qdd_d[j];
    }
    if (payload_running_) {
      Vec tau_model;
      ops_.feedforward(active, q_meas, qd_d, qdd_d, tau_model);
      for (int j = 0; j < N; ++j) out.tau_model[j] = tau_model[j];
    }
    if (scenario.contacts.empty()) {
      integrate(scenario, tau_cmd, clock, dt, out.qdd);
    } else {
      integrate(scenario, tau_cmd + contact_torques(scenario, time), clock, dt, out.qdd);
    }
    return out;
  }

  void begin_payload() override {
    payload_run_.begin();
    payload_running_ = true;
  }

  void update_payload(const PlantStep& p, const JointArray& tau_measured, const JointArray& r) override {
    Vec q, qd, qdd, residual, var;
    for (int j = 0; j < N; ++j) {
      q[j] = p.q_meas[j];
      qd[j] = p.qd_d[j];
      qdd[j] = p.qdd_d[j];
      residual[j] = tau_measured[j] - p.tau_model[j];
      var[j] = r[j];
    }
    payload_run_.update(q, qd, qdd, residual, var);
  }

  drive::PayloadVerdict payload_verdict() const override { return payload_run_.verdict(); }

  ParameterTable loaded_table(const ParameterTable& active, const drive::PayloadVerdict& v) const override {
    return drive::PayloadRun<Robot, double>::loaded(active, v);
  }

  std::string set_monitor(const MonitorSettings& m, double dt) override {
    if (std::string why = monitor_settings_error(m, dt); !why.empty()) return why;
    monitor_ = m;
    return {};
  }

  Trip monitor(const PlantStep& p, const JointArray& tau_measured) override {
    Vec q_in, tau_in;
    for (int j = 0; j < N; ++j) {
      q_in[j] = p.q_meas[j];
      tau_in[j] = tau_measured[j];
    }
    const auto c = collision_monitor_.update(q_in, tau_in);
    if (!c.tripped) return {};
    return {modbus_map::DriveFault::collision, c.joint, c.value};
  }

  JointArray monitor_residual() const override { return to_array(collision_monitor_.residual()); }
  JointArray monitor_widening() const override { return to_array(collision_monitor_.widening()); }

  modbus_map::MonitorState monitor_state() const override { return collision_monitor_.state(); }

  JointArray contact_torque(const JointArray& q, int link, const std::array<double, 3>& point,
                            const std::array<double, 3>& force) const override {
    return contact_joint_torque(data_.origins, N, q.data(), link, point, Eigen::Vector3d(force[0], force[1], force[2]));
  }

  void fix_gains(const JointArray& kp, const JointArray& kd) override {
    for (int j = 0; j < N; ++j) {
      kp_[j] = kp[j];
      kd_[j] = kd[j];
    }
  }
  JointArray kp() const override { return to_array(kp_); }
  JointArray kd() const override { return to_array(kd_); }

 private:
  /// Feed-forward tau = K(q, qd, qdd) phi and table check of one supported model.
  struct ModelOps {
    unsigned terms = 0;
    TableStatus (*check)(const ParameterTable&, const JointRatings<N>&) = nullptr;
    void (*feedforward)(const ParameterTable&, const Vec&, const Vec&, const Vec&, Vec&) = nullptr;
    void (*coulomb)(const ParameterTable&, Vec&) = nullptr;  ///< |Fc_j| of the table (0 without the column)
  };

  /// lib/'s dispatch of one term set (drive/term_sets.hpp), as the firmware drive runs it.
  template <unsigned Terms>
  static void coulomb(const ParameterTable& t, Vec& fc) {
    drive::TermSets<Robot, Terms>::coulomb(t, fc);
  }

  template <unsigned Terms>
  static void feedforward(const ParameterTable& t, const Vec& q, const Vec& qd, const Vec& qdd, Vec& tau) {
    drive::TermSets<Robot, Terms>::torque(t, q, qd, qdd, tau);
  }

  template <unsigned Terms>
  struct OpsFor {
    static ModelOps run() {
      ModelOps ops;
      ops.terms = Terms;
      ops.check = &check_table<IdentificationModel<Robot, Terms>>;  // the overload with the ratings
      ops.feedforward = &feedforward<Terms>;
      ops.coulomb = &coulomb<Terms>;
      return ops;
    }
  };

  /// The models this drive runs: the term sets the host tools build (model_terms.hpp).
  static std::optional<ModelOps> find_ops(std::uint32_t model_id) {
    if (!is_built_term_set(model_id)) return std::nullopt;
    return with_term_set<OpsFor>(model_id);
  }

  template <unsigned Terms>
  struct Truth {
    static std::vector<TrueParameter> run(const Scenario& s, const GeneratedRobotData& data);
  };

  Vec quantise(const Vec& q) const {
    Vec out = q;
    for (int j = 0; j < N; ++j) {
      if (quantum_[j] > 0) out[j] = quantum_[j] * std::round(out[j] / quantum_[j]);
    }
    return out;
  }

  /// The first limit the measurements break: a non-finite q or qd on any joint first (the plant
  /// diverged), then positions outside [q_min, q_max], then speeds above qd_max; joint 1 first.
  Trip check_limits(const Vec& q, const Vec& qd) const {
    for (int j = 0; j < N; ++j) {
      if (!std::isfinite(q[j]) || !std::isfinite(qd[j]))
        return {modbus_map::DriveFault::non_finite_state, j, std::numeric_limits<double>::quiet_NaN()};
    }
    for (int j = 0; j < N; ++j) {
      if (q[j] < q_min_[j] || q[j] > q_max_[j]) return {modbus_map::DriveFault::position_limit, j, q[j]};
    }
    for (int j = 0; j < N; ++j) {
      if (std::fabs(qd[j]) > qd_max_[j]) return {modbus_map::DriveFault::velocity_limit, j, qd[j]};
    }
    return {};
  }

  void integrate(const Scenario& scenario, const Vec& tau_cmd, double clock, double dt, JointArray& qdd0);

  /// The external contacts' joint torques at the period's start, held over it as the command is
  /// (ExternalContact: a fixed force, or a stiff obstacle anchored where the point was when the
  /// contact began).
  Vec contact_torques(const Scenario& scenario, double time) {
    Vec tau = Vec::Zero();
    for (size_t c = 0; c < scenario.contacts.size(); ++c) {
      const ExternalContact& e = scenario.contacts[c];
      if (time < e.start || time >= e.start + e.duration) continue;
      const Eigen::Vector3d p = link_point_position(data_.origins, N, q_.data(), e.link, e.point);
      if (!anchors_[c]) anchors_[c] = p;
      Eigen::Vector3d F(e.force[0], e.force[1], e.force[2]);
      if (e.stiffness > 0) {
        const Eigen::Vector3d n = F.normalized();
        const double depth = (p - *anchors_[c]).dot(n);
        F = depth < 0 ? Eigen::Vector3d(-e.stiffness * depth * n) : Eigen::Vector3d::Zero();
      }
      const auto t = contact_joint_torque(data_.origins, N, q_.data(), e.link, e.point, F);
      for (int j = 0; j < N; ++j) tau[j] += t[static_cast<size_t>(j)];
    }
    return tau;
  }

  static JointArray to_array(const Vec& v) {
    JointArray a{};
    for (int j = 0; j < N; ++j) a[j] = v[j];
    return a;
  }

  /// Starts lib/'s collision monitor for a run with the active table (drive/collision_monitor.hpp:
  /// off when the settings are off, refused when the observer cannot take the table).
  void begin_monitor(double dt) {
    Vec coulomb = Vec::Zero();
    if (monitor_.gain > 0) ops_.coulomb(active_, coulomb);
    collision_monitor_.begin(monitor_, active_, coulomb, dt);
  }

  GeneratedRobotData data_;
  StdVec phi_true_;
  drive::PayloadRun<Robot, double> payload_run_{data_.nominal_standard + Robot::kNumStandard - 10};
  bool payload_running_ = false;
  Mat motor_ = Mat::Identity();             // Scenario::motor_map: motor velocities v = T qd
  Mat rotor_ = Mat::Zero();                 // the motors' rotor inertia on the joints: sum_m Ia_m T_m^T T_m
  Vec q_ = Vec::Zero(), qd_ = Vec::Zero();  // plant state
  std::array<bool, N> stuck_{};             // Scenario::stiction: motor m held at rest by its static friction
  Vec q_meas_prev_ = Vec::Zero();
  Vec kp_ = Vec::Zero(), kd_ = Vec::Zero();
  Vec quantum_ = Vec::Zero();                                             // encoder resolution on the joint side [rad]
  Vec q_min_ = Vec::Zero(), q_max_ = Vec::Zero(), qd_max_ = Vec::Zero();  // the drive's trips
  JointRatings<N> ratings_{};                            ///< tau_max, qd_max, qdd_max: table plausibility (check_table)
  ModelOps ops_{};                                       // feed-forward and check of the active table's model
  ParameterTable active_{};                              // the active table (the monitor's model)
  std::vector<std::optional<Eigen::Vector3d>> anchors_;  // per scenario contact: where its obstacle sits
  MonitorSettings monitor_{};
  drive::CollisionMonitor<Robot, double> collision_monitor_;
};

/// Plant: (M(q) + sum_m Ia_m T_m^T T_m) qdd = tau - h(q, qd) - T^T f(T qd) - effects, RK4 with
/// zero-order hold (T the motor map, f the motors' friction; the identity without coupled motors).
/// qdd0: the acceleration at the period's start (the first RK4 stage).
/// With scenario.stiction the motors in stuck_ are held: their velocities v_S = T_S qd stay zero by
/// a holding torque T_S^T f_S in place of their friction, f_S = (T_S M^-1 T_S^T)^-1 T_S M^-1 rhs
/// (the constraint's force, Gauss's principle). At each substep's start a motor whose f_m leaves
/// [friction(-0), friction(+0)] is released (the largest excess first, then the rest re-solved)
/// and starts in f_m's direction against its friction. Within a substep each moving motor's friction
/// keeps the sign of its direction at the start; after the substep a motor whose velocity ended
/// against that direction (it crossed or reached zero) is caught: qd is projected onto v_S = 0 in the metric of M (the
/// velocity change an impulse along T_S^T makes), and the next substep's start decides if it holds.
template <class Robot>
void DrivePlantOf<Robot>::integrate(const Scenario& scenario, const Vec& tau_cmd, double clock, double dt,
                                    JointArray& qdd0) {
  const double warm = clock;
  const bool stiction = scenario.stiction;
  // The velocity a motor's friction is evaluated at while its velocity is zero or against its
  // direction (below): its sign alone matters (a Stribeck law's value at 0+).
  constexpr double kStartVelocity = 1e-12;
  // With stiction, each moving motor's direction over a substep (its velocity's sign at the start,
  // a released motor's the way it starts; 0 for a stuck one and without stiction): its friction
  // keeps that sign in every RK4 stage (a stage that crosses zero would otherwise flip it and throw
  // a light joint back), and a velocity that ends the substep against it crossed zero.
  std::array<double, N> direction{};
  struct Hold {
    Vec force = Vec::Zero();                 // f_m of the stuck motors
    Vec lo = Vec::Zero(), hi = Vec::Zero();  // friction(-0), friction(+0)
  };
  auto stuck_rows = [&]() {
    int k = 0;
    for (int m = 0; m < N; ++m) k += stuck_[m] ? 1 : 0;
    Eigen::MatrixXd T(k, N);
    for (int m = 0, r = 0; m < N; ++m) {
      if (stuck_[m]) T.row(r++) = motor_.row(m);
    }
    return T;
  };
  Eigen::MatrixXd stuck_T = stiction ? stuck_rows() : Eigen::MatrixXd();  // rows T_m of the stuck motors
  auto accel = [&](const Vec& q, const Vec& qd, Vec& qdd, Hold* hold) {
    Mat M;
    Robot::mass_matrix(q, phi_true_, M);
    M += rotor_;
    Vec h;
    Robot::inverse_dynamics(q, qd, Vec::Zero().eval(), phi_true_, h);
    Vec rhs = tau_cmd - h;
    const Vec v_motor = motor_ * qd;
    for (int j = 0; j < N; ++j) {
      const JointEffects& e = scenario.effects[j];
      JointFriction f = scenario.friction[j];
      if (e.viscous_drift != 0) f.beta *= 1.0 + e.viscous_drift * (1.0 - std::exp(-warm / e.drift_time_constant));
      const bool held = stiction && stuck_[j];
      double friction = 0;  // motor j's, at its velocity (held: its share of the holding torque)
      if (!held) {
        double v = v_motor[j];
        if (direction[j] != 0 && v * direction[j] <= 0) v = direction[j] * kStartVelocity;
        friction = friction_torque(f, v, h[j]);
      }
      for (int k = 0; k < N; ++k) {
        if (k != j && motor_(j, k) != 0.0) rhs[k] -= motor_(j, k) * friction;
      }
      double tf = motor_(j, j) * friction + e.offset;
      if (e.load_friction != 0 && !held) {
        const double sg = direction[j] != 0 ? direction[j] : (qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0));
        tf += e.load_friction * std::fabs(h[j]) * sg;
      }
      if (e.cogging_amplitude != 0) tf += e.cogging_amplitude * std::sin(e.cogging_cycles * q[j] + e.cogging_phase);
      rhs[j] -= tf;
      if (hold != nullptr) {
        hold->hi[j] = friction_torque(f, kStartVelocity, h[j]) + e.load_friction * std::fabs(h[j]);
        hold->lo[j] = friction_torque(f, -kStartVelocity, h[j]) - e.load_friction * std::fabs(h[j]);
      }
    }
    for (const CoupledFriction& c : scenario.couplings) {
      const double v = qd[c.joint_i] + c.sign * qd[c.joint_j];
      const double f = c.Fc * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0)) + c.beta * v;
      rhs[c.joint_i] -= f;
      rhs[c.joint_j] -= c.sign * f;
    }
    const Eigen::LDLT<Mat> ldlt(M);
    qdd = ldlt.solve(rhs);
    if (stuck_T.rows() == 0) return;
    const Eigen::MatrixXd& T = stuck_T;
    const Eigen::MatrixXd MinvTt = ldlt.solve(T.transpose());  // M^-1 T_S^T
    const Eigen::VectorXd f = (T * MinvTt).ldlt().solve(T * qdd);
    qdd -= MinvTt * f;
    if (hold != nullptr) {
      for (int m = 0, r = 0; m < N; ++m) {
        if (stuck_[m]) hold->force[m] = f[r++];
      }
    }
  };
  // Explicit RK4 is stable for a damping rate lambda while h lambda < 2.78. The viscous friction of
  // a light link (no rotor inertia, or a light plant under test) can exceed that at the nominal
  // substep: substeps grow with lambda_max(M^-1 B), B = diag(beta), at the step's start.
  int substeps = scenario.substeps;
  {
    Mat M;
    Robot::mass_matrix(q_, phi_true_, M);
    M += rotor_;
    const Eigen::LLT<Mat> llt(M);
    if (llt.info() == Eigen::Success) {
      Vec beta_m;
      for (int j = 0; j < N; ++j) {
        const JointEffects& e = scenario.effects[j];
        double beta = scenario.friction[j].beta;
        if (e.viscous_drift != 0) beta *= 1.0 + e.viscous_drift;
        beta_m[j] = std::max(beta, 0.0);
      }
      const Mat B = motor_.transpose() * beta_m.asDiagonal() * motor_;  // T^T diag(beta) T
      // lambda_max(M^-1 B) = lambda_max(L^-1 B L^-T), bounded by its largest row sum.
      const Mat A = llt.matrixL().solve(llt.matrixL().solve(B).transpose());
      const double lambda = A.cwiseAbs().rowwise().sum().maxCoeff();
      substeps = std::max(substeps, static_cast<int>(std::ceil(dt * lambda / 2.0)));
    }
  }
  const double hstep = dt / substeps;
  for (int k = 0; k < substeps; ++k) {
    Vec a1, a2, a3, a4;
    if (stiction) {
      // Release the stuck motors whose holding torque their static friction cannot give.
      const Vec v = motor_ * qd_;
      for (int m = 0; m < N; ++m) direction[m] = stuck_[m] ? 0.0 : (v[m] > 0 ? 1.0 : (v[m] < 0 ? -1.0 : 0.0));
      Hold hold;
      for (;;) {
        accel(q_, qd_, a1, &hold);
        int worst = -1;
        double excess = 0;
        for (int m = 0; m < N; ++m) {
          if (!stuck_[m]) continue;
          const double over = std::max(hold.force[m] - hold.hi[m], hold.lo[m] - hold.force[m]);
          if (over > excess) excess = over, worst = m;
        }
        if (worst < 0) break;
        stuck_[worst] = false;
        direction[worst] = hold.force[worst] > hold.hi[worst] ? 1.0 : -1.0;
        stuck_T = stuck_rows();
      }
    } else {
      accel(q_, qd_, a1, nullptr);
    }
    if (k == 0) {
      for (int j = 0; j < N; ++j) qdd0[j] = a1[j];
    }
    accel(q_ + 0.5 * hstep * qd_, qd_ + 0.5 * hstep * a1, a2, nullptr);
    accel(q_ + 0.5 * hstep * (qd_ + 0.5 * hstep * a1), qd_ + 0.5 * hstep * a2, a3, nullptr);
    accel(q_ + hstep * (qd_ + 0.5 * hstep * a2), qd_ + hstep * a3, a4, nullptr);
    q_ += hstep * qd_ + hstep * hstep / 6.0 * (a1 + a2 + a3);
    qd_ += hstep / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
    if (!stiction) continue;
    // Catch the motors whose velocity crossed or reached zero (a released one: that did not move
    // the way it started), then hold every stuck one exactly at rest.
    const Vec v_after = motor_ * qd_;
    for (int m = 0; m < N; ++m) {
      if (stuck_[m]) continue;
      const JointFriction& f = scenario.friction[m];
      const bool sticks = friction_torque(f, kStartVelocity, 0.0) > friction_torque(f, -kStartVelocity, 0.0) ||
                          scenario.effects[m].load_friction > 0;  // a frictionless motor never sticks
      if (sticks && direction[m] * v_after[m] <= 0) stuck_[m] = true;
    }
    stuck_T = stuck_rows();
    const Eigen::MatrixXd& T = stuck_T;
    if (T.rows() == 0) continue;
    Mat M;
    Robot::mass_matrix(q_, phi_true_, M);
    M += rotor_;
    const Eigen::LDLT<Mat> ldlt(M);
    const Eigen::MatrixXd MinvTt = ldlt.solve(T.transpose());
    qd_ -= MinvTt * (T * MinvTt).ldlt().solve(T * qd_);
  }
}

/// True base parameters (nominal standard parameters mapped to the base set, rotor inertia of
/// joints whose Ia is not separable added to the base parameter that absorbs it) followed by the
/// scenario's term values, in the order of IdentificationModel<Robot, Terms>.
template <class Robot>
template <unsigned Terms>
std::vector<TrueParameter> DrivePlantOf<Robot>::Truth<Terms>::run(const Scenario& s, const GeneratedRobotData& data) {
  using Model = IdentificationModel<Robot, Terms>;
  StdVec phi;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = data.nominal_standard[i];
  Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
  Robot::standard_to_base(phi, phi_b);
  for (int j = 0; j < N; ++j) {
    const bool own_column = Model::has_column(term::rotor_inertia, j);
    if (!Robot::rotor_inertia_separate(j) && Robot::rotor_inertia_absorbed_into(j) < 0) {
      // The description declares no rotor inertia: the model has no place for it.
      if (s.effects[j].rotor_inertia != 0)
        throw InputError("joint " + std::to_string(j + 1) +
                         " has rotor inertia, and the robot file declares none (\"rotor_inertia\": false)");
    } else if (!Robot::rotor_inertia_separate(j)) {
      phi_b[Robot::rotor_inertia_absorbed_into(j)] +=
          data.rotor_inertia_absorbed_coefficient[j] * s.effects[j].rotor_inertia;
    } else if (!own_column && s.effects[j].rotor_inertia != 0) {
      throw InputError("joint " + std::to_string(j + 1) + " has rotor inertia the model does not declare");
    }
  }
  std::vector<TrueParameter> out;
  for (int i = 0; i < Model::kNumParams; ++i) {
    const ParamInfo info = Model::info(i);
    TrueParameter p;
    if (info.kind == ParamKind::base) {
      p.name = Robot::base_param_name(info.base_index);
      p.value = phi_b[info.base_index];
    } else {
      const int j = info.joint - 1;
      p.name = std::string(term_name(info.term)) + std::to_string(info.joint);
      switch (info.term) {
        case term::coulomb:
          p.value = s.friction[j].Fc;
          break;
        case term::viscous:
          p.value = s.friction[j].beta;
          break;
        case term::power:
          p.value = s.friction[j].fp;
          break;
        case term::rotor_inertia:
          p.value = s.effects[j].rotor_inertia;
          break;
        case term::offset:
          p.value = s.effects[j].offset;
          break;
        default:
          p.value = 0;
      }
    }
    out.push_back(p);
  }
  return out;
}

/// Registers DrivePlantOf<Robot> under Robot::kName with the generated model's namespace data
/// (kNominalStandard, kRotorInertiaAbsorbedCoefficient, kJointOrigins); returns true (for a static
/// initialiser).
template <class Robot, class Origin>
bool register_drive_plant_of(const double (&nominal_standard)[Robot::kNumStandard],
                             const double (&rotor_inertia_absorbed_coefficient)[Robot::kNumJoints],
                             const Origin (&joint_origins)[Robot::kNumJoints]) {
  static const GeneratedRobotData data = [&] {
    GeneratedRobotData d{nominal_standard, rotor_inertia_absorbed_coefficient, {}};
    for (int i = 0; i < Robot::kNumJoints; ++i) {
      for (int k = 0; k < 9; ++k) d.origins[static_cast<size_t>(i)].R[static_cast<size_t>(k)] = joint_origins[i].R[k];
      for (int k = 0; k < 3; ++k) d.origins[static_cast<size_t>(i)].p[static_cast<size_t>(k)] = joint_origins[i].p[k];
      d.origins[static_cast<size_t>(i)].prismatic = Robot::joint_prismatic(i);
    }
    return d;
  }();
  return register_drive_plant(Robot::kName, [] { return std::unique_ptr<DrivePlant>(new DrivePlantOf<Robot>(data)); });
}

}  // namespace dyncal::host
