#include "dyncal_host/drive/simulated_drive.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <Eigen/Cholesky>
#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <thread>

#include "dyncal/effect_terms.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"

namespace dyncal::host {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Vec = Eigen::Matrix<double, kDriveJoints, 1>;
using Mat = Eigen::Matrix<double, kDriveJoints, kDriveJoints>;
using StdVec = Eigen::Matrix<double, Robot::kNumStandard, 1>;

/// Feed-forward tau = K(q, qd, qdd) phi and table check of one supported model.
struct ModelOps {
  unsigned terms;
  TableStatus (*check)(const ParameterTable&);
  void (*feedforward)(const ParameterTable&, const Vec&, const Vec&, const Vec&, Vec&);
};

template <unsigned Terms>
ModelOps ops_for() {
  using Model = IdentificationModel<Robot, Terms>;
  return ModelOps{Terms, &check_table<Model>,
                  [](const ParameterTable& t, const Vec& q, const Vec& qd, const Vec& qdd, Vec& tau) {
                    typename Model::template Regressor<double> K;
                    Model::regressor(q, qd, qdd, Vec::Zero().eval(), K);
                    typename Model::template ParamVector<double> phi;
                    for (int i = 0; i < Model::kNumParams; ++i) phi[i] = t.values[i];
                    tau = K * phi;
                    // Effect terms of the table (dyncal diagnose); load friction needs the rigid-body torque.
                    const Vec tau_rb = K.template leftCols<Robot::kNumBase>() * phi.template head<Robot::kNumBase>();
                    add_effect_torques(t.effects, t.effect_count, q, qd, qdd, tau_rb, tau);
                  }};
}

template <unsigned Terms>
struct OpsFor {
  static ModelOps run() { return ops_for<Terms>(); }
};

/// The models this drive runs: the term sets the host tools build (model_terms.hpp).
std::optional<ModelOps> find_ops(std::uint32_t model_id) {
  if (!is_built_term_set(model_id)) return std::nullopt;
  return with_term_set<OpsFor>(model_id);
}

TableStatus check_any(const ParameterTable& t) {
  if (t.robot_id != Robot::kRobotId) return TableStatus::wrong_robot;
  const std::optional<ModelOps> ops = find_ops(t.model_id);
  return ops ? ops->check(t) : TableStatus::wrong_model;
}

/// A drive trip: which limit, the 0-based joint, the measured value that broke it.
struct Trip {
  modbus_map::DriveFault fault = modbus_map::DriveFault::none;
  int joint = 0;
  double value = 0;
};

/// The first limit the measurements break: a non-finite q or qd on any joint first (the plant
/// diverged), then positions outside [q_min, q_max], then speeds above qd_max; joint 1 first.
Trip check_limits(const Vec& q, const Vec& qd, const Vec& q_min, const Vec& q_max, const Vec& qd_max) {
  for (int j = 0; j < kDriveJoints; ++j) {
    if (!std::isfinite(q[j]) || !std::isfinite(qd[j]))
      return {modbus_map::DriveFault::non_finite_state, j, std::numeric_limits<double>::quiet_NaN()};
  }
  for (int j = 0; j < kDriveJoints; ++j) {
    if (q[j] < q_min[j] || q[j] > q_max[j]) return {modbus_map::DriveFault::position_limit, j, q[j]};
  }
  for (int j = 0; j < kDriveJoints; ++j) {
    if (std::fabs(qd[j]) > qd_max[j]) return {modbus_map::DriveFault::velocity_limit, j, qd[j]};
  }
  return {};
}

std::vector<std::uint8_t> encode(const ParameterTable& t) {
  std::vector<std::uint8_t> bytes(kTableMaxBytes);
  int size = 0;
  if (encode_table(t, bytes.data(), static_cast<int>(bytes.size()), &size) != TableStatus::ok) {
    throw std::logic_error("cannot encode a parameter table");
  }
  bytes.resize(static_cast<size_t>(size));
  return bytes;
}

}  // namespace

