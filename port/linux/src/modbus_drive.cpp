#include "dyncal_port/modbus_drive.hpp"

#include <modbus/modbus.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <thread>
#include <vector>

namespace dyncal::linux_port {
namespace mm = dyncal::modbus_map;

std::unique_ptr<ModbusDrive> ModbusDrive::connect(const std::string& uri, std::string* error) {
  modbus_t* ctx = nullptr;
  if (uri.rfind("tcp://", 0) == 0) {
    const std::string rest = uri.substr(6);
    const size_t colon = rest.rfind(':');
    if (colon == std::string::npos) {
      *error = "drive URI '" + uri + "' lacks a port (tcp://HOST:PORT)";
      return nullptr;
    }
    int port = 0;
    try {
      port = std::stoi(rest.substr(colon + 1));
    } catch (const std::exception&) {
      port = -1;
    }
    if (port <= 0 || port > 65535) {
      *error = "drive URI '" + uri + "' has an invalid port";
      return nullptr;
    }
    ctx = modbus_new_tcp(rest.substr(0, colon).c_str(), port);
  } else if (uri.rfind("rtu:", 0) == 0) {
    ctx = modbus_new_rtu(uri.substr(4).c_str(), 115200, 'N', 8, 1);
    if (ctx) modbus_set_slave(ctx, 1);
  } else {
    *error = "drive URI '" + uri + "' is neither tcp://HOST:PORT nor rtu:DEVICE";
    return nullptr;
  }
  if (!ctx) {
    *error = std::string("cannot create a Modbus context for ") + uri + ": " + modbus_strerror(errno);
    return nullptr;
  }
  modbus_set_response_timeout(ctx, 2, 0);
  if (modbus_connect(ctx) != 0) {
    *error = "cannot connect to the drive at " + uri + ": " + modbus_strerror(errno);
    modbus_free(ctx);
    return nullptr;
  }
  return std::unique_ptr<ModbusDrive>(new ModbusDrive(ctx, uri.rfind("rtu:", 0) == 0));
}

ModbusDrive::~ModbusDrive() {
  modbus_close(ctx_);
  modbus_free(ctx_);
}

port::PortStatus ModbusDrive::fail(const char* what) {
  const int code = errno;
  error_ = std::string(what) + ": " + modbus_strerror(code);
  // A Modbus exception response (illegal function, address or value, device failure, busy, ...):
  // the drive answered and refused. Anything else (time-out, broken link, bad frame) is transport.
  const bool exception = code > MODBUS_ENOBASE && code <= MODBUS_ENOBASE + MODBUS_EXCEPTION_GATEWAY_TARGET;
  return exception ? port::PortStatus::rejected : port::PortStatus::transport_error;
}

port::PortStatus ModbusDrive::read_input(int address, int count, std::uint16_t* regs) {
  if (modbus_read_input_registers(ctx_, address, count, regs) != count) return fail("reading input registers");
  return port::PortStatus::ok;
}
port::PortStatus ModbusDrive::read_holding(int address, int count, std::uint16_t* regs) {
  if (modbus_read_registers(ctx_, address, count, regs) != count) return fail("reading holding registers");
  return port::PortStatus::ok;
}
port::PortStatus ModbusDrive::write_holding(int address, int count, const std::uint16_t* regs) {
  for (int done = 0; done < count;) {
    const int n = std::min(count - done, MODBUS_MAX_WRITE_REGISTERS / 2 * 2);  // never split a 32-bit value
    if (modbus_write_registers(ctx_, address + done, n, regs + done) != n) return fail("writing holding registers");
    done += n;
  }
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::read_info(DriveInfo& info) {
  std::uint16_t r[mm::kModelErrorReg + 2 * mm::kMaxJoints];
  if (const auto st = read_input(0, mm::kModelErrorReg + 2 * mm::kMaxJoints, r); st != port::PortStatus::ok) return st;
  info.map_version = r[mm::kMapVersionReg];
  if (info.map_version != mm::kMapVersion) {  // another layout: nothing else in it can be read
    error_ = "the drive speaks Modbus register map version " + std::to_string(info.map_version) +
             ", this host version " + std::to_string(mm::kMapVersion) + " (docs/modbus.md): update one of them";
    return port::PortStatus::rejected;
  }
  info.num_joints = r[mm::kNumJointsReg];
  if (info.num_joints < 1 || info.num_joints > mm::kMaxJoints) {
    error_ = "the drive reports " + std::to_string(info.num_joints) + " joints (1.." + std::to_string(mm::kMaxJoints) +
             " supported)";
    return port::PortStatus::rejected;
  }
  joints_ = info.num_joints;
  info.robot_id = mm::get_u32(r + mm::kRobotIdReg);
  info.active_model_id = mm::get_u32(r + mm::kActiveModelIdReg);
  info.active_count = r[mm::kActiveCountReg];
  info.state = static_cast<mm::DriveState>(r[mm::kStateReg]);
  info.sim_time = mm::get_f32(r + mm::kSimTimeReg);
  info.produced = mm::get_u32(r + mm::kProducedReg);
  info.overruns = mm::get_u32(r + mm::kOverrunReg);
  for (int j = 0; j < mm::kMaxJoints; ++j) info.model_error_rms[j] = mm::get_f32(r + mm::kModelErrorReg + 2 * j);
  // The fault registers only when there is a fault: read() polls this while it waits for samples.
  if (info.state != mm::DriveState::fault) {
    info.fault = mm::DriveFault::none;
    info.fault_joint = 0;
    info.fault_value = 0;
    return port::PortStatus::ok;
  }
  std::uint16_t f[4];
  if (const auto st = read_input(mm::kFaultReg, 4, f); st != port::PortStatus::ok) return st;
  info.fault = static_cast<mm::DriveFault>(f[0]);
  info.fault_joint = f[1];
  info.fault_value = mm::get_f32(f + 2);
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::read_control_law(DriveControlLaw& law) {
  constexpr int kWords = mm::kGainKdReg + 2 * mm::kMaxJoints - mm::kControlRateReg;
  std::uint16_t r[kWords];
  if (const auto st = read_input(mm::kControlRateReg, kWords, r); st != port::PortStatus::ok) return st;
  law.control_rate_hz = mm::get_f32(r);
  for (int j = 0; j < mm::kMaxJoints; ++j) {
    law.kp[j] = mm::get_f32(r + (mm::kGainKpReg - mm::kControlRateReg) + 2 * j);
    law.kd[j] = mm::get_f32(r + (mm::kGainKdReg - mm::kControlRateReg) + 2 * j);
  }
  return port::PortStatus::ok;
}

std::string describe_fault(const DriveInfo& info) {
  char text[160];
  if (info.fault == mm::DriveFault::communication_lost) {
    std::snprintf(text, sizeof text, "communication lost: no request for %.3g s while playing, stopped at t = %.3f s",
                  info.fault_value, info.sim_time);
    return text;
  }
  const char* what = info.fault == mm::DriveFault::position_limit   ? "q = %.4g rad"
                     : info.fault == mm::DriveFault::velocity_limit ? "qd = %.4g rad/s"
                     : info.fault == mm::DriveFault::collision      ? "residual r - mean = %.4g Nm"
                                                                    : nullptr;
  char value[48] = "";
  if (what) std::snprintf(value, sizeof value, what, info.fault_value);
  std::snprintf(text, sizeof text, "joint %d %s%s%s at t = %.3f s", info.fault_joint, mm::to_string(info.fault),
                what ? ": " : "", value, info.sim_time);
  return text;
}

port::PortStatus ModbusDrive::write_trajectory(const Trajectory& t, int periods, double sample_rate_hz) {
  // The drive checks these too (Modbus exception); checked here first to say which value and why.
  char text[200] = "";
  switch (mm::refused_trajectory_setting(sample_rate_hz, t.f_f, t.harmonics, periods)) {
    case mm::TrajectorySetting::none:
      break;
    case mm::TrajectorySetting::sample_rate:
      std::snprintf(text, sizeof text, "sample rate %.4g Hz outside %.0f..%.0f Hz", sample_rate_hz,
                    mm::kMinSampleRateHz, mm::kMaxSampleRateHz);
      break;
    case mm::TrajectorySetting::omega_f:
      std::snprintf(text, sizeof text, "fundamental frequency f_f = %.4g Hz outside (0, %.0f] Hz", t.f_f,
                    mm::kMaxFundamentalHz);
      break;
    case mm::TrajectorySetting::harmonics:
      std::snprintf(text, sizeof text, "%d harmonics, 1..%d supported", t.harmonics, mm::kMaxHarmonics);
      break;
    case mm::TrajectorySetting::periods:
      std::snprintf(text, sizeof text, "%d periods, 1..%d supported", periods, mm::kMaxPeriods);
      break;
    case mm::TrajectorySetting::run_length:
      std::snprintf(text, sizeof text,
                    "a run of %d periods at f_f = %.4g Hz and %.4g Hz is %.4g samples, longer than the drive's "
                    "%.0f (docs/modbus.md)",
                    periods, t.f_f, sample_rate_hz, mm::run_samples(periods, t.f_f, sample_rate_hz),
                    mm::kMaxRunSamples);
      break;
  }
  if (text[0] != '\0') {
    error_ = text;
    return port::PortStatus::rejected;
  }
  std::uint16_t settings[6];
  mm::set_f32(settings, static_cast<float>(sample_rate_hz));
  mm::set_f32(settings + 2, static_cast<float>(t.f_f));
  settings[4] = static_cast<std::uint16_t>(t.harmonics);
  settings[5] = static_cast<std::uint16_t>(periods);
  std::vector<std::uint16_t> c(mm::kCoefficientWords, 0);
  for (int j = 0; j < mm::kMaxJoints; ++j) {
    std::uint16_t* p = c.data() + 2 * mm::kCoefficientsPerJoint * j;
    mm::set_f32(p, static_cast<float>(t.q0[j]));
    for (int l = 0; l < mm::kMaxHarmonics; ++l) {
      mm::set_f32(p + 2 + 2 * l, static_cast<float>(t.a(j, l)));
      mm::set_f32(p + 2 + 2 * mm::kMaxHarmonics + 2 * l, static_cast<float>(t.b(j, l)));
    }
  }
  if (const auto st = write_holding(mm::kSampleRateReg, 6, settings); st != port::PortStatus::ok) return st;
  if (const auto st = write_holding(mm::kCoefficientsReg, mm::kCoefficientWords, c.data()); st != port::PortStatus::ok)
    return st;
  sample_rate_hz_ = sample_rate_hz;
  return port::PortStatus::ok;
}

void ModbusDrive::begin_run() {
  next_seq_ = 0;
  saturated_.fill(0);
  lost_ = drive_overruns_ = 0;
  pace_until_ = {};
}

port::PortStatus ModbusDrive::start() {
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::start);
  begin_run();
  return write_holding(mm::kCommandReg, 1, &cmd);
}

port::PortStatus ModbusDrive::trace() {
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::trace);
  begin_run();
  return write_holding(mm::kCommandReg, 1, &cmd);
}

port::PortStatus ModbusDrive::identify_payload() {
  const std::uint16_t key = mm::kUnlockKey;
  if (const auto st = write_holding(mm::kUnlockReg, 1, &key); st != port::PortStatus::ok) return st;
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::identify_payload);
  begin_run();
  return write_holding(mm::kCommandReg, 1, &cmd);
}

