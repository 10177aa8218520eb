#include "dyncal_host/drive/simulated_drive.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <thread>

#include "dyncal/table_check.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

std::vector<std::uint8_t> encoded_table(const ParameterTable& t) {
  std::vector<std::uint8_t> bytes(kTableMaxBytes);
  int size = 0;
  if (encode_table(t, bytes.data(), static_cast<int>(bytes.size()), &size) != TableStatus::ok) {
    throw std::logic_error("cannot encode a parameter table");
  }
  bytes.resize(static_cast<size_t>(size));
  return bytes;
}

ParameterTable nominal_table(const std::string& robot, const JointArray& Fc, const JointArray& beta) {
  return make_drive_plant(robot)->nominal_table(Fc, beta);
}

SimulatedDrive::SimulatedDrive(const RobotDescription& robot, const Scenario& scenario, std::string table_path)
    : plant_(make_drive_plant(robot)), scenario_(scenario), table_path_(std::move(table_path)), rng_(scenario.seed) {
  if (scenario.robot != robot.name || scenario.num_joints != robot.num_joints)
    throw InputError("the scenario is for robot '" + scenario.robot + "', the drive runs '" + robot.name + "'");
  sample_rate_hz = scenario.sample_rate_hz;
  plant_->configure(robot, scenario);
  for (int j = 0; j < robot.num_joints; ++j) {
    const double counts = scenario.encoder_counts > 0 ? scenario.encoder_counts : 1048576.0;
    q_resolution_[static_cast<std::size_t>(j)] = 2.0 * M_PI / (counts * std::fabs(robot.gear_ratios[j]));
    const bool rated = robot.tau_max.size() == robot.num_joints && robot.tau_max[j] > 0;
    tau_resolution_[static_cast<std::size_t>(j)] = rated ? 2.0 * robot.tau_max[j] / 32767.0 : 0.0;
  }
  // The flash: the stored table if it is valid for this drive, else the factory table.
  active_ = plant_->nominal_table({}, {});
  startup_note_ = "factory table (nominal base parameters, no friction)";
  // The flash is a regular file: a FIFO would block the drive before it is ready, a device such as
  // /dev/zero would never end. Refused before opening. Read up to one byte past the largest table.
  std::error_code ec;
  const auto kind = std::filesystem::status(table_path_, ec).type();
  if (kind != std::filesystem::file_type::not_found && kind != std::filesystem::file_type::regular)
    throw InputError(table_path_ + ": the drive's table file is not a regular file");
  std::ifstream in(table_path_, std::ios::binary);
  if (in) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(kTableMaxBytes) + 1);
    in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    bytes.resize(static_cast<std::size_t>(in.gcount()));
    ParameterTable t;
    TableStatus st = decode_table(bytes.data(), static_cast<int>(bytes.size()), t);
    if (st == TableStatus::ok) st = plant_->check(t);
    if (st == TableStatus::ok) {
      active_ = t;
      startup_note_ = "table from " + table_path_;
    } else {
      startup_note_ = std::string("factory table: ") + table_path_ + " rejected (" + to_string(st) + ")";
    }
  }
  active_bytes_ = encoded_table(active_);
  plant_->set_active(active_);  // the active table passed the plant's check
  trajectory.f_f = 0.1;
  trajectory.harmonics = 5;
}

SimulatedDrive::~SimulatedDrive() = default;

std::uint32_t SimulatedDrive::robot_id() const {
  return plant_->robot_id();
}

int SimulatedDrive::num_joints() const {
  return plant_->num_joints();
}

double SimulatedDrive::remaining() const {
  return state_ == modbus_map::DriveState::playing ? static_cast<double>(total_steps_ - steps_) * control_period()
                                                   : 0.0;
}

namespace {

/// A run's control periods per recorded sample and in all (the scenario's rests included).
struct RunSteps {
  long per_sample = 1, total = 0;
};
RunSteps run_steps(const Scenario& sc, double run_periods, double period_s, double sample_rate) {
  return {std::max(1L, std::lround(sc.control_rate_hz / sample_rate)),
          std::lround(sc.stop_and_go.run_time(run_periods * period_s) * sc.control_rate_hz)};
}

}  // namespace

long SimulatedDrive::run_samples(double run_periods, double period_s, double sample_rate) const {
  const RunSteps s = run_steps(scenario_, run_periods, period_s, sample_rate);
  return (s.total + s.per_sample - 1) / s.per_sample;  // a sample at every per_sample-th step from step 0
}

