#include "modbus_request_handler.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "dyncal/centred_slope.hpp"
#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/modbus_pdu_server.hpp"

namespace dyncal::host {
namespace {

namespace mm = dyncal::modbus_map;
using Clock = ModbusRequestHandler::Clock;
using drive::be16;
using drive::kMaxTcpAduBytes;
using drive::kMbapHeaderBytes;
using drive::MbapFrame;
using drive::next_mbap_frame;

/// Copies the drive's state into the input registers (the ring window starts at the ack).
/// `table_generation`: the drive's table generation last copied into the registers (-1: none yet).
void refresh_inputs(const SimulatedDrive& d, std::uint16_t* in, long& table_generation) {
  in[mm::kMapVersionReg] = mm::kMapVersion;
  const int n_joints = d.num_joints();
  in[mm::kNumJointsReg] = static_cast<std::uint16_t>(n_joints);
  mm::set_u32(in + mm::kRobotIdReg, d.robot_id());
  mm::set_u32(in + mm::kActiveModelIdReg, d.active_table().model_id);
  in[mm::kActiveCountReg] = d.active_table().count;
  in[mm::kStateReg] = static_cast<std::uint16_t>(d.state());
  mm::set_f32(in + mm::kSimTimeReg, static_cast<float>(d.time()));
  mm::set_u32(in + mm::kProducedReg, d.produced());
  mm::set_u32(in + mm::kOverrunReg, d.overruns());
  const auto err = d.model_error_rms();
  for (int j = 0; j < n_joints; ++j) mm::set_f32(in + mm::kModelErrorReg + 2 * j, static_cast<float>(err[j]));
  in[mm::kFaultReg] = static_cast<std::uint16_t>(d.fault());
  in[mm::kFaultJointReg] = static_cast<std::uint16_t>(d.fault_joint());
  mm::set_f32(in + mm::kFaultValueReg, static_cast<float>(d.fault_value()));
  // The control law of the run started last: what IDIM-IV simulates (identify --method iv --law).
  mm::set_f32(in + mm::kControlRateReg, static_cast<float>(d.control_rate_hz()));
  const JointArray kp = d.kp(), kd = d.kd();
  for (int j = 0; j < n_joints; ++j) {
    mm::set_f32(in + mm::kGainKpReg + 2 * j, static_cast<float>(kp[j]));
    mm::set_f32(in + mm::kGainKdReg + 2 * j, static_cast<float>(kd[j]));
  }
  in[mm::kPayloadStateReg] = static_cast<std::uint16_t>(d.payload_state());
  in[mm::kMonitorStateReg] = static_cast<std::uint16_t>(d.monitor_state());
  for (int i = 0; i < 10; ++i) {
    mm::set_f32(in + mm::kPayloadReg + 2 * i, static_cast<float>(d.payload_value()[static_cast<size_t>(i)]));
    mm::set_f32(in + mm::kPayloadStdReg + 2 * i, static_cast<float>(d.payload_std()[static_cast<size_t>(i)]));
  }
  // The table registers change only with the table: copy them when it changed.
  if (table_generation != static_cast<long>(d.table_generation())) {
    const auto& bytes = d.active_table_bytes();
    mm::set_u32(in + mm::kActiveCrcReg, dyncal::detail::get_u32(bytes.data() + bytes.size() - 4));
    in[mm::kActiveTableSizeReg] = static_cast<std::uint16_t>(bytes.size());
    std::memset(in + mm::kActiveTableReg, 0, 2 * mm::kTableWords);
    mm::bytes_to_regs(bytes.data(), static_cast<int>(bytes.size()), in + mm::kActiveTableReg);
    table_generation = static_cast<long>(d.table_generation());
  }
  in[mm::kRingFormatReg] = static_cast<std::uint16_t>(d.ring_format_in_use());
  mm::set_u32(in + mm::kRingCapacityReg, static_cast<std::uint32_t>(d.ring_capacity));
  for (int j = 0; j < n_joints; ++j) {
    mm::set_f32(in + mm::kQResolutionReg + 2 * j, static_cast<float>(d.q_resolution(j)));
    mm::set_f32(in + mm::kTauResolutionReg + 2 * j, static_cast<float>(d.tau_resolution(j)));
  }
}

/// Writes the ring window into the holding registers: the oldest unacknowledged samples up to the
/// first gap (samples dropped by a full ring), with the drive's state and counters of this instant.
void refresh_window(const SimulatedDrive& d, std::uint16_t* h) {
  std::uint16_t* w = h + mm::kRingReg;
  std::memset(w, 0, 2 * mm::kRingWords);
  const int n_joints = d.num_joints();
  const mm::RingFormat format = d.ring_format_in_use();
  const auto& ring = d.ring();
  const std::uint32_t first = ring.empty() ? d.produced() : ring.front().seq;
  int n = 0;
  while (n < mm::samples_per_block(n_joints, format) && n < static_cast<int>(ring.size()) &&
         ring[static_cast<size_t>(n)].seq == first + static_cast<std::uint32_t>(n))
    ++n;
  mm::set_u32(w, first);
  w[2] = static_cast<std::uint16_t>(n);
  w[3] = static_cast<std::uint16_t>(d.state());
  mm::set_u32(w + 4, d.produced());
  mm::set_u32(w + 6, d.overruns());
  std::uint16_t* p = w + mm::kRingHeaderWords;
  for (int k = 0; k < n; ++k, p += mm::sample_words(n_joints, format)) {
    const port::DriveSample& s = ring[static_cast<size_t>(k)];
    for (int j = 0; j < n_joints; ++j) {
      if (format == mm::RingFormat::float32) {
        mm::set_f32(p + 2 * j, s.q[j]);
        mm::set_f32(p + 2 * (n_joints + j), s.qd[j]);
        mm::set_f32(p + 2 * (2 * n_joints + j), s.tau[j]);
        continue;
      }
      const double q = std::round(static_cast<double>(s.q[j]) / d.q_resolution(j));
      const double tau = std::round(static_cast<double>(s.tau[j]) / d.tau_resolution(j));
      const bool q_fits = std::fabs(q) <= 2147483647.0;  // false for NaN too
      mm::set_u32(p + 2 * j, static_cast<std::uint32_t>(q_fits ? static_cast<std::int32_t>(q) : mm::kQInvalid));
      const double full = mm::kTauFullScale;
      const double saturated = std::isnan(tau) ? full : std::clamp(tau, -full, full);  // as an ADC saturates
      p[2 * n_joints + j] = static_cast<std::uint16_t>(static_cast<std::int16_t>(saturated));
    }
  }
}

/// Every register of [address, address + count) lies in a field of `bank`.
bool addresses_defined(mm::Bank bank, int address, int count) {
  for (int a = address; a < address + count; ++a) {
    if (!mm::find_field(bank, a)) return false;
  }
  return true;
}

/// A write may not split a u32/f32 element.
bool splits_element(int address, int count) {
  for (int edge : {address, address + count}) {
    const mm::Field* f = mm::find_field(mm::Bank::holding, edge);
    if (f && edge != f->address && (f->type == mm::Type::u32 || f->type == mm::Type::f32) &&
        (edge - f->address) % 2 != 0) {
      return true;
    }
  }
  return false;
}

bool overlaps(int address, int count, std::uint16_t reg, int words) {
  return address < reg + words && reg < address + count;
}

/// The collision monitor's settings as the holding registers hold them.
MonitorSettings monitor_from_registers(const std::uint16_t* h) {
  MonitorSettings m;
  m.gain = mm::get_f32(h + mm::kMonitorGainReg);
  for (int j = 0; j < mm::kMaxJoints; ++j) {
    m.threshold[static_cast<size_t>(j)] = mm::get_f32(h + mm::kMonitorThresholdReg + 2 * j);
    m.mean[static_cast<size_t>(j)] = mm::get_f32(h + mm::kMonitorMeanReg + 2 * j);
    m.band[static_cast<size_t>(j)] = mm::get_f32(h + mm::kMonitorBandReg + 2 * j);
  }
  return m;
}

/// Checks the holding registers after a write (applied to a scratch copy) against the access and
/// state rules (docs/modbus.md "Access and states"). `session`: the writing connection holds an
/// open staging session; `session_elsewhere`: another connection does; `stream_elsewhere`: another
/// connection started the run (and is still connected): the ring's ack is its alone. Returns the
/// Modbus exception, or none.
drive::ModbusException check_holding(const SimulatedDrive& d, const std::uint16_t* h, int address, int count,
                                     double control_rate, bool session, bool session_elsewhere, bool stream_elsewhere) {
  const bool playing = d.state() == mm::DriveState::playing;
  const bool fault = d.state() == mm::DriveState::fault;
  // Staging and committing: only in a session, only while no trajectory plays and no fault stands.
  auto staging_rule = [&]() -> drive::ModbusException {
    if (!session) return drive::ModbusException::illegal_function;  // locked: the server is in the wrong state for it
    if (playing) return drive::ModbusException::server_device_busy;
    if (fault) return drive::ModbusException::server_device_failure;
    return drive::ModbusException::none;
  };
  if (overlaps(address, count, mm::kCommandReg, 1)) {
    const std::uint16_t c = h[mm::kCommandReg];
    if (c > static_cast<std::uint16_t>(mm::Command::trace)) return drive::ModbusException::illegal_data_value;
    // identify_payload writes the active table at the run's end: a staging session's right.
    if (c == static_cast<std::uint16_t>(mm::Command::commit_table) ||
        c == static_cast<std::uint16_t>(mm::Command::identify_payload)) {
      if (const drive::ModbusException e = staging_rule(); e != drive::ModbusException::none) return e;
    }
    if (c == static_cast<std::uint16_t>(mm::Command::start) ||
        c == static_cast<std::uint16_t>(mm::Command::identify_payload) ||
        c == static_cast<std::uint16_t>(mm::Command::trace)) {
      if (playing) return drive::ModbusException::server_device_busy;   // would jump the arm back to the start pose
      if (fault) return drive::ModbusException::server_device_failure;  // only reset clears a fault
      const double f_f = mm::get_f32(h + mm::kOmegaFReg), fs = mm::get_f32(h + mm::kSampleRateReg);
      if (!(mm::run_samples(h[mm::kPeriodsReg], f_f, fs) <= mm::kMaxRunSamples))
        return drive::ModbusException::illegal_data_value;  // the run would outlast the sample counter's resolution
      // A trace records the whole run: refused unless the ring holds every sample of it.
      if (c == static_cast<std::uint16_t>(mm::Command::trace) &&
          !(f_f > 0 && fs > 0 && d.run_samples(h[mm::kPeriodsReg], 1.0 / f_f, fs) <= d.ring_capacity))
        return drive::ModbusException::illegal_data_value;
      // The run starts with the monitor settings the registers hold: the rule the drive applies
      // them by (monitor_settings_error), checked again here as when they were written.
      if (!monitor_settings_error(monitor_from_registers(h), 1.0 / control_rate).empty())
        return drive::ModbusException::illegal_data_value;
    }
  }
  if (overlaps(address, count, mm::kUnlockReg, 1)) {
    if (h[mm::kUnlockReg] != mm::kUnlockKey) return drive::ModbusException::illegal_data_value;
    // One session at a time: another connection's open session is not taken over (it would commit
    // what that connection staged).
    if (session_elsewhere) return drive::ModbusException::server_device_busy;
  }
  // Staging, and the collision monitor's settings (a safety function's): the same rule.
  if (overlaps(address, count, mm::kStagingSizeReg, mm::kRingReg - mm::kStagingSizeReg)) {
    if (const drive::ModbusException e = staging_rule(); e != drive::ModbusException::none) return e;
  }
  // The collision monitor's settings when written: the rule the drive applies them by.
  if (overlaps(address, count, mm::kMonitorGainReg, mm::kMonitorBandReg + 2 * mm::kMaxJoints - mm::kMonitorGainReg) &&
      !monitor_settings_error(monitor_from_registers(h), 1.0 / control_rate).empty())
    return drive::ModbusException::illegal_data_value;
  if (overlaps(address, count, mm::kAckReg, 2)) {
    // The ring's samples are the run owner's to acknowledge: another connection's ack would free
    // samples the owner has not read, and end its stream with a gap it did not cause.
    if (stream_elsewhere) return drive::ModbusException::server_device_busy;
    const std::uint32_t a = mm::get_u32(h + mm::kAckReg);
    if (a < d.acked() || a > d.produced()) return drive::ModbusException::illegal_data_value;
  }
  const bool settings =
      overlaps(address, count, mm::kSampleRateReg, mm::kCoefficientsReg + mm::kCoefficientWords - mm::kSampleRateReg);
  if (settings && playing) return drive::ModbusException::server_device_busy;
  if (overlaps(address, count, mm::kSampleRateReg, 2)) {
    const double fs = mm::get_f32(h + mm::kSampleRateReg);
    const double ratio = control_rate / fs;
    if (!(fs >= mm::kMinSampleRateHz && fs <= mm::kMaxSampleRateHz) || std::fabs(ratio - std::round(ratio)) > 1e-6)
      return drive::ModbusException::illegal_data_value;
  }
  if (overlaps(address, count, mm::kOmegaFReg, 2)) {
    const double f = mm::get_f32(h + mm::kOmegaFReg);
    if (!(f > 0 && f <= mm::kMaxFundamentalHz)) return drive::ModbusException::illegal_data_value;
  }
  if (overlaps(address, count, mm::kHarmonicsReg, 1)) {
    if (h[mm::kHarmonicsReg] < 1 || h[mm::kHarmonicsReg] > mm::kMaxHarmonics)
      return drive::ModbusException::illegal_data_value;
  }
  if (overlaps(address, count, mm::kPeriodsReg, 1)) {
    if (h[mm::kPeriodsReg] < 1 || h[mm::kPeriodsReg] > mm::kMaxPeriods)
      return drive::ModbusException::illegal_data_value;
  }
  for (int k = 0; k < mm::kCoefficientWords; k += 2) {
    if (overlaps(address, count, static_cast<std::uint16_t>(mm::kCoefficientsReg + k), 2) &&
        !std::isfinite(mm::get_f32(h + mm::kCoefficientsReg + k))) {
      return drive::ModbusException::illegal_data_value;
    }
  }
  if (overlaps(address, count, mm::kStagingSizeReg, 1) && h[mm::kStagingSizeReg] > kTableMaxBytes) {
    return drive::ModbusException::illegal_data_value;
  }
  return drive::ModbusException::none;
}

/// Applies the monitor settings the registers hold before a run starts. check_holding applied the
/// same rule (monitor_settings_error) before the reply, so a refusal here means the drive's state
/// changed in between: the run does not start, and the log says why.
bool take_monitor(SimulatedDrive& d, const std::uint16_t* h, std::FILE* log) {
  const std::string why = d.set_monitor(monitor_from_registers(h));
  if (!why.empty() && log) std::fprintf(log, "dyncal drive: run not started: collision monitor: %s\n", why.c_str());
  return why.empty();
}

void load_trajectory(SimulatedDrive& d, const std::uint16_t* h) {
  d.sample_rate_hz = mm::get_f32(h + mm::kSampleRateReg);
  d.trajectory.f_f = mm::get_f32(h + mm::kOmegaFReg);
  d.trajectory.harmonics = h[mm::kHarmonicsReg];
  d.periods = h[mm::kPeriodsReg];
  for (int j = 0; j < mm::kMaxJoints; ++j) {  // every slot; the drive plays its robot's joints
    const std::uint16_t* c = h + mm::kCoefficientsReg + 2 * mm::kCoefficientsPerJoint * j;
    d.trajectory.q0[j] = mm::get_f32(c);
    for (int l = 0; l < mm::kMaxHarmonics; ++l) {
      d.trajectory.a(j, l) = mm::get_f32(c + 2 + 2 * l);
      d.trajectory.b(j, l) = mm::get_f32(c + 2 + 2 * mm::kMaxHarmonics + 2 * l);
    }
  }
}

}  // namespace

ModbusRequestHandler::ModbusRequestHandler(SimulatedDrive& drive, int rtu_fd, int unit_id, std::FILE* log)
    : drive_(drive), rtu_fd_(rtu_fd), unit_id_(unit_id), log_(log) {
  // Defaults: the survey's excitation settings (Eq. 27: L = 5, f_f = 0.1 Hz), 2 periods.
  mm::set_f32(holding_.data() + mm::kSampleRateReg, static_cast<float>(drive.sample_rate_hz));
  mm::set_f32(holding_.data() + mm::kOmegaFReg, 0.1f);
  holding_.data()[mm::kHarmonicsReg] = 5;
  holding_.data()[mm::kPeriodsReg] = 2;
}

ModbusRequestHandler::TcpResult ModbusRequestHandler::serve_tcp(const std::uint8_t* bytes, std::size_t size,
                                                                int client) {
  TcpResult r;
  for (;;) {
    const MbapFrame f = next_mbap_frame(bytes + r.used, size - r.used);
    if (f.status == MbapFrame::Status::invalid) {
      r.keep = false;
      return r;
    }
    if (f.status == MbapFrame::Status::incomplete) return r;
    std::uint8_t frame[kMaxTcpAduBytes + 8] = {};  // zero beyond the frame: a short PDU reads zeros
    std::memcpy(frame, bytes + r.used, f.bytes);
    r.used += f.bytes;
    ++r.frames;
    // Protocol id 0 is Modbus; the unit id is 0xFF (the spec's value for a server addressed by its
    // IP address) or the drive's unit id. Other frames are not for this drive: ignored.
    if (f.protocol != 0 || (f.unit != 0xFF && f.unit != unit_id_)) continue;
    if (!answer(frame, static_cast<int>(f.bytes), client)) {
      r.keep = false;
      return r;
    }
  }
}

void ModbusRequestHandler::client_closed(int client) {
  if (session_client_ == client) session_client_ = kNoClient;
  if (owner_client_ == client) owner_client_ = kNoClient;
}

bool ModbusRequestHandler::session_open() const {
  return session_client_ != kNoClient && session_client_ == current_client_ && Clock::now() < session_until_;
}

bool ModbusRequestHandler::session_held_by_another() const {
  return session_client_ != kNoClient && session_client_ != current_client_ && Clock::now() < session_until_;
}

bool ModbusRequestHandler::holds_a_role(int client) const {
  if (client == owner_client_) return true;
  return client == session_client_ && Clock::now() < session_until_;
}

/// The drive's registers as lib/'s PDU server sees them (dyncal/drive/modbus_pdu_server.hpp): reads
/// of the map, writes checked against the register map and the access and state rules
/// (check_holding) on a copy of the holding registers with the write in it, then applied.
struct ModbusRequestHandler::Bank {
  ModbusRequestHandler& h;

