#pragma once
// The simulated drive of any compiled robot (1 to 7 joints) without its transport: plant (forward dynamics of the
// generated model, RK4), control law (PD + inverse-dynamics feed-forward from the active parameter table, survey Fig.
// 3), friction and effects from the scenario, measurement (encoder quantisation, torque noise), recording into a ring
// buffer, and the parameter table (checked, persisted atomically).

#include <array>
#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "dyncal/drive/sample_ring.hpp"
#include "dyncal/fourier_trajectory.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/port.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/drive_plant.hpp"
#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

class SimulatedDrive {
 public:
  /// The largest ring buffer (samples); ring_capacity may make it smaller.
  static constexpr int kRingCapacity = 16384;

  /// `table_path`: the simulated flash. Its table becomes active if valid; otherwise (missing or
  /// invalid, reason in startup_note()) the factory table: nominal base parameters, no friction.
  SimulatedDrive(const RobotDescription& robot, const Scenario& scenario, std::string table_path);
  ~SimulatedDrive();

  std::uint32_t robot_id() const;
  int num_joints() const;
  /// Trajectory and recording settings; only while not playing.
  DriveTrajectory trajectory;
  int periods = 2;
  double sample_rate_hz = 1000;

  void start();
  /// start(), identifying the payload on the last link while the run plays (the active table fixed,
  /// the estimator of lib/ payload_estimator.hpp on every recorded sample). At the run's end, when
  /// the run determines a positive mass, the active table takes the payload (its determined
  /// parameters; the others held at 0) through commit(): payload_state() written; otherwise, or
  /// when the run is stopped or trips, not_written and the table unchanged (docs/payload.md "On
  /// the drive").
  void start_payload();
  modbus_map::PayloadState payload_state() const { return payload_state_; }
  /// The estimate when the run ended or was stopped (NaN while a payload run plays): values, NaN
  /// where the run does not determine the parameter (1.96 std beyond its scale, or the mass not
  /// determined), and std (lib/ drive/payload_run.hpp).
  const drive::PayloadVerdict& payload() const { return payload_verdict_; }
  void stop();
  /// Stops a playing trajectory with `fault` (no joint; `value` in its unit), as a trip does: the
  /// arm holds, no further sample is recorded. No-op unless playing.
  void trip(modbus_map::DriveFault fault, double value);
  /// Clears a fault: the drive becomes idle, holding its position. No-op in any other state.
  void reset();
  modbus_map::DriveState state() const { return state_; }
  /// Why the drive stopped (state() == fault; none otherwise): each control period, before the
  /// control law, the measured q and qd of every joint are checked — finite, q within [q_min,
  /// q_max], |qd| <= qd_max of the robot file — and the first break stops the trajectory: no more
  /// samples are recorded, the ring keeps those before it. reset() or start() clears the fault
  /// (the Modbus server refuses start in fault: there only the reset command clears it).
  modbus_map::DriveFault fault() const { return fault_; }
  /// The 1-based joint that tripped (0: none).
  int fault_joint() const { return fault_joint_; }
  /// Its measured q [rad] (position limit) or qd [rad/s] (velocity limit) at the trip; NaN for a
  /// non-finite state.
  double fault_value() const { return fault_value_; }
  /// Advances one control period (no-op unless playing).
  void step();
  double time() const { return time_; }
  double control_period() const { return 1.0 / scenario_.control_rate_hz; }
  /// Seconds of simulated time until the trajectory ends.
  double remaining() const;
  /// Samples a run of `run_periods` periods of `period_s` [s] at `sample_rate` [Hz] records (the
  /// scenario's rests included): what the ring must hold to record it whole (trace mode).
  long run_samples(double run_periods, double period_s, double sample_rate) const;