ParameterTable nominal_table(const std::array<double, kDriveJoints>& Fc, const std::array<double, kDriveJoints>& beta) {
  using Model = IdentificationModel<Robot, kFrictionEq7>;
  StdVec phi_std;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi_std[i] = dyncal::generated::er20::kNominalStandard[i];
  Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
  dyncal::generated::er20::standard_to_base(phi_std, phi_b);
  typename Model::ParamVector<double> phi = Model::ParamVector<double>::Zero();
  phi.head<Robot::kNumBase>() = phi_b;
  for (int i = Robot::kNumBase; i < Model::kNumParams; ++i) {
    const ParamInfo info = Model::info(i);
    const size_t j = static_cast<size_t>(info.joint - 1);
    phi[i] = info.term == term::coulomb ? Fc[j] : beta[j];
  }
  ParameterTable t;
  make_table<Model>(phi, t);
  return t;
}

struct SimulatedDrive::Impl {
  StdVec phi_true;
  Vec ia = Vec::Zero();
  Vec q = Vec::Zero(), qd = Vec::Zero();  // plant state
  Vec q_meas_prev = Vec::Zero();
  Vec kp = Vec::Zero(), kd = Vec::Zero();
  Vec quantum = Vec::Zero();  // encoder resolution on the joint side [rad]
  Vec q_min, q_max, qd_max;   // the robot's limits, the drive's trips
  ModelOps ops{};             // feed-forward and check of the active table's model
  std::normal_distribution<double> normal{0.0, 1.0};
};

SimulatedDrive::SimulatedDrive(const RobotDescription& robot, const Scenario& scenario, std::string table_path)
    : impl_(std::make_unique<Impl>()), scenario_(scenario), table_path_(std::move(table_path)), rng_(scenario.seed) {
  if (robot.name != Robot::kName) throw InputError("the simulated drive runs the er20 model, not '" + robot.name + "'");
  sample_rate_hz = scenario.sample_rate_hz;
  for (int i = 0; i < Robot::kNumStandard; ++i) impl_->phi_true[i] = dyncal::generated::er20::kNominalStandard[i];
  impl_->q_min = robot.q_min;
  impl_->q_max = robot.q_max;
  impl_->qd_max = robot.qd_max;
  for (int j = 0; j < kDriveJoints; ++j) {
    impl_->ia[j] = scenario.effects[j].rotor_inertia;
    impl_->quantum[j] =
        scenario.encoder_counts > 0 ? 2.0 * M_PI / (scenario.encoder_counts * std::fabs(robot.gear_ratios[j])) : 0.0;
  }
  // The flash: the stored table if it is valid for this drive, else the factory table.
  active_ = nominal_table();
  startup_note_ = "factory table (nominal base parameters, no friction)";
  std::ifstream in(table_path_, std::ios::binary);
  if (in) {
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ParameterTable t;
    TableStatus st = decode_table(bytes.data(), static_cast<int>(bytes.size()), t);
    if (st == TableStatus::ok) st = check_any(t);
    if (st == TableStatus::ok) {
      active_ = t;
      startup_note_ = "table from " + table_path_;
    } else {
      startup_note_ = std::string("factory table: ") + table_path_ + " rejected (" + to_string(st) + ")";
    }
  }
  active_bytes_ = encode(active_);
  impl_->ops = *find_ops(active_.model_id);  // the active table passed check_any
  trajectory.f_f = 0.1;
  trajectory.harmonics = 5;
}

SimulatedDrive::~SimulatedDrive() = default;

std::uint32_t SimulatedDrive::robot_id() const {
  return Robot::kRobotId;
}

double SimulatedDrive::remaining() const {
  return state_ == modbus_map::DriveState::playing ? static_cast<double>(total_steps_ - steps_) * control_period()
                                                   : 0.0;
}