  drive::ModbusException read(bool input, std::uint16_t address, std::uint16_t count, std::uint16_t* out) const {
    if (!addresses_defined(input ? mm::Bank::input : mm::Bank::holding, address, count))
      return drive::ModbusException::illegal_data_address;
    const std::uint16_t* regs = input ? h.input_.data() : h.holding_.data();
    std::copy(regs + address, regs + address + count, out);
    return drive::ModbusException::none;
  }

  drive::ModbusException check_write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values) const {
    if (!addresses_defined(mm::Bank::holding, address, count) || splits_element(address, count) ||
        overlaps(address, count, mm::kRingReg, mm::kRingWords))
      return drive::ModbusException::illegal_data_address;
    std::vector<std::uint16_t> scratch(h.holding_.data(), h.holding_.data() + mm::kHoldingWords);
    for (int k = 0; k < count; ++k) scratch[static_cast<size_t>(address + k)] = be16(values + 2 * k);
    return (check_holding(h.drive_, scratch.data(), address, count, 1.0 / h.drive_.control_period(), h.session_open(),
                          h.session_held_by_another(),
                          h.owner_client_ != kNoClient && h.owner_client_ != h.current_client_));
  }

  /// The write, its effect on the drive, and the ring window after it (function 23 reads it next:
  /// an acknowledgement frees its samples before the next are shown). The command and unlock
  /// registers read 0 again at once.
  void write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values) const {
    for (int k = 0; k < count; ++k) h.holding_.data()[address + k] = be16(values + 2 * k);
    h.apply_write(address, count);
    refresh_window(h.drive_, h.holding_.data());
    h.holding_.data()[mm::kCommandReg] = 0;
    h.holding_.data()[mm::kUnlockReg] = 0;
  }
};

