#pragma once
// The drive application's register server: the register map (modbus_map.hpp) with its access and
// state rules, the staging session and its owner, the run's owner (whose silence the watchdog
// times), and the commands, served through lib/'s PDU server (modbus_pdu_server.hpp). One source
// for every drive: the Linux simulated drive and the Cortex-M drive images. Transport-free (the
// caller frames: modbus_frames.hpp), heap-free, exception-free; time is the port's monotonic clock
// in microseconds. The rules: docs/modbus.md "Access and states", "Exceptions"; the Modbus
// Application Protocol v1.1b3, sec. 7 for the exception codes.
//
// What the drive supplies (a type, `Drive`):
//
//   struct Drive {
//     // for the rules
//     modbus_map::DriveState state() const;
//     std::uint32_t acked() const;                 // samples with seq < acked() are freed
//     std::uint32_t produced() const;              // samples recorded since the start
//     long ring_capacity_samples() const;          // samples the ring holds
//     long run_samples(double periods, double period_s, double fs) const;  // a run's samples, rests included
//     double control_rate_hz() const;
//     // the commands
//     void ack(std::uint32_t seq_end);             // frees samples with seq < seq_end
//     // start, trace or identify_payload with these settings; false: refused (the run does not start)
//     bool start(modbus_map::Command c, const RunSettings& run, const MonitorSettings& monitor);
//     void stop();
//     void reset();                                // clears a fault
//     TableStatus commit(const std::uint8_t* bytes, int size);  // check, store, activate (or not)
//     // what the registers show: every input register but commit_result and commit_counter
//     // (the server's), and the ring window (ring_window.hpp's encode_ring_window)
//     void publish_inputs(std::uint16_t* input) const;
//     void publish_window(std::uint16_t* window) const;
//   };

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "dyncal/drive/modbus_pdu_server.hpp"
#include "dyncal/drive/monitor_settings.hpp"
#include "dyncal/fourier_trajectory.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"

namespace dyncal::drive {

/// Monotonic time [us] (the port's clock).
using Microseconds = std::uint64_t;

/// A run's settings as the holding registers carry them: the recording rate, the periods to play
/// and the Fourier excitation (survey Eq. 27) in every register slot (the drive plays its robot's
/// joints, the first slots).
struct RunSettings {
  double sample_rate_hz = 0;  ///< recording rate [Hz]
  int periods = 0;
  FourierTrajectory<double, modbus_map::kMaxJoints, modbus_map::kMaxHarmonics> trajectory{};
};

/// The run settings the holding registers `h` hold.
inline RunSettings run_from_registers(const std::uint16_t* h) noexcept {
  namespace mm = modbus_map;
  RunSettings r;
  r.sample_rate_hz = mm::get_f32(h + mm::kSampleRateReg);
  r.periods = h[mm::kPeriodsReg];
  r.trajectory.f_f = mm::get_f32(h + mm::kOmegaFReg);
  r.trajectory.harmonics = h[mm::kHarmonicsReg];
  for (int j = 0; j < mm::kMaxJoints; ++j) {
    const std::uint16_t* c = h + mm::kCoefficientsReg + 2 * mm::kCoefficientsPerJoint * j;
    r.trajectory.q0[j] = mm::get_f32(c);
    for (int l = 0; l < mm::kMaxHarmonics; ++l) {
      r.trajectory.a(j, l) = mm::get_f32(c + 2 + 2 * l);
      r.trajectory.b(j, l) = mm::get_f32(c + 2 + 2 * mm::kMaxHarmonics + 2 * l);
    }
  }
  return r;
}

namespace detail {

inline bool overlaps(int address, int count, int reg, int words) noexcept {
  return address < reg + words && reg < address + count;
}

/// Every register of [address, address + count) lies in a field of `bank` (walked field by field).
inline bool addresses_defined(modbus_map::Bank bank, int address, int count) noexcept {
  for (int a = address; a < address + count;) {
    const modbus_map::Field* f = modbus_map::find_field(bank, a);
    if (!f) return false;
    a = f->address + f->words;
  }
  return true;
}

/// A write that would split a u32/f32 element of the holding bank.
inline bool splits_element(int address, int count) noexcept {
  namespace mm = modbus_map;
  for (const int edge : {address, address + count}) {
    const mm::Field* f = mm::find_field(mm::Bank::holding, edge);
    if (f && edge != f->address && (f->type == mm::Type::u32 || f->type == mm::Type::f32) &&
        (edge - f->address) % 2 != 0)
      return true;
  }
  return false;
}

}  // namespace detail

/// What one request did besides its reply, for the transport's log.
struct ServedRequest {
  std::size_t reply_bytes = 0;  ///< the reply PDU's length (0: none)
  bool committed = false;       ///< a commit command ran; `commit` its result
  TableStatus commit = TableStatus::ok;
  bool run_refused = false;  ///< a start was accepted by the rules but refused by the drive (Drive::start)
};

template <typename Drive>
class RegisterServer {
 public:
  /// No client (the watchdog's owner before a start, the session before an unlock).
  static constexpr int kNoClient = -1;