void SimulatedDrive::start() {
  const double steps_per_sample = scenario_.control_rate_hz / sample_rate_hz;
  steps_per_sample_ = std::max(1L, std::lround(steps_per_sample));
  total_steps_ = std::lround(periods * trajectory.period() * scenario_.control_rate_hz);
  Vec q_d, qd_d, qdd_d;
  trajectory.evaluate(0.0, q_d, qd_d, qdd_d);  // the simulation starts on the trajectory
  impl_->q = q_d;
  impl_->qd = qd_d;
  Vec q_meas = impl_->q;
  for (int j = 0; j < kDriveJoints; ++j) {
    if (impl_->quantum[j] > 0) q_meas[j] = impl_->quantum[j] * std::round(q_meas[j] / impl_->quantum[j]);
  }
  impl_->q_meas_prev = q_meas - qd_d * control_period();
  // PD gains from the arm's inertia at the start pose: natural frequency bandwidth_hz, damping zeta.
  if (!gains_fixed_) {
    Mat M;
    Robot::mass_matrix(impl_->q, impl_->phi_true, M);
    const double w = 2.0 * M_PI * scenario_.bandwidth_hz;
    for (int j = 0; j < kDriveJoints; ++j) {
      const double m = M(j, j) + impl_->ia[j];
      impl_->kp[j] = m * w * w;
      impl_->kd[j] = 2.0 * scenario_.damping * m * w;
    }
  }
  time_ = 0;
  steps_ = 0;
  ring_.clear();
  acked_ = produced_ = overruns_ = 0;
  error_sq_.fill(0.0);
  error_n_ = 0;
  fault_ = modbus_map::DriveFault::none;
  fault_joint_ = 0;
  fault_value_ = 0;
  state_ = modbus_map::DriveState::playing;
}

void SimulatedDrive::stop() {
  if (state_ == modbus_map::DriveState::playing) state_ = modbus_map::DriveState::finished;
}