port::PortStatus ModbusDrive::read_payload(DrivePayload& payload) {
  constexpr int kWords = mm::kPayloadStdReg + 20 - mm::kPayloadStateReg;
  std::uint16_t r[kWords];
  if (const auto st = read_input(mm::kPayloadStateReg, kWords, r); st != port::PortStatus::ok) return st;
  payload.state = static_cast<mm::PayloadState>(r[0]);
  for (int i = 0; i < 10; ++i) {
    payload.value[static_cast<size_t>(i)] = mm::get_f32(r + (mm::kPayloadReg - mm::kPayloadStateReg) + 2 * i);
    payload.std[static_cast<size_t>(i)] = mm::get_f32(r + (mm::kPayloadStdReg - mm::kPayloadStateReg) + 2 * i);
  }
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::write_monitor(const DriveMonitor& m) {
  constexpr int kWords = mm::kMonitorBandReg + 2 * mm::kMaxJoints - mm::kMonitorGainReg;
  std::uint16_t r[kWords] = {};
  mm::set_f32(r, static_cast<float>(m.gain));
  for (int j = 0; j < mm::kMaxJoints; ++j) {
    const auto i = static_cast<size_t>(j);
    mm::set_f32(r + (mm::kMonitorThresholdReg - mm::kMonitorGainReg) + 2 * j, static_cast<float>(m.threshold[i]));
    mm::set_f32(r + (mm::kMonitorMeanReg - mm::kMonitorGainReg) + 2 * j, static_cast<float>(m.mean[i]));
    mm::set_f32(r + (mm::kMonitorBandReg - mm::kMonitorGainReg) + 2 * j, static_cast<float>(m.band[i]));
  }
  const std::uint16_t key = mm::kUnlockKey;
  if (const auto st = write_holding(mm::kUnlockReg, 1, &key); st != port::PortStatus::ok) return st;
  return write_holding(mm::kMonitorGainReg, kWords, r);
}

port::PortStatus ModbusDrive::read_monitor_state(mm::MonitorState& state) {
  std::uint16_t r = 0;
  if (const auto st = read_input(mm::kMonitorStateReg, 1, &r); st != port::PortStatus::ok) return st;
  state = static_cast<mm::MonitorState>(r);
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::reset() {
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::reset);
  return write_holding(mm::kCommandReg, 1, &cmd);
}

port::PortStatus ModbusDrive::stop() {
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::stop);
  return write_holding(mm::kCommandReg, 1, &cmd);
}

