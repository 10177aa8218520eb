// The drive's Modbus register map: the one definition used by the drive (simulated or firmware)
// and the host client. docs/modbus.md's table is printed from kRegisterMap (`dyncal registers`)
// and a test fails when the two differ.
#pragma once

#include <cstdint>

#include "dyncal/joint_capacity.hpp"
#include "dyncal/parameter_table.hpp"

namespace dyncal::modbus_map {

/// Register words are 16-bit. 32-bit values (u32, f32) take two consecutive registers, most
/// significant word first (big-endian words, "ABCD"; libmodbus modbus_get_float_abcd).
enum class Bank : std::uint8_t { input, holding };
enum class Type : std::uint8_t { u16, u32, f32, bytes };
enum class Access : std::uint8_t { read, read_write };

struct Field {
  const char* name;
  Bank bank;
  std::uint16_t address;
  std::uint16_t words;  ///< registers in all (count * words per element)
  Type type;
  const char* unit;
  const char* description;
};

inline constexpr int kMaxJoints = kMaxRobotJoints;  ///< the joint capacity (joint_capacity.hpp)
inline constexpr int kMaxHarmonics = 8;
/// 4: up to 7 joints (model error and coefficients sized for 7; ring samples packed for the
/// drive's num_joints, as many per block as fit). 5: the `unlock` register and the `reset`
/// command (access and state rules, docs/modbus.md "Access and states"). 7: the identify_payload
/// command and the payload registers (docs/payload.md "On the drive"). 8: the collision monitor
/// (fault 5 collision, monitor_state, the monitor_* holding registers; docs/monitor.md "On the
/// drive"). 9: the ring window moves to the holding registers, read with the acknowledgement in
/// one transaction (function 23); its header carries the drive's state and counters; samples
/// carry no seq (a block ends at a gap) and come in the drive's ring_format (counts: i32 encoder
/// counts and i16 torque counts, scaled by q_resolution and tau_resolution).
inline constexpr std::uint16_t kMapVersion = 10;

/// Key that, written to `unlock`, opens a staging session for the writing connection.
inline constexpr std::uint16_t kUnlockKey = 0xCA1B;
/// A staging session ends this long after the unlock [s], at the commit, or when its connection
/// closes, whichever comes first.
inline constexpr double kSessionSeconds = 10.0;

/// Longest run a drive plays, in samples. The sample counter is a u32 and the drive's time an f32,
/// whose 24-bit mantissa still resolves one sample period after 2^24 samples (4.66 h at 1 kHz); a
/// start command whose run would be longer is refused (illegal data value).
inline constexpr double kMaxRunSamples = 16777216.0;
/// Samples in a run of `periods` periods of a Fourier trajectory of fundamental frequency f_f [Hz]
/// sampled at fs [Hz] (Eq. 27: one period lasts 1 / f_f s).
constexpr double run_samples(double periods, double f_f, double fs) noexcept {
  return periods / f_f * fs;
}

/// Trajectory settings a drive accepts (holding registers sample_rate, omega_f, harmonics,
/// periods; docs/modbus.md "Exceptions").
inline constexpr double kMinSampleRateHz = 100.0;
inline constexpr double kMaxSampleRateHz = 1000.0;
inline constexpr double kMaxFundamentalHz = 10.0;
inline constexpr int kMaxPeriods = 100;

/// The trajectory setting a drive refuses first, or none.
enum class TrajectorySetting : std::uint8_t { none, sample_rate, omega_f, harmonics, periods, run_length };

/// Checks settings as the drive does: fs in [kMinSampleRateHz, kMaxSampleRateHz], f_f [Hz] in
/// (0, kMaxFundamentalHz], harmonics 1..kMaxHarmonics, periods 1..kMaxPeriods, and a run of at
/// most kMaxRunSamples. (The drive also requires fs to divide its control rate.)
constexpr TrajectorySetting refused_trajectory_setting(double fs, double f_f, int harmonics, int periods) noexcept {
  if (!(fs >= kMinSampleRateHz && fs <= kMaxSampleRateHz)) return TrajectorySetting::sample_rate;
  if (!(f_f > 0 && f_f <= kMaxFundamentalHz)) return TrajectorySetting::omega_f;
  if (harmonics < 1 || harmonics > kMaxHarmonics) return TrajectorySetting::harmonics;
  if (periods < 1 || periods > kMaxPeriods) return TrajectorySetting::periods;
  if (!(run_samples(periods, f_f, fs) <= kMaxRunSamples)) return TrajectorySetting::run_length;
  return TrajectorySetting::none;
}

/// Drive states (input register `state`). `fault`: the drive stopped the trajectory on a trip
/// (register `fault` says which); only the reset command clears it.
enum class DriveState : std::uint16_t { idle = 0, playing = 1, finished = 2, fault = 3 };

/// Why the drive tripped (input register `fault`). Every trip is judged on the measurements, as a
/// drive would, against the robot's own ratings (robot.json), not against tuned windows.
enum class DriveFault : std::uint16_t {
  none = 0,
  non_finite_state = 1,  ///< a measured q or qd is NaN or infinite (the plant diverged)
  position_limit = 2,    ///< measured q outside [q_min, q_max] of the joint (software limit)
  velocity_limit = 3,    ///< measured |qd| above qd_max of the joint (overspeed)
  /// No complete request from any client for the drive's watchdog time while playing: the host is
  /// gone, the trajectory stops (fault_joint 0, fault_value the silence in seconds).
  communication_lost = 4,
  /// The collision monitor's residual left its threshold (docs/monitor.md "On the drive"):
  /// fault_joint the joint furthest beyond it, fault_value its r - mean [Nm].
  collision = 5,
};

constexpr const char* to_string(DriveFault f) noexcept {
  switch (f) {
    case DriveFault::none:
      return "no fault";
    case DriveFault::non_finite_state:
      return "non-finite position or velocity";
    case DriveFault::position_limit:
      return "position limit";
    case DriveFault::velocity_limit:
      return "velocity limit";
    case DriveFault::communication_lost:
      return "communication lost";
    case DriveFault::collision:
      return "collision";
  }
  return "unknown fault";
}

/// Commands (holding register `command`). Any other value is answered with ILLEGAL DATA VALUE.
enum class Command : std::uint16_t {
  none = 0,
  start = 1,         ///< play the Fourier trajectory from its start; clears the ring and the statistics
  stop = 2,          ///< stop playing and hold the current position
  commit_table = 3,  ///< check the staging table and make it active (see docs/modbus.md)
  reset = 4,         ///< clear a fault: the drive becomes idle (no-op in any other state)
  /// play the trajectory from its start as `start`, identifying the payload on the last link with
  /// the active table fixed; at the run's end the active table takes it (docs/payload.md)
  identify_payload = 5,
  /// play the trajectory from its start as `start`, recording the whole run for upload (trace mode,
  /// docs/modbus.md "Trace"): refused with ILLEGAL DATA VALUE when the run records more samples than
  /// `ring_capacity`, so a traced run never drops one, however slowly the host reads
  trace = 6,
};

/// The drive's payload identification (input register `payload_state`).
enum class PayloadState : std::uint16_t {
  none = 0,     ///< no identify_payload since the drive started
  running = 1,  ///< the run plays (the estimate registers hold NaN until it ends)
  written = 2,  ///< the run ended, the mass was determined: the active table holds the loaded model
  /// the run ended without a determined positive mass, or was stopped or tripped: the table unchanged
  not_written = 3,
};

/// The longest velocity window of a drive's collision monitor: 2 * 64 + 1 control periods (lib/
/// centred_slope.hpp, D = round(1 / (K dt)) <= 64: K >= control_rate / 64.5).
inline constexpr int kMonitorMaxHalfWidth = 64;

/// The collision monitor of the run started last (input register `monitor_state`).
enum class MonitorState : std::uint16_t {
  off = 0,       ///< monitor_gain 0 when the run started
  watching = 1,  ///< the observer runs on the active table
  refused = 2,   ///< the observer cannot take the active table's model: the run is not watched
};

// --- input registers (function code 04), read-only
inline constexpr std::uint16_t kMapVersionReg = 0;        // u16
inline constexpr std::uint16_t kNumJointsReg = 1;         // u16
inline constexpr std::uint16_t kRobotIdReg = 2;           // u32
inline constexpr std::uint16_t kActiveModelIdReg = 4;     // u32
inline constexpr std::uint16_t kActiveCountReg = 6;       // u16
inline constexpr std::uint16_t kStateReg = 7;             // u16 DriveState
inline constexpr std::uint16_t kCommitResultReg = 8;      // u16 TableStatus of the last commit
inline constexpr std::uint16_t kCommitCounterReg = 9;     // u16, +1 per commit command
inline constexpr std::uint16_t kSimTimeReg = 10;          // f32
inline constexpr std::uint16_t kProducedReg = 12;         // u32 samples recorded so far (next seq)
inline constexpr std::uint16_t kOverrunReg = 14;          // u32 samples dropped (ring full)
inline constexpr std::uint16_t kActiveCrcReg = 16;        // u32 CRC-32 field of the active table
inline constexpr std::uint16_t kModelErrorReg = 18;       // f32[kMaxJoints]
inline constexpr std::uint16_t kActiveTableSizeReg = 32;  // u16 bytes
inline constexpr std::uint16_t kActiveTableReg = 33;      // bytes, kTableMaxBytes
inline constexpr std::uint16_t kTableWords = kTableMaxBytes / 2;
inline constexpr std::uint16_t kFaultReg = 460;        // u16 DriveFault
inline constexpr std::uint16_t kFaultJointReg = 461;   // u16 1-based joint that tripped, 0: none
inline constexpr std::uint16_t kFaultValueReg = 462;   // f32 the measured q [rad] or qd [rad/s] at the trip
inline constexpr std::uint16_t kControlRateReg = 464;  // f32 [Hz] the control loop's rate
inline constexpr std::uint16_t kGainKpReg = 466;       // f32[kMaxJoints] PD position gains of the last start
inline constexpr std::uint16_t kGainKdReg = 480;       // f32[kMaxJoints] PD velocity gains of the last start
/// How the ring window packs a sample (input register `ring_format`).
enum class RingFormat : std::uint16_t {
  /// f32 q[N] [rad], qd[N] [rad/s], tau[N] [Nm]: 6 N registers per sample
  float32 = 0,
  /// i32 q[N] in encoder counts (q = count x q_resolution), i16 tau[N] (tau = count x tau_resolution,
  /// saturated at +-kTauFullScale), velocity left to the host: 3 N registers
  counts = 1,
};
/// Full scale of a tau count (format counts): a torque at or beyond it reads +-kTauFullScale.
inline constexpr std::int16_t kTauFullScale = 32767;
/// q count meaning "no finite position" (format counts).
inline constexpr std::int32_t kQInvalid = -2147483647 - 1;
inline constexpr std::uint16_t kRingFormatReg = 500;     // u16 RingFormat
inline constexpr std::uint16_t kQResolutionReg = 501;    // f32[kMaxJoints] rad per position count
inline constexpr std::uint16_t kTauResolutionReg = 515;  // f32[kMaxJoints] Nm per torque count
inline constexpr std::uint16_t kRingCapacityReg = kTauResolutionReg + 2 * kMaxJoints;  // u32 samples the ring holds
/// Registers of one ring sample of a drive with `joints` joints in `format`.
constexpr int sample_words(int joints, RingFormat format) noexcept {
  return format == RingFormat::counts ? 3 * joints : 6 * joints;
}
inline constexpr std::uint16_t kPayloadStateReg = 623;                  // u16 PayloadState
inline constexpr std::uint16_t kPayloadReg = kPayloadStateReg + 1;      // f32[10] XX..M, NaN: not determined
inline constexpr std::uint16_t kPayloadStdReg = kPayloadReg + 20;       // f32[10] their std
inline constexpr std::uint16_t kMonitorStateReg = kPayloadStdReg + 20;  // u16 MonitorState
inline constexpr std::uint16_t kInputWords = kMonitorStateReg + 1;

// --- holding registers (function codes 03, 06, 16, 23)
inline constexpr std::uint16_t kCommandReg = 0;        // u16 Command
inline constexpr std::uint16_t kUnlockReg = 1;         // u16 kUnlockKey opens a staging session
inline constexpr std::uint16_t kAckReg = 2;            // u32 host consumed all samples with seq < ack
inline constexpr std::uint16_t kSampleRateReg = 4;     // f32 [Hz], 100..1000, divides 1000
inline constexpr std::uint16_t kOmegaFReg = 6;         // f32 [Hz] fundamental frequency, (0, 10]
inline constexpr std::uint16_t kHarmonicsReg = 8;      // u16 L, 1..kMaxHarmonics
inline constexpr std::uint16_t kPeriodsReg = 9;        // u16 periods to play, 1..100
inline constexpr std::uint16_t kCoefficientsReg = 10;  // f32[kMaxJoints][1 + 2 * 8]: q0, a_1..a_8, b_1..b_8
inline constexpr int kCoefficientsPerJoint = 1 + 2 * kMaxHarmonics;
inline constexpr std::uint16_t kCoefficientWords = 2 * kMaxJoints * kCoefficientsPerJoint;
inline constexpr std::uint16_t kStagingSizeReg = 300;                             // u16 bytes of the staged table
inline constexpr std::uint16_t kStagingTableReg = 301;                            // bytes, kTableMaxBytes
inline constexpr std::uint16_t kMonitorGainReg = kStagingTableReg + kTableWords;  // f32 K [1/s], 0: off
inline constexpr std::uint16_t kMonitorThresholdReg = kMonitorGainReg + 2;        // f32[kMaxJoints] [Nm]
inline constexpr std::uint16_t kMonitorMeanReg = kMonitorThresholdReg + 2 * kMaxJoints;  // f32[kMaxJoints] [Nm]
inline constexpr std::uint16_t kMonitorBandReg = kMonitorMeanReg + 2 * kMaxJoints;       // f32[kMaxJoints] [rad/s]
/// The ring window (read-only): the oldest unacknowledged consecutive samples. Header: u32 first
/// seq, u16 count n, u16 state (DriveState), u32 produced, u32 overruns (the drive's counters at
/// the same instant as the samples); then n samples. Read it with function 23, writing `ack` in the
/// same transaction: the write is applied first, so the window shows the samples after it.
inline constexpr std::uint16_t kRingReg = kMonitorBandReg + 2 * kMaxJoints;
inline constexpr std::uint16_t kRingWords = 125;  // one read of at most 125 registers
inline constexpr int kRingHeaderWords = 8;
/// Samples per ring block for `joints` joints in `format` (float32: 1 joint 19, 3: 6, 6: 3, 7: 2;
/// counts: 1 joint 39, 3: 13, 6: 6, 7: 5).
constexpr int samples_per_block(int joints, RingFormat format) noexcept {
  return (kRingWords - kRingHeaderWords) / sample_words(joints, format);
}
/// The most samples any block carries (one joint, format counts).
inline constexpr int kMaxSamplesPerBlock = samples_per_block(1, RingFormat::counts);
inline constexpr std::uint16_t kHoldingWords = kRingReg + kRingWords;

static_assert(kCoefficientsReg + kCoefficientWords <= kStagingSizeReg, "holding fields overlap");
static_assert(kModelErrorReg + 2 * kMaxJoints <= kActiveTableSizeReg, "input fields overlap");
static_assert(kActiveTableReg + kTableWords <= kFaultReg, "input fields overlap");
static_assert(kFaultValueReg + 2 <= kControlRateReg, "input fields overlap");
static_assert(kControlRateReg + 2 <= kGainKpReg && kGainKpReg + 2 * kMaxJoints <= kGainKdReg, "input fields overlap");
static_assert(kGainKdReg + 2 * kMaxJoints <= kRingFormatReg, "input fields overlap");
static_assert(kRingCapacityReg + 2 <= kPayloadStateReg, "input fields overlap");
static_assert(kRingWords <= 125, "one ring block must fit one Modbus read");
static_assert(samples_per_block(kMaxJoints, RingFormat::float32) >= 2, "a block carries at least two samples");

inline constexpr Field kRegisterMap[] = {
    {"map_version", Bank::input, kMapVersionReg, 1, Type::u16, "-", "register map version (10)"},
    {"num_joints", Bank::input, kNumJointsReg, 1, Type::u16, "-", "joints of the arm"},
    {"robot_id", Bank::input, kRobotIdReg, 2, Type::u32, "-", "generated kRobotId of the drive's robot"},
    {"active_model_id", Bank::input, kActiveModelIdReg, 2, Type::u32, "-", "model id of the active table"},
    {"active_count", Bank::input, kActiveCountReg, 1, Type::u16, "-", "parameters in the active table"},
    {"state", Bank::input, kStateReg, 1, Type::u16, "-", "0 idle, 1 playing, 2 finished, 3 fault"},
    {"commit_result", Bank::input, kCommitResultReg, 1, Type::u16, "-", "TableStatus of the last commit (0 ok)"},
    {"commit_counter", Bank::input, kCommitCounterReg, 1, Type::u16, "-", "incremented when a commit completes"},
    {"sim_time", Bank::input, kSimTimeReg, 2, Type::f32, "s", "drive time since the trajectory started"},
    {"produced", Bank::input, kProducedReg, 2, Type::u32, "-", "samples recorded since start (next seq)"},
    {"overruns", Bank::input, kOverrunReg, 2, Type::u32, "-", "samples dropped because the ring was full"},
    {"active_crc", Bank::input, kActiveCrcReg, 2, Type::u32, "-", "CRC-32 field of the active table"},
    {"model_error_rms", Bank::input, kModelErrorReg, 2 * kMaxJoints, Type::f32, "Nm",
     "per joint: RMS of tau - tau_ff (drive's model error) since start"},
    {"active_table_size", Bank::input, kActiveTableSizeReg, 1, Type::u16, "bytes", "size of the active table"},
    {"active_table", Bank::input, kActiveTableReg, kTableWords, Type::bytes, "-",
     "active parameter table, 2 bytes per register (first byte high)"},
    {"fault", Bank::input, kFaultReg, 1, Type::u16, "-",
     "why the drive stopped: 0 none, 1 non-finite q or qd, 2 position limit, 3 velocity limit, 4 communication "
     "lost, 5 collision"},
    {"fault_joint", Bank::input, kFaultJointReg, 1, Type::u16, "-", "joint that tripped (1-based; 0 none)"},
    {"fault_value", Bank::input, kFaultValueReg, 2, Type::f32, "rad, rad/s, s, Nm",
     "the measured q (position limit) or qd (velocity limit) of that joint at the trip; the silence "
     "(communication lost); the observer's r - mean (collision)"},
    {"control_rate", Bank::input, kControlRateReg, 2, Type::f32, "Hz",
     "rate of the control loop (PD plus feed-forward) and of its zero-order hold"},
    {"gain_kp", Bank::input, kGainKpReg, 2 * kMaxJoints, Type::f32, "Nm/rad",
     "per joint: PD position gain of the run started last (set at start; 0 before the first)"},
    {"gain_kd", Bank::input, kGainKdReg, 2 * kMaxJoints, Type::f32, "Nm s/rad",
     "per joint: PD velocity gain (on the backward-difference velocity) of the run started last"},
    {"ring_format", Bank::input, kRingFormatReg, 1, Type::u16, "-",
     "how the ring window packs a sample: 0 float32 (f32 q, qd, tau), 1 counts (i32 q counts, i16 tau counts)"},
    {"q_resolution", Bank::input, kQResolutionReg, 2 * kMaxJoints, Type::f32, "rad",
     "per joint: the position of one count (format counts; the encoder's resolution on the joint side)"},
    {"tau_resolution", Bank::input, kTauResolutionReg, 2 * kMaxJoints, Type::f32, "Nm",
     "per joint: the torque of one count (format counts; full scale +-32767 counts, saturated there)"},
    {"ring_capacity", Bank::input, kRingCapacityReg, 2, Type::u32, "samples",
     "samples the ring holds: a run of at most this many is recorded whole however slowly it is read (trace)"},
    {"payload_state", Bank::input, kPayloadStateReg, 1, Type::u16, "-",
     "payload identification: 0 none, 1 running, 2 written into the active table, 3 not written"},
    {"payload", Bank::input, kPayloadReg, 20, Type::f32, "kg m^2, kg m, kg",
     "the last link's payload, standard parameters XX XY XZ YY YZ ZZ MX MY MZ M (link frame, about its "
     "origin); NaN where the run does not determine it"},
    {"payload_std", Bank::input, kPayloadStdReg, 20, Type::f32, "as payload",
     "standard deviation of each payload parameter (NaN where not determined)"},
    {"monitor_state", Bank::input, kMonitorStateReg, 1, Type::u16, "-",
     "collision monitor of the run started last: 0 off, 1 watching, 2 refused (the observer cannot take the "
     "active table)"},
    {"command", Bank::holding, kCommandReg, 1, Type::u16, "-",
     "1 start, 2 stop, 3 commit table, 4 reset a fault, 5 start and identify the payload, 6 start and "
     "record the whole run (trace; refused beyond ring_capacity); reads 0"},
    {"unlock", Bank::holding, kUnlockReg, 1, Type::u16, "-",
     "0xCA1B opens a staging session for this connection (10 s, until commit or disconnect); reads 0"},
    {"ack", Bank::holding, kAckReg, 2, Type::u32, "-", "samples with seq < ack are consumed and freed"},
    {"sample_rate", Bank::holding, kSampleRateReg, 2, Type::f32, "Hz", "recording rate, 100..1000, divides 1000"},
    {"omega_f", Bank::holding, kOmegaFReg, 2, Type::f32, "Hz", "Fourier fundamental frequency (Eq. 27), (0, 10]"},
    {"harmonics", Bank::holding, kHarmonicsReg, 1, Type::u16, "-", "L, number of harmonics, 1..8"},
    {"periods", Bank::holding, kPeriodsReg, 1, Type::u16, "-", "trajectory periods to play, 1..100"},
    {"coefficients", Bank::holding, kCoefficientsReg, kCoefficientWords, Type::f32, "rad, rad/s",
     "per joint: q0, a_1..a_8, b_1..b_8 of Eq. 27 (17 f32 per joint)"},
    {"staging_size", Bank::holding, kStagingSizeReg, 1, Type::u16, "bytes", "size of the staged table"},
    {"staging_table", Bank::holding, kStagingTableReg, kTableWords, Type::bytes, "-",
     "staging bank for the next table, 2 bytes per register (first byte high)"},
    {"monitor_gain", Bank::holding, kMonitorGainReg, 2, Type::f32, "1/s",
     "collision monitor: observer gain K, K / control_rate <= 1; 0 off (taken at the next start)"},
    {"monitor_threshold", Bank::holding, kMonitorThresholdReg, 2 * kMaxJoints, Type::f32, "Nm",
     "per joint: alarm when |r - mean| exceeds it (plus the table's |Fc| while the joint rests); 0 not watched"},
    {"monitor_mean", Bank::holding, kMonitorMeanReg, 2 * kMaxJoints, Type::f32, "Nm",
     "per joint: the residual's mean on contact-free motion"},
    {"monitor_band", Bank::holding, kMonitorBandReg, 2 * kMaxJoints, Type::f32, "rad/s",
     "per joint: friction standstill band (|qd| below it: no friction velocity)"},
    {"ring", Bank::holding, kRingReg, kRingWords, Type::bytes, "-",
     "read-only: u32 first seq, u16 count n, u16 state, u32 produced, u32 overruns, then n consecutive "
     "samples of N = num_joints in ring_format (float32: 6 N registers, counts: 3 N); read with function 23 "
     "writing ack"},
};

/// A holding field no write may touch (the ring window).
constexpr bool read_only_holding(const Field& f) noexcept {
  return f.bank == Bank::holding && f.address == kRingReg;
}

/// The field that contains register `address` of `bank`, or nullptr (an illegal address).
inline const Field* find_field(Bank bank, int address) noexcept {
  for (const Field& f : kRegisterMap) {
    if (f.bank == bank && address >= f.address && address < f.address + f.words) return &f;
  }
  return nullptr;
}

inline std::uint32_t get_u32(const std::uint16_t* regs) noexcept {
  return (static_cast<std::uint32_t>(regs[0]) << 16) | regs[1];
}
inline void set_u32(std::uint16_t* regs, std::uint32_t v) noexcept {
  regs[0] = static_cast<std::uint16_t>(v >> 16);
  regs[1] = static_cast<std::uint16_t>(v);
}
inline float get_f32(const std::uint16_t* regs) noexcept {
  const std::uint32_t u = get_u32(regs);
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}
inline void set_f32(std::uint16_t* regs, float f) noexcept {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  set_u32(regs, u);
}
/// Bytes <-> registers: byte 2k is the high half of register k.
inline void bytes_to_regs(const std::uint8_t* bytes, int size, std::uint16_t* regs) noexcept {
  for (int k = 0; k < (size + 1) / 2; ++k) {
    const std::uint8_t lo = 2 * k + 1 < size ? bytes[2 * k + 1] : 0;
    regs[k] = static_cast<std::uint16_t>((bytes[2 * k] << 8) | lo);
  }
}
inline void regs_to_bytes(const std::uint16_t* regs, int size, std::uint8_t* bytes) noexcept {
  for (int i = 0; i < size; ++i) {
    bytes[i] = static_cast<std::uint8_t>(i % 2 == 0 ? regs[i / 2] >> 8 : regs[i / 2] & 0xFF);
  }
}

}  // namespace dyncal::modbus_map