void SimulatedDrive::step() {
  if (state_ != modbus_map::DriveState::playing) return;
  if (steps_ >= total_steps_) {
    state_ = modbus_map::DriveState::finished;
    return;
  }
  Impl& s = *impl_;
  const double dt = control_period();
  // Measurement: quantised encoder position, velocity by backward difference.
  Vec q_meas = s.q;
  for (int j = 0; j < kDriveJoints; ++j) {
    if (s.quantum[j] > 0) q_meas[j] = s.quantum[j] * std::round(q_meas[j] / s.quantum[j]);
  }
  const Vec qd_meas = (q_meas - s.q_meas_prev) / dt;
  s.q_meas_prev = q_meas;
  const Trip trip = check_limits(q_meas, qd_meas, s.q_min, s.q_max, s.qd_max);
  if (trip.fault != modbus_map::DriveFault::none) {
    state_ = modbus_map::DriveState::fault;
    fault_ = trip.fault;
    fault_joint_ = trip.joint + 1;
    fault_value_ = trip.value;
    return;
  }
  // Control law (survey Fig. 3): feed-forward from the active table plus PD on the tracking error.
  Vec q_d, qd_d, qdd_d, tau_ff;
  trajectory.evaluate(time_, q_d, qd_d, qdd_d);
  s.ops.feedforward(active_, q_d, qd_d, qdd_d, tau_ff);
  const Vec tau_cmd = tau_ff + s.kp.cwiseProduct(q_d - q_meas) + s.kd.cwiseProduct(qd_d - qd_meas);
  for (int j = 0; j < kDriveJoints; ++j) error_sq_[j] += (tau_cmd[j] - tau_ff[j]) * (tau_cmd[j] - tau_ff[j]);
  ++error_n_;
  // Record.
  const bool record = steps_ % steps_per_sample_ == 0;
  if (record) {
    port::DriveSample sample{};
    sample.seq = produced_++;
    PlantSample exact;
    exact.t = time_;
    for (int j = 0; j < kDriveJoints; ++j) {
      const double tau_measured = tau_cmd[j] + scenario_.tau_noise_std[j] * s.normal(rng_);
      sample.q[j] = static_cast<float>(q_meas[j]);
      sample.qd[j] = static_cast<float>(qd_meas[j]);
      sample.tau[j] = static_cast<float>(tau_measured);
      exact.q[j] = s.q[j];
      exact.qd[j] = s.qd[j];
      exact.tau_cmd[j] = tau_cmd[j];
      exact.tau_measured[j] = tau_measured;
    }
    if (plant_log) plant_log->push_back(exact);  // qdd filled in by the first RK4 stage below
    if (ring_full()) {
      ++overruns_;  // the host sees the gap in seq
    } else {
      ring_.push_back(sample);
    }
  }
  // Plant: (M(q) + diag(Ia)) qdd = tau - h(q, qd) - friction - effects, RK4 with zero-order hold.
  const double warm = clock_;
  auto accel = [&](const Vec& q, const Vec& qd, Vec& qdd) {
    Mat M;
    Robot::mass_matrix(q, s.phi_true, M);
    M.diagonal() += s.ia;
    Vec h;
    Robot::inverse_dynamics(q, qd, Vec::Zero().eval(), s.phi_true, h);
    Vec rhs = tau_cmd - h;
    for (int j = 0; j < kDriveJoints; ++j) {
      const JointEffects& e = scenario_.effects[j];
      JointFriction f = scenario_.friction[j];
      if (e.viscous_drift != 0) f.beta *= 1.0 + e.viscous_drift * (1.0 - std::exp(-warm / e.drift_time_constant));
      double tf = friction_torque(f, qd[j], h[j]) + e.offset;
      if (e.load_friction != 0) tf += e.load_friction * std::fabs(h[j]) * (qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0));
      if (e.cogging_amplitude != 0) tf += e.cogging_amplitude * std::sin(e.cogging_cycles * q[j] + e.cogging_phase);
      rhs[j] -= tf;
    }
    for (const CoupledFriction& c : scenario_.couplings) {
      const double v = qd[c.joint_i] + c.sign * qd[c.joint_j];
      const double f = c.Fc * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0)) + c.beta * v;
      rhs[c.joint_i] -= f;
      rhs[c.joint_j] -= c.sign * f;
    }
    qdd = M.ldlt().solve(rhs);
  };
  // Explicit RK4 is stable for a damping rate lambda while h lambda < 2.78. The viscous friction of
  // a light link (no rotor inertia, or a light plant under test) can exceed that at the nominal
  // substep: substeps grow with lambda_max(M^-1 B), B = diag(beta), at the step's start.
  int substeps = scenario_.substeps;
  {
    Mat M;
    Robot::mass_matrix(s.q, s.phi_true, M);
    M.diagonal() += s.ia;
    const Eigen::LLT<Mat> llt(M);
    if (llt.info() == Eigen::Success) {
      Mat B = Mat::Zero();
      for (int j = 0; j < kDriveJoints; ++j) {
        const JointEffects& e = scenario_.effects[j];
        double beta = scenario_.friction[j].beta;
        if (e.viscous_drift != 0) beta *= 1.0 + e.viscous_drift;
        B(j, j) = std::max(beta, 0.0);
      }
      // lambda_max(M^-1 B) = lambda_max(L^-1 B L^-T), bounded by its largest row sum.
      const Mat A = llt.matrixL().solve(llt.matrixL().solve(B).transpose());
      const double lambda = A.cwiseAbs().rowwise().sum().maxCoeff();
      substeps = std::max(substeps, static_cast<int>(std::ceil(dt * lambda / 2.0)));
    }
  }
  const double hstep = dt / substeps;
  for (int k = 0; k < substeps; ++k) {
    Vec a1, a2, a3, a4;
    accel(s.q, s.qd, a1);
    if (k == 0 && record && plant_log) {
      for (int j = 0; j < kDriveJoints; ++j) plant_log->back().qdd[j] = a1[j];
    }
    accel(s.q + 0.5 * hstep * s.qd, s.qd + 0.5 * hstep * a1, a2);
    accel(s.q + 0.5 * hstep * (s.qd + 0.5 * hstep * a1), s.qd + 0.5 * hstep * a2, a3);
    accel(s.q + hstep * (s.qd + 0.5 * hstep * a2), s.qd + hstep * a3, a4);
    s.q += hstep * s.qd + hstep * hstep / 6.0 * (a1 + a2 + a3);
    s.qd += hstep / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
  }
  ++steps_;
  time_ += dt;
  clock_ += dt;
}