void SimulatedDrive::start() {
  const RunSteps s = run_steps(scenario_, periods, trajectory.period(), sample_rate_hz);
  steps_per_sample_ = s.per_sample;
  total_steps_ = s.total;
  plant_->begin(trajectory, scenario_, gains_fixed_, control_period());
  time_ = 0;
  steps_ = 0;
  ring_->clear();
  acked_ = produced_ = overruns_ = 0;
  error_sq_.fill(0.0);
  error_n_ = 0;
  fault_ = modbus_map::DriveFault::none;
  fault_joint_ = 0;
  fault_value_ = 0;
  state_ = modbus_map::DriveState::playing;
}

void SimulatedDrive::start_payload() {
  start();
  plant_->begin_payload();
  payload_state_ = modbus_map::PayloadState::running;
  payload_verdict_ = drive::PayloadVerdict::unknown();
}

bool SimulatedDrive::publish_payload() {
  payload_verdict_ = plant_->payload_verdict();  // lib/'s verdict rule (drive/payload_run.hpp)
  return payload_verdict_.mass_determined;
}

void SimulatedDrive::finish_payload() {
  if (payload_state_ != modbus_map::PayloadState::running) return;
  payload_state_ = modbus_map::PayloadState::not_written;
  if (!publish_payload()) return;
  const std::vector<std::uint8_t> bytes = encoded_table(plant_->loaded_table(active_, payload_verdict_));
  if (commit(bytes.data(), static_cast<int>(bytes.size())) == TableStatus::ok)
    payload_state_ = modbus_map::PayloadState::written;
}

void SimulatedDrive::trip(modbus_map::DriveFault fault, double value) {
  if (state_ != modbus_map::DriveState::playing) return;
  if (payload_state_ == modbus_map::PayloadState::running) payload_state_ = modbus_map::PayloadState::not_written;
  state_ = modbus_map::DriveState::fault;
  fault_ = fault;
  fault_joint_ = 0;
  fault_value_ = value;
}

void SimulatedDrive::reset() {
  if (state_ != modbus_map::DriveState::fault) return;
  state_ = modbus_map::DriveState::idle;
  fault_ = modbus_map::DriveFault::none;
  fault_joint_ = 0;
  fault_value_ = 0;
}

void SimulatedDrive::stop() {
  if (state_ != modbus_map::DriveState::playing) return;
  state_ = modbus_map::DriveState::finished;
  if (payload_state_ == modbus_map::PayloadState::running) {
    publish_payload();  // the estimate so far stays readable; the table is not touched
    payload_state_ = modbus_map::PayloadState::not_written;
  }
}

void SimulatedDrive::step() {
  if (state_ != modbus_map::DriveState::playing) return;
  if (steps_ >= total_steps_) {
    state_ = modbus_map::DriveState::finished;
    finish_payload();
    return;
  }
  const double dt = control_period();
  const PlantStep p = plant_->step(trajectory, scenario_, active_, time_, clock_, dt);
  if (p.trip.fault != modbus_map::DriveFault::none) {
    state_ = modbus_map::DriveState::fault;
    if (payload_state_ == modbus_map::PayloadState::running) payload_state_ = modbus_map::PayloadState::not_written;
    fault_ = p.trip.fault;
    fault_joint_ = p.trip.joint + 1;
    fault_value_ = p.trip.value;
    return;
  }
  const int n = plant_->num_joints();
  // The measured torque: the commanded one with the sensor's noise, drawn for every recorded
  // sample and, while the collision monitor watches, every control period.
  const bool record = steps_ % steps_per_sample_ == 0;
  const bool watching = plant_->monitor_state() == modbus_map::MonitorState::watching;
  JointArray tau_measured{};
  if (record || watching) {
    for (int j = 0; j < n; ++j) tau_measured[j] = p.tau_cmd[j] + scenario_.tau_noise_std[j] * normal_(rng_);
  }
  if (watching) {
    const Trip c = plant_->monitor(p, tau_measured);
    if (c.fault != modbus_map::DriveFault::none) {
      state_ = modbus_map::DriveState::fault;
      if (payload_state_ == modbus_map::PayloadState::running) payload_state_ = modbus_map::PayloadState::not_written;
      fault_ = c.fault;
      fault_joint_ = c.joint + 1;
      fault_value_ = c.value;
      return;
    }
  }
  for (int j = 0; j < n; ++j) error_sq_[j] += (p.tau_cmd[j] - p.tau_ff[j]) * (p.tau_cmd[j] - p.tau_ff[j]);
  ++error_n_;
  // Record.
  const bool payload = payload_state_ == modbus_map::PayloadState::running;
  if (record) {
    JointArray r{};
    port::DriveSample sample{};
    sample.seq = produced_++;
    PlantSample exact;
    exact.t = time_;
    for (int j = 0; j < n; ++j) {
      // The sensor's variance (drive.json tau_noise_std); its float32 register's resolution at least.
      const double resolution = 6e-8 * std::max(1.0, std::fabs(tau_measured[j]));
      r[j] = std::max(scenario_.tau_noise_std[j] * scenario_.tau_noise_std[j], resolution * resolution);
      sample.q[j] = static_cast<float>(p.q_meas[j]);
      sample.qd[j] = static_cast<float>(p.qd_meas[j]);
      sample.tau[j] = static_cast<float>(tau_measured[j]);
      exact.q[j] = p.q[j];
      exact.qd[j] = p.qd[j];
      exact.qdd[j] = p.qdd[j];
      exact.tau_cmd[j] = p.tau_cmd[j];
      exact.tau_measured[j] = tau_measured[j];
    }
    if (payload) plant_->update_payload(p, tau_measured, r);
    if (plant_log) plant_log->push_back(exact);
    if (ring_full()) {
      ++overruns_;  // the host sees the gap in seq
    } else {
      ring_->push_back(sample);
    }
  }
  ++steps_;
  time_ += dt;
  clock_ += dt;
}

