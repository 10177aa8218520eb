#pragma once
// DrivePlantOf<Robot>: the simulated drive of one generated robot model (drive_plant.hpp): lib/'s
// drive application in double over the scenario's arm (scenario_arm.hpp), running every term set
// the host tools build. Included by the robots' registration units
// (host_sim/robots/robot_drive.cpp.in) only: each robot compiles its own fixed-size copy.

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <memory>
#include <utility>

#include "dyncal/drive/drive_application.hpp"
#include "dyncal/drive/term_sets.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/drive/contact_force.hpp"
#include "dyncal_host/drive/drive_plant.hpp"
#include "dyncal_host/drive/scenario_arm.hpp"

namespace dyncal::host {

/// The generated model's namespace-level data a plant needs besides the Robot type.
struct GeneratedRobotData {
  const double* nominal_standard;                    ///< kNominalStandard [kNumStandard]
  const double* rotor_inertia_absorbed_coefficient;  ///< kRotorInertiaAbsorbedCoefficient [kNumJoints]
  JointOrigins origins;                              ///< kJointOrigins (contact forces)
};

/// lib/'s TermSets of the term sets the host tools build (model_terms.hpp), Eq. 7 first (the
/// factory table's).
template <class Robot, class Indices>
struct BuiltTermSetsOf;
template <class Robot, int... I>
struct BuiltTermSetsOf<Robot, std::integer_sequence<int, I...>> {
  using type = drive::TermSets<Robot, built_term_set(I)...>;
};
template <class Robot>
using BuiltTermSets = typename BuiltTermSetsOf<Robot, std::make_integer_sequence<int, kBuiltTermSets>>::type;

template <class Robot>
class DrivePlantOf final : public DrivePlant {
 public:
  static constexpr int N = Robot::kNumJoints;
  static_assert(N >= 1 && N <= kMaxDriveJoints, "the simulated drive runs 1 to kMaxDriveJoints joints");
  using Vec = Eigen::Matrix<double, N, 1>;
  using StdVec = Eigen::Matrix<double, Robot::kNumStandard, 1>;
  using Models = BuiltTermSets<Robot>;
  using Application = drive::DriveApplication<Models, double, kSimulatedRingCapacity>;

  explicit DrivePlantOf(const GeneratedRobotData& data) : data_(data) {}

  std::uint32_t robot_id() const override { return Robot::kRobotId; }
  int num_joints() const override { return N; }
  int num_standard() const override { return Robot::kNumStandard; }

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

  JointArray contact_torque(const JointArray& q, int link, const std::array<double, 3>& point,
                            const std::array<double, 3>& force) const override {
    return contact_joint_torque(data_.origins, N, q.data(), link, point, Eigen::Vector3d(force[0], force[1], force[2]));
  }

  void configure(const RobotDescription& robot, const Scenario& scenario, port::ParameterStore& store) override {
    arm_ = std::make_unique<ScenarioArm<Robot>>(data_.nominal_standard, data_.origins, robot, scenario);
    typename Application::Settings s;
    s.control_rate_hz = scenario.control_rate_hz;
    s.bandwidth_hz = scenario.bandwidth_hz;
    s.damping = scenario.damping;
    s.nominal_standard = data_.nominal_standard;
    s.loop_standard = arm_->standard();  // the loop tuned on the arm it drives, load included
    s.motor_map = motor_map_;
    s.stop_and_go = scenario.stop_and_go;
    for (int j = 0; j < N; ++j) {
      s.rotor_inertia[j] = scenario.effects[j].rotor_inertia;  // motor j's
      for (int k = 0; k < N; ++k) motor_map_[N * j + k] = scenario.motor_map[j][k];
      s.ratings.tau_max[j] = robot.tau_max.size() == N ? static_cast<float>(robot.tau_max[j]) : 0.0f;
      s.ratings.qd_max[j] = static_cast<float>(robot.qd_max[j]);
      s.ratings.qdd_max[j] = static_cast<float>(robot.qdd_max[j]);
      s.ratings.q_min[j] = static_cast<float>(robot.q_min[j]);
      s.ratings.q_max[j] = static_cast<float>(robot.q_max[j]);
      // The ring's position count: the encoder's quantum on the joint side (2^20 counts per motor
      // turn when the scenario does not quantise).
      const double counts = scenario.encoder_counts > 0 ? scenario.encoder_counts : 1048576.0;
      s.q_resolution[j] = static_cast<float>(2.0 * M_PI / (counts * std::fabs(robot.gear_ratios[j])));
      s.tau_noise_std[j] = scenario.tau_noise_std[j];
    }
    app_ = std::make_unique<Application>(store, *arm_, s);
  }