  /// Defaults: the survey's excitation settings (Eq. 27: L = 5, f_f = 0.1 Hz), 2 periods,
  /// `sample_rate_hz` [Hz].
  RegisterServer(Drive& drive, double sample_rate_hz) noexcept : drive_(drive) {
    namespace mm = modbus_map;
    mm::set_f32(holding_.data() + mm::kSampleRateReg, static_cast<float>(sample_rate_hz));
    mm::set_f32(holding_.data() + mm::kOmegaFReg, 0.1f);
    holding_[mm::kHarmonicsReg] = 5;
    holding_[mm::kPeriodsReg] = 2;
  }
  RegisterServer(const RegisterServer&) = delete;
  RegisterServer& operator=(const RegisterServer&) = delete;

  /// Answers request PDU req[0, n) of `client` (an id >= 0 or any id but kNoClient the transport
  /// gives its connection) at time `now` into reply[0, kMaxPduBytes). A write is applied only when
  /// it passes the register map and the access and state rules; otherwise the reply is the Modbus
  /// exception they give (docs/modbus.md "Exceptions").
  ServedRequest answer(const std::uint8_t* req, std::size_t n, int client, Microseconds now,
                       std::uint8_t* reply) noexcept {
    namespace mm = modbus_map;
    current_client_ = client;
    now_ = now;
    served_ = ServedRequest{};
    if (client == owner_client_) owner_last_request_ = now;
    drive_.publish_inputs(input_.data());
    drive_.publish_window(holding_.data() + mm::kRingReg);
    holding_[mm::kCommandReg] = 0;
    Bank bank{*this};
    served_.reply_bytes = serve_pdu(bank, req, n, reply);
    return served_;
  }

  /// `client`'s connection closed: a session it held ends and it no longer owns the run (its id
  /// may be reused). The watchdog still counts the owner's silence from its last request: a host
  /// that died mid-run trips it.
  void client_closed(int client) noexcept {
    if (session_client_ == client) session_client_ = kNoClient;
    if (owner_client_ == client) owner_client_ = kNoClient;
  }

  /// `client` must not be disconnected to make room for a newcomer: it owns the run or holds an
  /// open staging session.
  bool holds_a_role(int client, Microseconds now) const noexcept {
    return client == owner_client_ || (client == session_client_ && now < session_until_);
  }
  /// The last request of the client that started the run (the start's time if it has sent
  /// nothing since): the watchdog watches this client only.
  Microseconds owner_last_request() const noexcept { return owner_last_request_; }
  /// When the last start was applied.
  Microseconds started() const noexcept { return started_; }

