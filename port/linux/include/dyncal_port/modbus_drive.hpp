#pragma once
// port/linux: a drive reached over Modbus (libmodbus client), TCP or RTU. Implements the lib/
// port surface (dyncal/port.hpp): sample source (the drive's ring buffer, in order, each sample
// once), parameter store (staging bank + commit + read-back) and a monotonic clock.

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include "dyncal/drive/ring_window.hpp"
#include "dyncal/fourier_trajectory.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/port.hpp"

typedef struct _modbus modbus_t;

namespace dyncal::linux_port {

using Trajectory = FourierTrajectory<double, modbus_map::kMaxJoints, modbus_map::kMaxHarmonics>;

struct DriveInfo {
  int map_version = 0;
  int num_joints = 0;
  std::uint32_t robot_id = 0;
  std::uint32_t active_model_id = 0;
  int active_count = 0;
  modbus_map::DriveState state = modbus_map::DriveState::idle;
  double sim_time = 0;
  std::uint32_t produced = 0;
  std::uint32_t overruns = 0;
  std::array<double, modbus_map::kMaxJoints> model_error_rms{};
  modbus_map::DriveFault fault = modbus_map::DriveFault::none;  ///< why it stopped (read only in state fault)
  int fault_joint = 0;                                          ///< 1-based; 0 none
  double fault_value = 0;  ///< measured q [rad] or qd [rad/s] of that joint at the trip
};

/// The drive's control law of the run it started last (registers control_rate, gain_kp, gain_kd):
/// PD on the encoder position and its backward difference plus the active table's feed-forward,
/// what IDIM-IV simulates (identify --method iv --law).
struct DriveControlLaw {
  double control_rate_hz = 0;                       ///< [Hz]
  std::array<double, modbus_map::kMaxJoints> kp{};  ///< [Nm/rad], num_joints used; 0 before any start
  std::array<double, modbus_map::kMaxJoints> kd{};  ///< [Nm s/rad]
};

/// The drive's payload identification (registers payload_state, payload, payload_std).
struct DrivePayload {
  modbus_map::PayloadState state = modbus_map::PayloadState::none;
  /// The last link's payload [XX XY XZ YY YZ ZZ (kg m^2) MX MY MZ (kg m) M (kg)], link frame, about
  /// its origin; NaN where the run does not determine it.
  std::array<double, 10> value{};
  std::array<double, 10> std{};
};

/// The drive's collision monitor (registers monitor_gain .. monitor_band; docs/modbus.md
/// "Collision monitor"): observer gain K [1/s] (0: off) and per joint (num_joints used) the
/// threshold on |r - mean| [Nm] (0: not watched), the residual's mean [Nm] and the friction terms'
/// standstill band [rad/s].
struct DriveMonitor {
  double gain = 0;
  std::array<double, modbus_map::kMaxJoints> threshold{}, mean{}, band{};
};

/// The drive's fault in words: "joint 2 velocity limit: qd = 3.51 rad/s at t = 1.234 s".
std::string describe_fault(const DriveInfo& info);

/// Every call returns a port::PortStatus and, unless ok, leaves the reason in error(). As libmodbus
/// documents each call, the "Errors" line says which statuses a call returns: transport_error when
/// the request or its answer failed (time-out, broken link, bad frame; libmodbus's text in error()),
/// rejected when the drive answered with a Modbus exception (illegal address or value, device
/// failure; error() names it) or refused a table (the TableStatus in *reason).
class ModbusDrive final : public port::SampleSource, public port::ParameterStore, public port::Clock {
 public:
  /// Connects to `uri`: tcp://HOST:PORT or rtu:DEVICE (115200 8N1, slave 1), response time-out 2 s.
  /// Errors: nullptr, with the reason in *error (malformed URI, no context, connection refused).
  static std::unique_ptr<ModbusDrive> connect(const std::string& uri, std::string* error);
  ~ModbusDrive();
  ModbusDrive(const ModbusDrive&) = delete;
  ModbusDrive& operator=(const ModbusDrive&) = delete;

  /// Last failure in words (libmodbus's text, or the drive's exception).
  const std::string& error() const { return error_; }

