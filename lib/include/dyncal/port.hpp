// The port surface: what lib/ code needs from a platform (time, a sample source, a parameter
// store). Implemented per target: port/linux (Modbus client of a drive), port/cortex_m (firmware).
#pragma once

#include <cstdint>

#include "dyncal/joint_capacity.hpp"
#include "dyncal/parameter_table.hpp"

namespace dyncal::port {

inline constexpr int kMaxJoints = kMaxRobotJoints;  ///< the joint capacity (joint_capacity.hpp)

/// One sample as a drive records it, joint side: q [rad], qd [rad/s], tau [Nm] (motor torque
/// reflected to the joint), float32 as on the wire. `seq` counts samples from the trajectory start.
struct DriveSample {
  std::uint32_t seq;
  float q[kMaxJoints];
  float qd[kMaxJoints];
  float tau[kMaxJoints];
};

enum class PortStatus : std::uint8_t {
  ok = 0,
  no_data,          ///< nothing yet; try again
  end_of_stream,    ///< the source finished and every sample has been delivered
  transport_error,  ///< the link failed (details from the port's own error text)
  sequence_gap,     ///< samples were lost (drive overrun): the block starts after a gap
  rejected,         ///< the other side refused the request (e.g. a table failed its checks)
  device_fault,     ///< the source stopped on a fault after its last sample (details from the port)
};

constexpr const char* to_string(PortStatus s) noexcept {
  switch (s) {
    case PortStatus::ok:
      return "ok";
    case PortStatus::no_data:
      return "no data";
    case PortStatus::end_of_stream:
      return "end of stream";
    case PortStatus::transport_error:
      return "transport error";
    case PortStatus::sequence_gap:
      return "sequence gap: samples lost";
    case PortStatus::rejected:
      return "rejected";
    case PortStatus::device_fault:
      return "device fault";
  }
  return "unknown";
}

/// Delivers samples in order, each exactly once.
class SampleSource {
 public:
  /// Copies up to `capacity` unread samples into `out`, sets *count. ok with *count > 0, no_data,
  /// end_of_stream, sequence_gap (the samples returned follow a gap; the gap size is the jump in
  /// seq), device_fault (every sample recorded before the fault has been delivered; no more will
  /// come) or transport_error.
  virtual PortStatus read(DriveSample* out, int capacity, int* count) noexcept = 0;

 protected:
  ~SampleSource() = default;
};

/// Holds the drive's active parameter table.
class ParameterStore {
 public:
  /// Stages and commits `table`. ok when the drive made it active; rejected with *reason set when
  /// the drive refused it (the active table is unchanged); transport_error otherwise.
  virtual PortStatus write(const ParameterTable& table, TableStatus* reason) noexcept = 0;
  /// Reads the active table back (decoded and CRC-checked; *reason says why if not ok).
  virtual PortStatus read(ParameterTable& table, TableStatus* reason) noexcept = 0;

 protected:
  ~ParameterStore() = default;
};

/// The arm's joints as the drive application drives them (dyncal/drive/drive_application.hpp),
/// joint side, SI units, joint 1 first, the robot's joints only: one control period is sense(),
/// then actuate(). A drive maker implements it over its encoders and current loop; the drive
/// image implements it with a simulated arm.
template <typename Scalar>
class Joints {
 public:
  /// Brings the arm to the run's first state, q [rad or m] moving at qd [rad/s or m/s], before the
  /// run's first period (a real drive plays its own move there; a simulated arm is put there).
  virtual void place(const Scalar* q, const Scalar* qd) noexcept = 0;
  /// The measured positions [rad or m] at the period's start (the encoders).
  virtual void sense(Scalar* q) noexcept = 0;
  /// Applies the torque command [Nm or N] for one control period and gives the torque the drive
  /// measured with it (its current sensor times the torque constant, or a torque sensor).
  virtual void actuate(const Scalar* tau_command, Scalar* tau_measured) noexcept = 0;

 protected:
  ~Joints() = default;
};

/// Monotonic time.
class Clock {
 public:
  virtual std::uint64_t now_us() noexcept = 0;

 protected:
  ~Clock() = default;
};

}  // namespace dyncal::port