modbus_map::RingFormat SimulatedDrive::ring_format_in_use() const {
  for (int j = 0; j < num_joints(); ++j) {
    if (!(tau_resolution_[static_cast<std::size_t>(j)] > 0)) return modbus_map::RingFormat::float32;
  }
  return ring_format;
}

void SimulatedDrive::ack(std::uint32_t seq_end) {
  if (seq_end < acked_ || seq_end > produced_) return;
  while (!ring_->empty() && ring_->front().seq < seq_end) ring_->pop_front();
  acked_ = seq_end;
}

TableStatus SimulatedDrive::commit(const std::uint8_t* bytes, int size) {
  ParameterTable t;
  TableStatus st = decode_table(bytes, size, t);
  if (st == TableStatus::ok) st = plant_->check(t);
  if (st != TableStatus::ok) return st;
  std::vector<std::uint8_t> encoded(bytes, bytes + size);
  write_file_atomically(table_path_, encoded, flash_chunk_delay_ms);
  active_ = t;
  active_bytes_ = std::move(encoded);
  ++table_generation_;
  plant_->set_active(t);
  return TableStatus::ok;
}

JointArray SimulatedDrive::model_error_rms() const {
  JointArray r{};
  for (int j = 0; j < plant_->num_joints(); ++j)
    r[j] = error_n_ > 0 ? std::sqrt(error_sq_[j] / static_cast<double>(error_n_)) : 0.0;
  return r;
}

void write_file_atomically(const std::string& path, const std::vector<std::uint8_t>& bytes, int chunk_delay_ms,
                           long cut_at) {
  const std::string tmp = path + ".tmp";
  const long size = static_cast<long>(bytes.size());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create " + tmp);
  for (size_t off = 0; off < bytes.size(); off += 64) {
    size_t n = std::min<size_t>(64, bytes.size() - off);
    const bool cut_here = cut_at >= 0 && cut_at <= static_cast<long>(off + n) && cut_at <= size;
    if (cut_here) n = static_cast<size_t>(cut_at) - off;  // the write in progress torn at cut_at
    if (::write(fd, bytes.data() + off, n) != static_cast<ssize_t>(n)) {
      ::close(fd);
      throw std::runtime_error("cannot write " + tmp);
    }
    if (cut_here) {
      ::close(fd);
      return;
    }
    if (chunk_delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(chunk_delay_ms));
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) throw std::runtime_error("cannot sync " + tmp);
  if (cut_at == size + 1) return;
  if (::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot replace " + path);
  if (cut_at == size + 2) return;
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

void SimulatedDrive::set_plant_parameters(const std::vector<double>& phi_standard) {
  plant_->set_plant_parameters(phi_standard);
}

void SimulatedDrive::fix_gains(const JointArray& kp, const JointArray& kd) {
  plant_->fix_gains(kp, kd);
  gains_fixed_ = true;
}

std::string SimulatedDrive::set_monitor(const MonitorSettings& m) {
  if (state_ == modbus_map::DriveState::playing) return "the collision monitor is set while no trajectory plays";
  return plant_->set_monitor(m, control_period());
}

modbus_map::MonitorState SimulatedDrive::monitor_state() const {
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

JointArray SimulatedDrive::kp() const {
  return plant_->kp();
}

JointArray SimulatedDrive::kd() const {
  return plant_->kd();
}

}  // namespace dyncal::host