void SimulatedDrive::ack(std::uint32_t seq_end) {
  if (seq_end < acked_ || seq_end > produced_) return;
  while (!ring_.empty() && ring_.front().seq < seq_end) ring_.pop_front();
  acked_ = seq_end;
}

TableStatus SimulatedDrive::commit(const std::uint8_t* bytes, int size) {
  ParameterTable t;
  TableStatus st = decode_table(bytes, size, t);
  if (st == TableStatus::ok) st = check_any(t);
  if (st != TableStatus::ok) return st;
  std::vector<std::uint8_t> encoded(bytes, bytes + size);
  write_file_atomically(table_path_, encoded, flash_chunk_delay_ms);
  active_ = t;
  active_bytes_ = std::move(encoded);
  ++table_generation_;
  impl_->ops = *find_ops(t.model_id);
  return TableStatus::ok;
}

std::array<double, kDriveJoints> SimulatedDrive::model_error_rms() const {
  std::array<double, kDriveJoints> r{};
  for (int j = 0; j < kDriveJoints; ++j)
    r[j] = error_n_ > 0 ? std::sqrt(error_sq_[j] / static_cast<double>(error_n_)) : 0.0;
  return r;
}

void write_file_atomically(const std::string& path, const std::vector<std::uint8_t>& bytes, int chunk_delay_ms) {
  const std::string tmp = path + ".tmp";
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create " + tmp);
  for (size_t off = 0; off < bytes.size(); off += 64) {
    const size_t n = std::min<size_t>(64, bytes.size() - off);
    if (::write(fd, bytes.data() + off, n) != static_cast<ssize_t>(n)) {
      ::close(fd);
      throw std::runtime_error("cannot write " + tmp);
    }
    if (chunk_delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(chunk_delay_ms));
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) throw std::runtime_error("cannot sync " + tmp);
  if (::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot replace " + path);
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

void SimulatedDrive::set_plant_parameters(const std::vector<double>& phi_standard) {
  if (static_cast<int>(phi_standard.size()) != Robot::kNumStandard) {
    throw InputError("plant parameters: expected " + std::to_string(Robot::kNumStandard) + " standard parameters");
  }
  for (int i = 0; i < Robot::kNumStandard; ++i) impl_->phi_true[i] = phi_standard[static_cast<size_t>(i)];
}

void SimulatedDrive::fix_gains(const std::array<double, kDriveJoints>& kp, const std::array<double, kDriveJoints>& kd) {
  for (int j = 0; j < kDriveJoints; ++j) {
    impl_->kp[j] = kp[j];
    impl_->kd[j] = kd[j];
  }
  gains_fixed_ = true;
}

std::array<double, kDriveJoints> SimulatedDrive::kp() const {
  std::array<double, kDriveJoints> g{};
  for (int j = 0; j < kDriveJoints; ++j) g[j] = impl_->kp[j];
  return g;
}

std::array<double, kDriveJoints> SimulatedDrive::kd() const {
  std::array<double, kDriveJoints> g{};
  for (int j = 0; j < kDriveJoints; ++j) g[j] = impl_->kd[j];
  return g;
}

}  // namespace dyncal::host