  void set_plant_parameters(const std::vector<double>& phi_standard) override { arm_->set_standard(phi_standard); }

  TableStatus load() override { return app_->load(); }
  TableStatus activate(const ParameterTable& t) override { return app_->activate(t); }
  const ParameterTable& active_table() const override { return app_->active_table(); }
  std::vector<std::uint8_t> active_table_bytes() const override {
    int size = 0;
    const std::uint8_t* bytes = app_->active_table_bytes(&size);
    return std::vector<std::uint8_t>(bytes, bytes + size);
  }
  std::uint32_t table_generation() const override { return app_->table_generation(); }
  TableStatus commit(const std::uint8_t* bytes, int size) override { return app_->commit(bytes, size); }
  bool start(modbus_map::Command c, const drive::RunSettings& run, const MonitorSettings& monitor) override {
    if (!app_->start(c, run, monitor)) return false;
    const long every = run.sample_rate_hz > 0 ? std::lround(app_->control_rate_hz() / run.sample_rate_hz) : 1;
    arm_->read_measurements(every, app_->monitor().state() == modbus_map::MonitorState::watching);
    return true;
  }
  void stop() override { app_->stop(); }
  void reset() override { app_->reset(); }
  void trip(modbus_map::DriveFault fault, int joint, double value) override { app_->trip(fault, joint, value); }
  bool wants_period() const override { return app_->wants_period(); }
  void period() override { app_->period(); }
  const PlantSample& last_sample() const override { return arm_->last(); }
  modbus_map::DriveState state() const override { return app_->state(); }
  modbus_map::DriveFault fault() const override { return app_->fault(); }
  int fault_joint() const override { return app_->fault_joint(); }
  double fault_value() const override { return app_->fault_value(); }
  double time() const override { return app_->time(); }
  std::uint32_t acked() const override { return app_->acked(); }
  std::uint32_t produced() const override { return app_->produced(); }
  std::uint32_t overruns() const override { return app_->overruns(); }
  void ack(std::uint32_t seq_end) override { app_->ack(seq_end); }
  const SimulatedRing& ring() const override { return app_->ring(); }
  long ring_capacity_samples() const override { return app_->ring_capacity_samples(); }
  bool set_ring_limit(long samples) override { return app_->set_ring_limit(samples); }
  bool set_ring_format(modbus_map::RingFormat f) override { return app_->set_ring_format(f); }
  modbus_map::RingFormat ring_format() const override { return app_->ring_format(); }
  long run_samples(double periods, double period_s, double fs) const override {
    return app_->run_samples(periods, period_s, fs);
  }
  void publish_inputs(std::uint16_t* input) const override { app_->publish_inputs(input); }
  void publish_window(std::uint16_t* window) const override { app_->publish_window(window); }
  bool fix_gains(const JointArray& kp, const JointArray& kd) override {
    Vec p, d;
    for (int j = 0; j < N; ++j) p[j] = kp[j], d[j] = kd[j];
    return app_->fix_gains(p, d);
  }
  JointArray kp() const override { return to_array(app_->kp()); }
  JointArray kd() const override { return to_array(app_->kd()); }
  JointArray model_error_rms() const override {
    JointArray e{};
    for (int j = 0; j < N; ++j) e[j] = app_->model_error_rms(j);
    return e;
  }
  modbus_map::PayloadState payload_state() const override { return app_->payload_state(); }
  const drive::PayloadVerdict& payload() const override { return app_->payload(); }
  modbus_map::MonitorState monitor_state() const override { return app_->monitor().state(); }
  JointArray monitor_residual() const override { return to_array(app_->monitor().residual()); }
  JointArray monitor_widening() const override { return to_array(app_->monitor().widening()); }

 private:
  template <unsigned Terms>
  struct Truth {
    static std::vector<TrueParameter> run(const Scenario& s, const GeneratedRobotData& data);
  };

  template <class V>
  static JointArray to_array(const V& v) {
    JointArray a{};
    for (int j = 0; j < N; ++j) a[j] = static_cast<double>(v[j]);
    return a;
  }

  GeneratedRobotData data_;
  std::unique_ptr<ScenarioArm<Robot>> arm_;  ///< the arm (configure())
  std::unique_ptr<Application> app_;         ///< lib/'s drive application over it (1.4 MB of ring)
  double motor_map_[N * N] = {};             ///< the scenario's transmission T, row-major (the app's settings)
};

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