bool ModbusRequestHandler::answer(const std::uint8_t* adu, int length, int client) {
  current_client_ = client;
  if (client == owner_client_) owner_last_request_ = Clock::now();
  // The PDU: after the MBAP header on TCP; after the address and before the CRC on RTU.
  const bool rtu = client == kRtuClient;
  const std::size_t header = rtu ? 1 : kMbapHeaderBytes, trailer = rtu ? 2 : 0;
  if (length < 0 || static_cast<std::size_t>(length) < header + trailer + 1) return true;  // nothing to answer
  refresh_inputs(drive_, input_.data(), table_generation_);
  refresh_window(drive_, holding_.data());
  holding_.data()[mm::kCommandReg] = 0;
  Bank bank{*this};
  std::uint8_t reply[kMbapHeaderBytes + drive::kMaxPduBytes + 2];
  const std::size_t pdu =
      drive::serve_pdu(bank, adu + header, static_cast<std::size_t>(length) - header - trailer, reply + header);
  if (rtu) {  // the address, the PDU, the CRC low byte first (MODBUS over Serial Line v1.02, sec. 2.5.1)
    reply[0] = adu[0];
    const std::uint16_t crc = drive::crc16(reply, 1 + pdu);
    reply[1 + pdu] = static_cast<std::uint8_t>(crc & 0xFF);
    reply[2 + pdu] = static_cast<std::uint8_t>(crc >> 8);
    const std::size_t n = 3 + pdu;
    return ::write(rtu_fd_, reply, n) == static_cast<ssize_t>(n);
  }
  // MBAP: the request's transaction id, protocol 0, the length of unit id + PDU, its unit id.
  reply[0] = adu[0];
  reply[1] = adu[1];
  reply[2] = 0;
  reply[3] = 0;
  reply[4] = static_cast<std::uint8_t>((pdu + 1) >> 8);
  reply[5] = static_cast<std::uint8_t>((pdu + 1) & 0xFF);
  reply[6] = adu[6];
  const std::size_t n = kMbapHeaderBytes + pdu;
  return ::send(client, reply, n, MSG_NOSIGNAL) == static_cast<ssize_t>(n);
}