  /// Ring buffer: samples with seq >= acked() not yet freed, oldest first.
  const drive::SampleRing<kRingCapacity>& ring() const { return *ring_; }
  std::uint32_t acked() const { return acked_; }
  /// Frees samples with seq < seq_end (ignored if it would skip unrecorded samples).
  void ack(std::uint32_t seq_end);
  bool ring_full() const { return static_cast<int>(ring_->size()) >= ring_capacity; }
  /// Samples the ring holds, 1..kRingCapacity (a real drive's trace buffer is often far smaller;
  /// `dyncal drive --ring-samples`). Set while not playing.
  int ring_capacity = kRingCapacity;
  /// How the Modbus ring window packs a sample (docs/modbus.md "Measurement stream"). Set while not
  /// playing.
  modbus_map::RingFormat ring_format = modbus_map::RingFormat::counts;
  /// Joint j's (0-based) position per count of format counts [rad]: the encoder's quantum on the
  /// joint side, 2 pi / (encoder_counts |N_j|); 2 pi / (2^20 |N_j|) when the scenario does not
  /// quantise (encoder_counts 0).
  double q_resolution(int j) const { return q_resolution_[static_cast<std::size_t>(j)]; }
  /// Joint j's torque per count of format counts [Nm]: 2 tau_max_j / 32767 (full scale twice the
  /// joint's rated torque; 0 when the robot gives no tau_max). Resolution against the noise:
  /// docs/modbus.md.
  double tau_resolution(int j) const { return tau_resolution_[static_cast<std::size_t>(j)]; }
  /// ring_format, or float32 when a joint has no torque resolution (no tau_max).
  modbus_map::RingFormat ring_format_in_use() const;
  /// Lockstep mode: the drive waits for the host instead of dropping samples when the ring is full.
  bool lockstep = true;
  std::uint32_t produced() const { return produced_; }
  std::uint32_t overruns() const { return overruns_; }

  /// Checks the encoded table (format, CRC, robot, model, value ranges), then persists it (write a
  /// temporary file, fsync, rename over the flash file, fsync the directory) and makes it active.
  /// On any failure the active table and the file stay as they were.
  TableStatus commit(const std::uint8_t* bytes, int size);
  const std::vector<std::uint8_t>& active_table_bytes() const { return active_bytes_; }
  /// Incremented each time the active table changes (a commit that took effect).
  std::uint32_t table_generation() const { return table_generation_; }
  const ParameterTable& active_table() const { return active_; }
  const std::string& startup_note() const { return startup_note_; }
  /// Milliseconds to sleep after each 64-byte chunk written to the flash file (0: none); lets tests
  /// kill the drive in the middle of a flash.
  int flash_chunk_delay_ms = 0;

  /// Per joint RMS of tau_cmd - tau_ff [Nm] since start(): the drive's own model error.
  JointArray model_error_rms() const;

  /// The exact plant state at one recorded sample (simulation studies, survey Fig. 3): q [rad],
  /// qd [rad/s], qdd [rad/s^2] of the plant at the sample instant, the commanded torque [Nm] and the
  /// measured (noisy) torque [Nm] recorded with it.
  struct PlantSample {
    double t = 0;
    JointArray q{}, qd{}, qdd{}, tau_cmd{}, tau_measured{};
  };
  /// If set, every recorded sample also appends its PlantSample here (not through the ring).
  std::vector<PlantSample>* plant_log = nullptr;
  /// Standard parameters of the plant (10 N, generated StandardParam order); nominal by default.
  /// Only while not playing. Throws InputError on a size mismatch.
  void set_plant_parameters(const std::vector<double>& phi_standard);
  /// PD gains of the control law (computed by start() from M(q0) unless fixed here; the known
  /// control law IDIM-IV simulates). Only while not playing.
  void fix_gains(const JointArray& kp, const JointArray& kd);
  JointArray kp() const;
  JointArray kd() const;
  /// The collision monitor (drive_plant.hpp MonitorSettings, docs/monitor.md "On the drive") for
  /// the runs started after it: while one is watched, every control period's measured torque goes
  /// through lib/'s observer with the active table, and a residual beyond its threshold stops the
  /// trajectory with fault collision (fault_joint the joint furthest beyond it, fault_value its
  /// r - mean [Nm]; time() the drive time of the detection, which judges the state D = round(1 /
  /// (K dt)) periods back). An empty string when taken, else why not (then unchanged): playing, or
  /// a value DrivePlant::set_monitor refuses.
  std::string set_monitor(const MonitorSettings& m);
  /// Whether the run started last is watched (refused: the observer cannot take the active table).
  modbus_map::MonitorState monitor_state() const;
  /// The observer's last r - mean [Nm] per joint.
  JointArray monitor_residual() const;
  /// What the last period widened each threshold by [Nm]: the friction the model cannot know.
  JointArray monitor_widening() const;
  /// J_p(q)^T F [Nm] of a force F [N, base frame] on `point` [m] of 1-based `link` (its frame) at q.
  JointArray contact_torque(const JointArray& q, int link, const std::array<double, 3>& point,
                            const std::array<double, 3>& force) const;
  /// The control loop's rate [Hz] (the scenario's).
  double control_rate_hz() const { return scenario_.control_rate_hz; }