 private:
  /// The registers as serve_pdu reads and writes them.
  struct Bank {
    RegisterServer& s;
    ModbusException read(bool input, std::uint16_t address, std::uint16_t count, std::uint16_t* out) const noexcept {
      if (!detail::addresses_defined(input ? modbus_map::Bank::input : modbus_map::Bank::holding, address, count))
        return ModbusException::illegal_data_address;
      const std::uint16_t* regs = input ? s.input_.data() : s.holding_.data();
      for (int k = 0; k < count; ++k) out[k] = regs[address + k];
      return ModbusException::none;
    }
    /// The write is put into the registers, judged, and the old values restored: no effect.
    ModbusException check_write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values) const noexcept {
      namespace mm = modbus_map;
      if (!detail::addresses_defined(mm::Bank::holding, address, count) || detail::splits_element(address, count) ||
          detail::overlaps(address, count, mm::kRingReg, mm::kRingWords))
        return ModbusException::illegal_data_address;
      std::uint16_t old[kMaxWriteRegisters];
      for (int k = 0; k < count; ++k) {
        old[k] = s.holding_[static_cast<std::size_t>(address + k)];
        s.holding_[static_cast<std::size_t>(address + k)] = be16(values + 2 * k);
      }
      const ModbusException e = s.check_holding(address, count);
      for (int k = 0; k < count; ++k) s.holding_[static_cast<std::size_t>(address + k)] = old[k];
      return e;
    }
    /// The write, its effect, and the ring window after it (function 23 reads it next: an
    /// acknowledgement frees its samples before the next are shown). command and unlock read 0.
    void write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values) const noexcept {
      namespace mm = modbus_map;
      for (int k = 0; k < count; ++k) s.holding_[static_cast<std::size_t>(address + k)] = be16(values + 2 * k);
      s.apply_write(address, count);
      s.drive_.publish_window(s.holding_.data() + mm::kRingReg);
      s.holding_[mm::kCommandReg] = 0;
      s.holding_[mm::kUnlockReg] = 0;
    }
  };
  friend struct Bank;

  bool session_open() const noexcept {
    return session_client_ != kNoClient && session_client_ == current_client_ && now_ < session_until_;
  }
  bool session_held_by_another() const noexcept {
    return session_client_ != kNoClient && session_client_ != current_client_ && now_ < session_until_;
  }

  /// The holding registers with a write in them, against the access and state rules.
  ModbusException check_holding(int address, int count) const noexcept {
    namespace mm = modbus_map;
    using E = ModbusException;
    using detail::overlaps;
    const std::uint16_t* h = holding_.data();
    const bool playing = drive_.state() == mm::DriveState::playing;
    const bool fault = drive_.state() == mm::DriveState::fault;
    const bool session = session_open();
    // Staging and committing: only in a session, only while no run plays and no fault stands.
    auto staging_rule = [&]() -> E {
      if (!session) return E::illegal_function;  // locked: the server is in the wrong state for it
      if (playing) return E::server_device_busy;
      if (fault) return E::server_device_failure;
      return E::none;
    };
    // The monitor settings by the rule the drive runs them by (only where a write or a start needs it).
    auto monitor_ok = [&] {
      const double dt = 1.0 / drive_.control_rate_hz();
      return check_monitor_settings(monitor_from_registers(h), dt).refusal == MonitorRefusal::none;
    };
    if (overlaps(address, count, mm::kCommandReg, 1)) {
      const std::uint16_t c = h[mm::kCommandReg];
      using C = mm::Command;
      if (c > static_cast<std::uint16_t>(C::trace)) return E::illegal_data_value;
      // identify_payload writes the active table at the run's end: a staging session's right.
      if (c == static_cast<std::uint16_t>(C::commit_table) || c == static_cast<std::uint16_t>(C::identify_payload)) {
        if (const E e = staging_rule(); e != E::none) return e;
      }
      if (c == static_cast<std::uint16_t>(C::start) || c == static_cast<std::uint16_t>(C::identify_payload) ||
          c == static_cast<std::uint16_t>(C::trace)) {
        if (playing) return E::server_device_busy;   // would jump the arm back to the start pose
        if (fault) return E::server_device_failure;  // only reset clears a fault
        const double f_f = mm::get_f32(h + mm::kOmegaFReg), fs = mm::get_f32(h + mm::kSampleRateReg);
        if (!(mm::run_samples(h[mm::kPeriodsReg], f_f, fs) <= mm::kMaxRunSamples))
          return E::illegal_data_value;  // the run would outlast the sample counter's resolution
        // A trace records the whole run: refused unless the ring holds every sample of it.
        if (c == static_cast<std::uint16_t>(C::trace) &&
            !(f_f > 0 && fs > 0 &&
              drive_.run_samples(h[mm::kPeriodsReg], 1.0 / f_f, fs) <= drive_.ring_capacity_samples()))
          return E::illegal_data_value;
        // The run starts with the monitor settings the registers hold, by the rule they were written by.
        if (!monitor_ok()) return E::illegal_data_value;
      }
    }
    if (overlaps(address, count, mm::kUnlockReg, 1)) {
      if (h[mm::kUnlockReg] != mm::kUnlockKey) return E::illegal_data_value;
      // One session at a time: another connection's open session is not taken over (it would
      // commit what that connection staged).
      if (session_held_by_another()) return E::server_device_busy;
    }
    // Staging, and the collision monitor's settings (a safety function's): the same rule.
    if (overlaps(address, count, mm::kStagingSizeReg, mm::kRingReg - mm::kStagingSizeReg)) {
      if (const E e = staging_rule(); e != E::none) return e;
    }
    if (overlaps(address, count, mm::kMonitorGainReg, mm::kMonitorBandReg + 2 * mm::kMaxJoints - mm::kMonitorGainReg) &&
        !monitor_ok())
      return E::illegal_data_value;
    if (overlaps(address, count, mm::kAckReg, 2)) {
      // The ring's samples are the run owner's to acknowledge: another connection's ack would free
      // samples the owner has not read, and end its stream with a gap it did not cause.
      if (owner_client_ != kNoClient && owner_client_ != current_client_) return E::server_device_busy;
      const std::uint32_t a = mm::get_u32(h + mm::kAckReg);
      if (a < drive_.acked() || a > drive_.produced()) return E::illegal_data_value;
    }
    const bool settings =
        overlaps(address, count, mm::kSampleRateReg, mm::kCoefficientsReg + mm::kCoefficientWords - mm::kSampleRateReg);
    if (settings && playing) return E::server_device_busy;
    if (overlaps(address, count, mm::kSampleRateReg, 2)) {
      const double fs = mm::get_f32(h + mm::kSampleRateReg);
      const double ratio = drive_.control_rate_hz() / fs;
      if (!(fs >= mm::kMinSampleRateHz && fs <= mm::kMaxSampleRateHz) || std::fabs(ratio - std::round(ratio)) > 1e-6)
        return E::illegal_data_value;
    }
    if (overlaps(address, count, mm::kOmegaFReg, 2)) {
      const double f = mm::get_f32(h + mm::kOmegaFReg);
      if (!(f > 0 && f <= mm::kMaxFundamentalHz)) return E::illegal_data_value;
    }
    if (overlaps(address, count, mm::kHarmonicsReg, 1) &&
        (h[mm::kHarmonicsReg] < 1 || h[mm::kHarmonicsReg] > mm::kMaxHarmonics))
      return E::illegal_data_value;
    if (overlaps(address, count, mm::kPeriodsReg, 1) &&
        (h[mm::kPeriodsReg] < 1 || h[mm::kPeriodsReg] > mm::kMaxPeriods))
      return E::illegal_data_value;
    // Every coefficient the write touches is finite (f32 elements: the write splits none).
    const int first = address > mm::kCoefficientsReg ? address : mm::kCoefficientsReg;
    const int end = address + count < mm::kCoefficientsReg + mm::kCoefficientWords
                        ? address + count
                        : mm::kCoefficientsReg + mm::kCoefficientWords;
    for (int a = first - (first - mm::kCoefficientsReg) % 2; a < end; a += 2) {
      if (!std::isfinite(mm::get_f32(h + a))) return E::illegal_data_value;
    }
    if (overlaps(address, count, mm::kStagingSizeReg, 1) && h[mm::kStagingSizeReg] > kTableMaxBytes)
      return E::illegal_data_value;
    return E::none;
  }

  void apply_write(int address, int count) noexcept {
    namespace mm = modbus_map;
    using detail::overlaps;
    std::uint16_t* h = holding_.data();
    if (overlaps(address, count, mm::kAckReg, 2)) drive_.ack(mm::get_u32(h + mm::kAckReg));
    if (overlaps(address, count, mm::kUnlockReg, 1)) {
      // A session starts empty: a commit writes only what its own connection staged.
      session_client_ = current_client_;
      session_until_ = now_ + static_cast<Microseconds>(mm::kSessionSeconds * 1e6);
      for (int a = mm::kStagingSizeReg; a < mm::kStagingTableReg + mm::kTableWords; ++a)
        holding_[static_cast<std::size_t>(a)] = 0;
    }
    if (!overlaps(address, count, mm::kCommandReg, 1)) return;
    const auto c = static_cast<mm::Command>(h[mm::kCommandReg]);
    switch (c) {
      case mm::Command::start:
      case mm::Command::trace:  // the same run: the rules made sure the ring holds all of it
      case mm::Command::identify_payload:
        // identify_payload ends with a table write: it takes the session's right with it.
        if (c == mm::Command::identify_payload) session_client_ = kNoClient;
        if (!drive_.start(c, run_from_registers(h), monitor_from_registers(h))) {
          served_.run_refused = true;
          break;
        }
        started_ = now_;
        owner_client_ = current_client_;
        owner_last_request_ = now_;
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
        mm::regs_to_bytes(h + mm::kStagingTableReg, size, staged_.data());
        served_.committed = true;
        served_.commit = drive_.commit(staged_.data(), size);
        input_[mm::kCommitResultReg] = static_cast<std::uint16_t>(served_.commit);
        ++input_[mm::kCommitCounterReg];
        break;
      }
      case mm::Command::none:
        break;
    }
    h[mm::kCommandReg] = 0;
  }

  Drive& drive_;
  std::array<std::uint16_t, modbus_map::kHoldingWords> holding_{};
  std::array<std::uint16_t, modbus_map::kInputWords> input_{};
  std::array<std::uint8_t, kTableMaxBytes> staged_{};  ///< the staged table's bytes at a commit
  int current_client_ = kNoClient;                     ///< the client whose request is being answered
  int session_client_ = kNoClient;                     ///< the client holding the staging session
  int owner_client_ = kNoClient;                       ///< the client that started the run (while connected)
  Microseconds now_ = 0;
  Microseconds session_until_ = 0;
  Microseconds owner_last_request_ = 0;
  Microseconds started_ = 0;
  ServedRequest served_{};
};

}  // namespace dyncal::drive