  /// Reads the drive's identity, state and counters (input registers 0..31; the fault registers too
  /// when the state is fault). Errors: transport_error, rejected (also when the drive's register map
  /// version is not modbus_map::kMapVersion: error() names both versions, or the joint count is not
  /// 1..kMaxJoints).
  port::PortStatus read_info(DriveInfo& info);
  /// Reads the control law of the run the drive started last (input registers 464..493).
  /// Errors: transport_error, rejected.
  port::PortStatus read_control_law(DriveControlLaw& law);
  /// Writes the trajectory (Eq. 27 coefficients), periods and sample rate; the drive must be idle.
  /// Errors: transport_error, rejected (a value outside the register's range, or a run longer than
  /// modbus_map::kMaxRunSamples: checked before sending, error() names the value; docs/modbus.md).
  port::PortStatus write_trajectory(const Trajectory& trajectory, int periods, double sample_rate_hz);
  /// Starts the written trajectory from its beginning (clears the ring and the statistics).
  /// Errors: transport_error, rejected (the drive is playing already, or in fault: reset() first).
  port::PortStatus start();
  /// Starts the written trajectory as start() does, recording the whole run for upload (trace mode,
  /// docs/modbus.md "Trace"): the drive keeps every sample until read() has received it, however
  /// slowly the link carries them. Errors: transport_error, rejected (playing, in fault, or a run
  /// of more samples than ring_capacity(): the drive refuses to start it).
  port::PortStatus trace();
  /// Starts the written trajectory as start() does and has the drive identify the payload on the
  /// last link while it plays (opens a staging session first: the drive writes the loaded model
  /// into its active table at the run's end; docs/payload.md "On the drive"). Errors:
  /// transport_error, rejected (playing, in fault, or the run too long).
  port::PortStatus identify_payload();
  /// Reads the payload registers. Errors: transport_error, rejected.
  port::PortStatus read_payload(DrivePayload& payload);
  /// Writes the collision monitor's settings (opens a staging session first: a safety function's
  /// settings are written as a table is); the drive takes them at its next start. Errors:
  /// transport_error, rejected (playing, in fault, or a value the drive refuses: a gain outside
  /// [control rate / 64.5, control rate], a negative or non-finite threshold or band).
  port::PortStatus write_monitor(const DriveMonitor& monitor);
  /// Reads monitor_state: the collision monitor of the run started last. Errors: transport_error, rejected.
  port::PortStatus read_monitor_state(modbus_map::MonitorState& state);
  /// Clears a drive fault (the only way to): the drive becomes idle. A no-op in any other state.
  /// Errors: transport_error, rejected.
  port::PortStatus reset();
  /// Stops playing; the drive holds its position. Errors: transport_error, rejected.
  port::PortStatus stop();

  // port::SampleSource
  /// One function 23 transaction per call: it acknowledges the samples the previous call returned
  /// and reads the ring window after that (docs/modbus.md "Measurement stream"). Samples carry the
  /// drive's num_joints joints (the rest of each DriveSample is zero); the first call reads the
  /// joint count and the ring format. In format counts, q and tau are decoded with the drive's
  /// resolutions, qd is NaN (the host differentiates), an invalid q is NaN, and a torque at the
  /// stream's full scale (saturated: its true value may lie beyond) is counted in saturated(). While the run plays and
  /// the drive holds less than a block past the samples returned (by the window header's produced counter), the next
  /// call first waits until the rest of a block is due, plus half a sample period (at most 50 ms), instead of asking
  /// again at once. A block that starts past a gap (samples dropped by a full ring) is delivered with status
  /// sequence_gap; every gap is checked against the drive's own overrun counter, which the window's header carries.
  /// Errors: transport_error, rejected (read_info's; also a gap the drive's overrun counter does not
  /// account for, or a window that repeats received samples: replies out of step with requests);
  /// sequence_gap when samples were lost (lost() counts them); device_fault once every sample
  /// recorded before a drive fault has been read (error() then describes the fault).
  port::PortStatus read(port::DriveSample* out, int capacity, int* count) noexcept override;
  /// Samples the drive dropped in this run, by its own overrun counter as read at the last gap
  /// (0 while no sample is missing).
  std::uint32_t lost() const { return drive_overruns_; }
  /// Per joint (0-based), the samples of this run whose torque read the stream's full scale
  /// (format counts: +-32767 counts, 2 tau_max on the simulated drive): saturated, not measured.
  const std::array<long, modbus_map::kMaxJoints>& saturated() const { return saturated_; }
  /// The stream's cost on the link since connect (the ring transactions of read() and measure_link()).
  struct LinkStats {
    long transactions = 0;  ///< function 23 transactions (one per block)
    long bytes = 0;    ///< bytes of those transactions on the wire, both ways (TCP: MBAP headers; RTU: address, CRC)
    long samples = 0;  ///< samples read() delivered
  };
  const LinkStats& link_stats() const { return link_; }
  /// How the drive packs a sample, and the samples its ring holds (known after the first read() or
  /// measure_link()).
  modbus_map::RingFormat ring_format() const { return format_; }
  long ring_capacity() const { return ring_capacity_; }
  /// Samples one read() delivers at most (joints and format as above).
  int samples_per_block() const { return modbus_map::samples_per_block(joints_, format_); }
  /// Times `transactions` (>= 1) ring transactions, the stream's own (a function 23 that writes
  /// the acknowledgement the drive holds again: it frees nothing), and stores the mean wall time of one in *seconds
  /// [s]: with samples_per_block(), what the link carries live. Reads the stream's format first. Call it between runs.
  /// Errors: transport_error, rejected (as read()).
  port::PortStatus measure_link(int transactions, double* seconds);
  /// The transport's name: "TCP" or "RTU".
  const char* transport() const { return rtu_ ? "RTU" : "TCP"; }