 private:
  std::unique_ptr<DrivePlant> plant_;  ///< the robot's compiled model (drive_plant.hpp)
  Scenario scenario_;
  std::string table_path_;
  modbus_map::DriveState state_ = modbus_map::DriveState::idle;
  modbus_map::DriveFault fault_ = modbus_map::DriveFault::none;
  int fault_joint_ = 0;
  double fault_value_ = 0;
  double time_ = 0, clock_ = 0;
  long steps_ = 0, steps_per_sample_ = 1, total_steps_ = 0;
  /// lib/'s ring (1.4 MB at kRingCapacity: on the heap here, static storage in a firmware drive)
  std::unique_ptr<drive::SampleRing<kRingCapacity>> ring_ = std::make_unique<drive::SampleRing<kRingCapacity>>();
  std::uint32_t acked_ = 0, produced_ = 0, overruns_ = 0;
  JointArray q_resolution_{}, tau_resolution_{};
  ParameterTable active_;
  std::vector<std::uint8_t> active_bytes_;
  std::uint32_t table_generation_ = 0;
  std::string startup_note_;
  JointArray error_sq_{};
  bool gains_fixed_ = false;
  long error_n_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  modbus_map::PayloadState payload_state_ = modbus_map::PayloadState::none;
  drive::PayloadVerdict payload_verdict_{};
  /// Publishes the plant's payload fit with the verdicts; returns whether the mass is determined.
  bool publish_payload();
  void finish_payload();
};

/// The table of robot `robot`'s nominal (CAD) base parameters with Eq. 7 friction Fc [Nm], beta
/// [Nm s/rad] per joint: with zero friction, the drive's factory table; with a scenario's, the
/// survey's set-parameter feed-forward (Fig. 3). Throws InputError for a robot not compiled in.
ParameterTable nominal_table(const std::string& robot, const JointArray& Fc = {}, const JointArray& beta = {});

/// `t` encoded as the drive's flash holds it (parameter_table.hpp). Throws std::logic_error if it
/// does not encode (a table built by the host always does).
std::vector<std::uint8_t> encoded_table(const ParameterTable& t);

/// Writes `bytes` to `path` atomically (temporary file in the same directory, fsync, rename, fsync
/// of the directory): a crash at any moment leaves the old or the new content. Throws
/// std::runtime_error on I/O failure. This is the parameter store's only write path, and its seam
/// for crash tests: `cut_at` >= 0 simulates the process dying at that point and returns there —
/// 0..size: after that many bytes of the temporary file (the write in progress torn at that
/// offset), before its fsync; size + 1: after the fsync, before the rename; size + 2: after the
/// rename, before the directory's fsync. -1: no cut.
void write_file_atomically(const std::string& path, const std::vector<std::uint8_t>& bytes, int chunk_delay_ms = 0,
                           long cut_at = -1);

}  // namespace dyncal::host