port::PortStatus ModbusDrive::read_stream_format() {
  if (stream_format_known_) return port::PortStatus::ok;
  DriveInfo info;
  if (const auto st = read_info(info); st != port::PortStatus::ok) return st;
  constexpr int kWords = mm::kRingCapacityReg + 2 - mm::kRingFormatReg;
  std::uint16_t r[kWords];
  if (const auto st = read_input(mm::kRingFormatReg, kWords, r); st != port::PortStatus::ok) return st;
  if (r[0] > static_cast<std::uint16_t>(mm::RingFormat::counts)) {
    error_ = "the drive's ring format " + std::to_string(r[0]) + " is unknown (0 float32, 1 counts)";
    return port::PortStatus::rejected;
  }
  format_ = static_cast<mm::RingFormat>(r[0]);
  ring_capacity_ = static_cast<long>(mm::get_u32(r + (mm::kRingCapacityReg - mm::kRingFormatReg)));
  for (int j = 0; j < joints_; ++j) {
    resolution_.q[j] = mm::get_f32(r + (mm::kQResolutionReg - mm::kRingFormatReg) + 2 * j);
    resolution_.tau[j] = mm::get_f32(r + (mm::kTauResolutionReg - mm::kRingFormatReg) + 2 * j);
    if (format_ == mm::RingFormat::counts && !(resolution_.q[j] > 0 && resolution_.tau[j] > 0)) {
      error_ = "the drive streams counts but gives joint " + std::to_string(j + 1) + " no resolution";
      return port::PortStatus::rejected;
    }
  }
  stream_format_known_ = true;
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::confirm_loss(std::uint32_t from, std::uint32_t to, std::uint32_t overruns) {
  if (overruns < lost_) {
    error_ = "the samples jump from seq " + std::to_string(from) + " to " + std::to_string(to) + " (" +
             std::to_string(lost_) + " missing in all) but the drive counts " + std::to_string(overruns) +
             " overruns: the link delivered replies out of step with the requests";
    return port::PortStatus::transport_error;
  }
  drive_overruns_ = overruns;
  return port::PortStatus::sequence_gap;
}

port::PortStatus ModbusDrive::ring_transaction(std::uint32_t ack_seq, std::uint16_t* w) {
  std::uint16_t ack[2];
  mm::set_u32(ack, ack_seq);
  if (modbus_write_and_read_registers(ctx_, mm::kAckReg, 2, ack, mm::kRingReg, mm::kRingWords, w) != mm::kRingWords) {
    fail("reading the ring window");
    return port::PortStatus::transport_error;
  }
  ++link_.transactions;
  link_.bytes += rtu_ ? kRtuTransactionBytes : kTcpTransactionBytes;
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::measure_link(int transactions, double* seconds) {
  if (const auto st = read_stream_format(); st != port::PortStatus::ok) return st;
  // The acknowledgement the drive holds (the ack register), written again: it frees nothing, and
  // the drive accepts it whoever streamed last (an ack below it is refused).
  std::uint16_t held[2];
  if (const auto st = read_holding(mm::kAckReg, 2, held); st != port::PortStatus::ok) return st;
  std::uint16_t w[mm::kRingWords];
  const int n = std::max(1, transactions);
  const auto t0 = std::chrono::steady_clock::now();
  for (int k = 0; k < n; ++k) {
    if (const auto st = ring_transaction(mm::get_u32(held), w); st != port::PortStatus::ok) return st;
  }
  *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() / n;
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::read(port::DriveSample* out, int capacity, int* count) noexcept {
  *count = 0;
  // The sample layout depends on the drive's joint count and format.
  if (const auto st = read_stream_format(); st != port::PortStatus::ok) return st;
  const int per_block = mm::samples_per_block(joints_, format_);
  // Paced: after a block that was not full, wait until the rest of a block is due instead of
  // asking again at once (a block per transaction, not a sample).
  if (pace_until_ > std::chrono::steady_clock::now()) std::this_thread::sleep_until(pace_until_);
  // One transaction: acknowledge what was received (ack = next seq) and read the window after it.
  std::uint16_t w[mm::kRingWords];
  if (const auto st = ring_transaction(next_seq_, w); st != port::PortStatus::ok) return st;
  const drive::RingWindowHeader header = drive::decode_ring_header(w);
  const std::uint32_t first = header.first;
  const int in_block = header.count;
  const mm::DriveState state = header.state;
  const std::uint32_t produced = header.produced, overruns = header.overruns;
  if (in_block > per_block) {
    error_ = "ring block of " + std::to_string(in_block) + " samples, at most " + std::to_string(per_block) +
             " fit for " + std::to_string(joints_) + " joints";
    return port::PortStatus::transport_error;
  }
  const bool playing = state == mm::DriveState::playing;
  // Samples the drive holds past this block (by its counter): fewer than a block's worth means the
  // next call waits until the rest is due.
  const long waiting = static_cast<long>(produced) - static_cast<long>(first) - in_block;
  pace_until_ = playing && waiting < per_block && sample_rate_hz_ > 0
                    ? std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(
                              std::min(0.05, (static_cast<double>(per_block - waiting) + 0.5) / sample_rate_hz_)))
                    : std::chrono::steady_clock::time_point{};
  if (in_block == 0) {
    if (playing) return port::PortStatus::no_data;
    // The header and the window are of one instant: an empty window after the run is final.
    if (produced > next_seq_) {  // the run's last samples were dropped (a full ring)
      const std::uint32_t from = next_seq_;
      lost_ += produced - next_seq_;
      next_seq_ = produced;
      return confirm_loss(from, produced, overruns);
    }
    if (state == mm::DriveState::fault) {
      DriveInfo info;
      if (read_info(info) != port::PortStatus::ok) return port::PortStatus::transport_error;
      error_ = "drive fault: " + describe_fault(info);
      return port::PortStatus::device_fault;
    }
    return port::PortStatus::end_of_stream;
  }
  if (first < next_seq_) {
    error_ = "the drive's ring window repeats samples already received (seq " + std::to_string(first) + ", expected " +
             std::to_string(next_seq_) + ")";
    return port::PortStatus::transport_error;
  }
  const int n = std::min(in_block, capacity);
  const std::uint16_t* p = w + mm::kRingHeaderWords;
  for (int k = 0; k < n; ++k, p += mm::sample_words(joints_, format_)) {
    port::DriveSample& s = out[k];
    s = port::DriveSample{};
    s.seq = first + static_cast<std::uint32_t>(k);
    // Counts: the velocity is the host's (qd NaN), an invalid q decodes as NaN, a torque at full
    // scale is counted as saturated.
    const std::uint32_t saturated = drive::decode_ring_sample(p, joints_, format_, resolution_, s);
    for (int j = 0; j < joints_; ++j)
      if (saturated & (1u << j)) ++saturated_[static_cast<std::size_t>(j)];
  }
  const std::uint32_t from = next_seq_;
  next_seq_ = first + static_cast<std::uint32_t>(n);  // acknowledged by the next transaction
  *count = n;
  link_.samples += n;
  if (first == from) return port::PortStatus::ok;
  lost_ += first - from;  // dropped by a full ring: the block starts after the gap
  return confirm_loss(from, first, overruns);
}

port::PortStatus ModbusDrive::write(const ParameterTable& table, TableStatus* reason) noexcept {
  std::uint8_t bytes[kTableMaxBytes];
  int size = 0;
  *reason = encode_table(table, bytes, kTableMaxBytes, &size);
  if (*reason != TableStatus::ok) return port::PortStatus::rejected;
  std::uint16_t regs[mm::kTableWords + 1] = {};
  regs[0] = static_cast<std::uint16_t>(size);
  mm::bytes_to_regs(bytes, size, regs + 1);
  std::uint16_t counter_before = 0;
  if (read_input(mm::kCommitCounterReg, 1, &counter_before) != port::PortStatus::ok)
    return port::PortStatus::transport_error;
  // A staging session for this connection (docs/modbus.md "Access and states"); the commit ends it.
  // The drive refuses staging while it plays (busy) or stands in fault (device failure).
  const std::uint16_t key = mm::kUnlockKey;
  if (write_holding(mm::kUnlockReg, 1, &key) != port::PortStatus::ok) {
    // One staging session at a time (docs/modbus.md "Access and states"): busy names who holds it.
    if (errno == EMBXSBUSY)
      error_ =
          "another connection holds the drive's staging session (another host flashing or writing the "
          "collision monitor); it ends with that connection's commit, when it closes, or " +
          std::to_string(static_cast<int>(mm::kSessionSeconds)) + " s after it opened: try again then";
    return port::PortStatus::transport_error;
  }
  if (write_holding(mm::kStagingSizeReg, 1 + (size + 1) / 2, regs) != port::PortStatus::ok) {
    if (errno == EMBXSFAIL) error_ = "the drive is in fault: it takes no table until reset (docs/modbus.md)";
    if (errno == EMBXSBUSY) error_ = "the drive is playing a trajectory: it takes a table only when idle";
    return port::PortStatus::transport_error;
  }
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::commit_table);
  if (write_holding(mm::kCommandReg, 1, &cmd) != port::PortStatus::ok) return port::PortStatus::transport_error;
  // The drive answers the command at once and flashes afterwards: poll its commit counter, with a
  // deadline (a drive that never counts must not hang the host).
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(commit_timeout_s_);
  for (;;) {
    std::uint16_t r[2];
    if (read_input(mm::kCommitResultReg, 2, r) != port::PortStatus::ok) return port::PortStatus::transport_error;
    if (r[1] != counter_before) {
      *reason = static_cast<TableStatus>(r[0]);
      break;
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "the drive did not finish the commit within %.3g s (its commit counter stayed at %u); "
                    "read the active table back before trusting it",
                    commit_timeout_s_, static_cast<unsigned>(counter_before));
      error_ = text;
      return port::PortStatus::transport_error;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  if (*reason != TableStatus::ok) return port::PortStatus::rejected;
  // Read back and compare byte for byte.
  std::uint8_t back[kTableMaxBytes];
  int back_size = 0;
  if (read_active_bytes(back, kTableMaxBytes, &back_size) != port::PortStatus::ok)
    return port::PortStatus::transport_error;
  if (back_size != size || std::memcmp(back, bytes, static_cast<size_t>(size)) != 0) {
    error_ = "the drive's active table differs from the table sent";
    return port::PortStatus::transport_error;
  }
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::read_active_bytes(std::uint8_t* bytes, int capacity, int* size) {
  std::uint16_t regs[mm::kTableWords + 1];
  for (int done = 0; done < mm::kTableWords + 1;) {
    const int n = std::min(mm::kTableWords + 1 - done, MODBUS_MAX_READ_REGISTERS);
    if (const auto st = read_input(mm::kActiveTableSizeReg + done, n, regs + done); st != port::PortStatus::ok)
      return st;
    done += n;
  }
  *size = regs[0];
  if (*size > capacity) {
    error_ = "active table larger than the buffer";
    return port::PortStatus::transport_error;
  }
  mm::regs_to_bytes(regs + 1, *size, bytes);
  return port::PortStatus::ok;
}

port::PortStatus ModbusDrive::read(ParameterTable& table, TableStatus* reason) noexcept {
  std::uint8_t bytes[kTableMaxBytes];
  int size = 0;
  if (read_active_bytes(bytes, kTableMaxBytes, &size) != port::PortStatus::ok) return port::PortStatus::transport_error;
  *reason = decode_table(bytes, size, table);
  return *reason == TableStatus::ok ? port::PortStatus::ok : port::PortStatus::rejected;
}

std::uint64_t ModbusDrive::now_us() noexcept {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

}  // namespace dyncal::linux_port
