#include "dyncal_host/drive/simulated_drive.hpp"

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

namespace mm = modbus_map;

ParameterTable nominal_table(const std::string& robot, const JointArray& Fc, const JointArray& beta) {
  return make_drive_plant(robot)->nominal_table(Fc, beta);
}

SimulatedDrive::SimulatedDrive(const RobotDescription& robot, const Scenario& scenario, std::string table_path)
    : control_rate_hz_(scenario.control_rate_hz) {
  if (scenario.robot != robot.name || scenario.num_joints != robot.num_joints)
    throw InputError("the scenario is for robot '" + scenario.robot + "', the drive runs '" + robot.name + "'");
  store_ = std::make_unique<FileParameterStore>(std::move(table_path));
  plant_ = make_drive_plant(robot);
  plant_->configure(robot, scenario, *store_);
  sample_rate_hz = scenario.sample_rate_hz;
  trajectory.f_f = 0.1;
  trajectory.harmonics = 5;
  // The flash: the stored table if it is valid for this drive, else the factory table.
  if (!store_->exists()) {
    startup_note_ = "factory table (nominal base parameters, no friction)";
  } else if (const TableStatus st = plant_->load(); st == TableStatus::ok) {
    startup_note_ = "table from " + store_->path();
    return;
  } else {
    startup_note_ = "factory table: " + store_->path() + " rejected (" + to_string(st) + ")";
  }
  plant_->activate(plant_->nominal_table({}, {}));
}

SimulatedDrive::~SimulatedDrive() = default;

std::uint32_t SimulatedDrive::robot_id() const {
  return plant_->robot_id();
}
int SimulatedDrive::num_joints() const {
  return plant_->num_joints();
}

drive::RunSettings SimulatedDrive::run_settings() const {
  drive::RunSettings run;
  run.sample_rate_hz = sample_rate_hz;
  run.periods = periods;
  run.trajectory = trajectory;
  return run;
}

void SimulatedDrive::start() {
  plant_->start(mm::Command::start, run_settings(), monitor_);
}

void SimulatedDrive::start_payload() {
  plant_->start(mm::Command::identify_payload, run_settings(), monitor_);
}

bool SimulatedDrive::start(mm::Command c, const drive::RunSettings& run, const MonitorSettings& monitor) {
  if (!plant_->start(c, run, monitor)) return false;
  sample_rate_hz = run.sample_rate_hz;
  periods = run.periods;
  trajectory = run.trajectory;
  monitor_ = monitor;
  return true;
}

mm::PayloadState SimulatedDrive::payload_state() const {
  return plant_->payload_state();
}
const drive::PayloadVerdict& SimulatedDrive::payload() const {
  return plant_->payload();
}
void SimulatedDrive::stop() {
  plant_->stop();
}
void SimulatedDrive::trip(mm::DriveFault fault, double value) {
  plant_->trip(fault, 0, value);
}
void SimulatedDrive::reset() {
  plant_->reset();
}
mm::DriveState SimulatedDrive::state() const {
  return plant_->state();
}
mm::DriveFault SimulatedDrive::fault() const {
  return plant_->fault();
}
int SimulatedDrive::fault_joint() const {
  return plant_->fault_joint();
}
double SimulatedDrive::fault_value() const {
  return plant_->fault_value();
}
double SimulatedDrive::time() const {
  return plant_->time();
}

void SimulatedDrive::step() {
  const std::uint32_t before = plant_->produced();
  plant_->period();
  if (plant_log && plant_->produced() != before) plant_log->push_back(plant_->last_sample());
}

long SimulatedDrive::run_samples(double run_periods, double period_s, double sample_rate) const {
  return plant_->run_samples(run_periods, period_s, sample_rate);
}

const SimulatedRing& SimulatedDrive::ring() const {
  return plant_->ring();
}
std::uint32_t SimulatedDrive::acked() const {
  return plant_->acked();
}
void SimulatedDrive::ack(std::uint32_t seq_end) {
  plant_->ack(seq_end);
}
bool SimulatedDrive::ring_full() const {
  return static_cast<long>(plant_->ring().size()) >= plant_->ring_capacity_samples();
}
bool SimulatedDrive::set_ring_capacity(long samples) {
  return plant_->set_ring_limit(samples);
}
long SimulatedDrive::ring_capacity() const {
  return plant_->ring_capacity_samples();
}
std::uint32_t SimulatedDrive::produced() const {
  return plant_->produced();
}
std::uint32_t SimulatedDrive::overruns() const {
  return plant_->overruns();
}

TableStatus SimulatedDrive::commit(const std::uint8_t* bytes, int size) {
  return plant_->commit(bytes, size);
}
const std::string& SimulatedDrive::store_error() const {
  return store_->error();
}
std::vector<std::uint8_t> SimulatedDrive::active_table_bytes() const {
  return plant_->active_table_bytes();
}
std::uint32_t SimulatedDrive::table_generation() const {
  return plant_->table_generation();
}
const ParameterTable& SimulatedDrive::active_table() const {
  return plant_->active_table();
}
void SimulatedDrive::set_flash_chunk_delay(int ms) {
  store_->chunk_delay_ms = ms;
}

JointArray SimulatedDrive::model_error_rms() const {
  return plant_->model_error_rms();
}

void SimulatedDrive::set_plant_parameters(const std::vector<double>& phi_standard) {
  plant_->set_plant_parameters(phi_standard);
}

void SimulatedDrive::fix_gains(const JointArray& kp, const JointArray& kd) {
  plant_->fix_gains(kp, kd);
}
JointArray SimulatedDrive::kp() const {
  return plant_->kp();
}
JointArray SimulatedDrive::kd() const {
  return plant_->kd();
}

std::string SimulatedDrive::set_monitor(const MonitorSettings& m) {
  if (state() == mm::DriveState::playing) return "the collision monitor is set while no trajectory plays";
  if (std::string why = monitor_settings_error(m, control_period()); !why.empty()) return why;
  monitor_ = m;
  return {};
}

mm::MonitorState SimulatedDrive::monitor_state() const {
  return plant_->monitor_state();
}
JointArray SimulatedDrive::monitor_residual() const {
  return plant_->monitor_residual();
}
JointArray SimulatedDrive::monitor_widening() const {
  return plant_->monitor_widening();
}

JointArray SimulatedDrive::contact_torque(const JointArray& q, int link, const std::array<double, 3>& point,
                                          const std::array<double, 3>& force) const {
  return plant_->contact_torque(q, link, point, force);
}

void SimulatedDrive::publish_inputs(std::uint16_t* input) const {
  plant_->publish_inputs(input);
}
void SimulatedDrive::publish_window(std::uint16_t* window) const {
  plant_->publish_window(window);
}

}  // namespace dyncal::host