  // port::ParameterStore
  /// Opens a staging session (writes modbus_map::kUnlockKey to `unlock`), stages, commits and reads
  /// the table back byte for byte. Polls the drive's commit counter
  /// (every 1 ms) until it moves, at most commit_timeout_s (set_commit_timeout). Errors: rejected
  /// with *reason (the table cannot be encoded, or the drive refused it: its active table is
  /// unchanged); transport_error (link failure, the read-back differs from what was sent, or the
  /// drive did not finish the commit within the deadline: error() says so, the table's fate is
  /// then unknown until read back).
  port::PortStatus write(const ParameterTable& table, TableStatus* reason) noexcept override;
  /// The active table, decoded and CRC-checked. Errors: transport_error; rejected with *reason.
  port::PortStatus read(ParameterTable& table, TableStatus* reason) noexcept override;
  /// Raw bytes of the active table (for comparison with what was sent). Errors: transport_error
  /// (also when the table is larger than `capacity`), rejected.
  port::PortStatus read_active_bytes(std::uint8_t* bytes, int capacity, int* size);

  /// Deadline for a commit (default 10 s; a flash of the largest table takes milliseconds).
  /// Values <= 0 or non-finite are ignored.
  void set_commit_timeout(double seconds) {
    if (seconds > 0 && seconds < 1e6) commit_timeout_s_ = seconds;
  }
  double commit_timeout() const { return commit_timeout_s_; }

  // port::Clock
  std::uint64_t now_us() noexcept override;

  /// Low-level register access (tests). Errors: transport_error, rejected (Modbus exception).
  port::PortStatus read_input(int address, int count, std::uint16_t* regs);
  port::PortStatus read_holding(int address, int count, std::uint16_t* regs);
  port::PortStatus write_holding(int address, int count, const std::uint16_t* regs);

 private:
  ModbusDrive(modbus_t* ctx, bool rtu) : ctx_(ctx), rtu_(rtu) {}
  /// error() from errno; rejected for a Modbus exception, transport_error otherwise.
  port::PortStatus fail(const char* what);
  /// A new run's stream: seq from 0, no loss, no saturation, no pacing (start, identify_payload).
  void begin_run();
  /// Reads the joint count (read_info), ring_format, q_resolution, tau_resolution and
  /// ring_capacity, once per connection (a no-op once they are known).
  port::PortStatus read_stream_format();
  /// After the samples jumped from seq `from` to `to`: sequence_gap if the drive's overrun counter
  /// `overruns` accounts for every sample missing so far (drive_overruns_ takes it), else
  /// transport_error.
  port::PortStatus confirm_loss(std::uint32_t from, std::uint32_t to, std::uint32_t overruns);
  /// One ring transaction: the function 23 request (PDU 10 + 4 bytes for the two ack registers)
  /// and its reply (PDU 2 + 2 kRingWords) in their frames: TCP adds a 7-byte MBAP header to each,
  /// RTU an address byte and a 2-byte CRC (its 3.5-character silences carry no byte).
  static constexpr long kPduBytes = (10 + 4) + (2 + 2 * modbus_map::kRingWords);
  static constexpr long kTcpTransactionBytes = kPduBytes + 2 * 7;
  static constexpr long kRtuTransactionBytes = kPduBytes + 2 * 3;
  /// One ring transaction: writes `ack_seq` to ack and reads the window into w (kRingWords);
  /// counted in link_.
  port::PortStatus ring_transaction(std::uint32_t ack_seq, std::uint16_t* w);
  modbus_t* ctx_;
  bool rtu_ = false;
  long ring_capacity_ = 0;  ///< the drive's ring_capacity register (read_stream_format)
  std::string error_;
  std::uint32_t next_seq_ = 0;
  std::uint32_t lost_ = 0;            ///< samples missing from the seq received in this run
  std::uint32_t drive_overruns_ = 0;  ///< the drive's overrun counter at the last gap
  bool stream_format_known_ = false;  ///< read_stream_format has run (once per connection)
  modbus_map::RingFormat format_ = modbus_map::RingFormat::float32;
  drive::RingResolution resolution_{};  ///< format counts: the drive's q and tau per count
  double sample_rate_hz_ = 0;           ///< of the trajectory written last (paces read())
  std::array<long, modbus_map::kMaxJoints> saturated_{};
  std::chrono::steady_clock::time_point pace_until_{};
  LinkStats link_;
  int joints_ = 0;  ///< the drive's num_joints (read_info), 0 until known
  double commit_timeout_s_ = 10.0;
};

}  // namespace dyncal::linux_port