void ModbusRequestHandler::apply_write(int address, int count) {
  std::uint16_t* h = holding_.data();
  if (overlaps(address, count, mm::kAckReg, 2)) drive_.ack(mm::get_u32(h + mm::kAckReg));
  if (overlaps(address, count, mm::kUnlockReg, 1)) {
    // A new session starts empty: a commit writes only what its own connection staged.
    session_client_ = current_client_;
    session_until_ = Clock::now() + seconds(mm::kSessionSeconds);
    h[mm::kUnlockReg] = 0;
    std::fill(h + mm::kStagingSizeReg, h + mm::kStagingTableReg + mm::kTableWords, std::uint16_t{0});
  }
  if (!overlaps(address, count, mm::kCommandReg, 1)) return;
  switch (static_cast<mm::Command>(h[mm::kCommandReg])) {
    case mm::Command::start:
    case mm::Command::trace:  // the same run: the start check made sure the ring holds all of it
      load_trajectory(drive_, h);
      if (!take_monitor(drive_, h, log_)) break;
      drive_.start();
      started_ = Clock::now();
      owner_client_ = current_client_;
      owner_last_request_ = started_;
      mm::set_u32(h + mm::kAckReg, 0);
      break;
    case mm::Command::identify_payload:
      session_client_ = kNoClient;  // the table write it ends with uses the session
      load_trajectory(drive_, h);
      if (!take_monitor(drive_, h, log_)) break;
      drive_.start_payload();
      started_ = Clock::now();
      owner_client_ = current_client_;
      owner_last_request_ = started_;
      mm::set_u32(h + mm::kAckReg, 0);
      break;
    case mm::Command::stop:
      drive_.stop();
      break;
    case mm::Command::reset:
      drive_.reset();
      break;
    case mm::Command::commit_table: {
      session_client_ = kNoClient;  // a commit ends the session
      const int size = h[mm::kStagingSizeReg];
      std::vector<std::uint8_t> bytes(static_cast<size_t>(size));
      mm::regs_to_bytes(h + mm::kStagingTableReg, size, bytes.data());
      TableStatus st;
      try {
        st = drive_.commit(bytes.data(), size);
      } catch (const std::exception& e) {
        if (log_) std::fprintf(log_, "dyncal drive: flash write failed: %s\n", e.what());
        st = TableStatus::store_failed;  // the store's own failure, not the table's (the active one stays)
      }
      input_.data()[mm::kCommitResultReg] = static_cast<std::uint16_t>(st);
      ++input_.data()[mm::kCommitCounterReg];
      if (log_) {
        std::fprintf(log_, "dyncal drive: commit %s\n", to_string(st));
        std::fflush(log_);
      }
      break;
    }
    case mm::Command::none:
      break;
  }
  h[mm::kCommandReg] = 0;
}

}  // namespace dyncal::host
