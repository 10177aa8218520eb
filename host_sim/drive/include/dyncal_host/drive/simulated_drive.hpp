#pragma once
// The simulated drive of any compiled robot (1 to 7 joints) without its transport: lib/'s drive
// application (dyncal/drive/drive_application.hpp: run control, the control law of survey Fig. 3,
// limit trips, recording into the sample ring, the model error, the collision monitor, the payload
// run, the parameter table), the same source the Cortex-M drive images run, in double, over the
// scenario's arm (scenario_arm.hpp: forward dynamics of the generated model, friction and effects,
// encoder quantisation, torque noise) and a table file (file_parameter_store.hpp).

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dyncal/drive/register_server.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/drive_plant.hpp"
#include "dyncal_host/drive/file_parameter_store.hpp"
#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

class SimulatedDrive {
 public:
  /// The largest ring buffer (samples); set_ring_capacity may make it smaller.
  static constexpr int kRingCapacity = kSimulatedRingCapacity;

  /// `table_path`: the simulated flash. Its table becomes active if valid; otherwise (missing or
  /// invalid, reason in startup_note()) the factory table: nominal base parameters, no friction.
  /// Throws InputError for a scenario of another robot or a table path that is not a regular file.
  SimulatedDrive(const RobotDescription& robot, const Scenario& scenario, std::string table_path);
  ~SimulatedDrive();

  std::uint32_t robot_id() const;
  int num_joints() const;
  /// Trajectory and recording settings of start() and start_payload(); only while not playing.
  DriveTrajectory trajectory;
  int periods = 2;
  double sample_rate_hz = 1000;

  /// Plays `periods` periods of `trajectory`, recording at sample_rate_hz, watched by the collision
  /// monitor when set_monitor turned it on (drive_application.hpp start).
  void start();
  /// start(), identifying the payload on the last link while the run plays (the active table fixed,
  /// lib/'s payload run on every recorded sample). At the run's end, when the run determines a
  /// positive mass, the active table takes the payload (its determined parameters; the others held
  /// at 0) through the store: payload_state() written; otherwise, or when the run is stopped or
  /// trips, not_written and the table unchanged (docs/payload.md "On the drive").
  void start_payload();
  /// A run with the register map's command and settings (what the Modbus start commands give);
  /// false when it did not start (monitor settings check_monitor_settings refuses).
  bool start(modbus_map::Command c, const drive::RunSettings& run, const MonitorSettings& monitor);
  modbus_map::PayloadState payload_state() const;
  /// The estimate when the run ended or was stopped (NaN while a payload run plays): values, NaN
  /// where the run does not determine the parameter (1.96 std beyond its scale, or the mass not
  /// determined), and std (lib/ drive/payload_run.hpp).
  const drive::PayloadVerdict& payload() const;
  void stop();
  /// Stops a playing trajectory with `fault` (no joint; `value` in its unit), as a trip does: the
  /// arm holds, no further sample is recorded. No-op unless playing.
  void trip(modbus_map::DriveFault fault, double value);
  /// Clears a fault: the drive becomes idle, holding its position. No-op in any other state.
  void reset();
  modbus_map::DriveState state() const;
  /// Why the drive stopped (state() == fault; none otherwise): each control period, before the
  /// control law, the measured q and qd of every joint are checked — finite, q within [q_min,
  /// q_max], |qd| <= qd_max of the robot file — and the first break stops the trajectory: no more
  /// samples are recorded, the ring keeps those before it. start() clears the fault (the Modbus
  /// server refuses start in fault: there only the reset command clears it).
  modbus_map::DriveFault fault() const;
  /// The 1-based joint that tripped (0: none).
  int fault_joint() const;
  /// Its measured q [rad] (position limit) or qd [rad/s] (velocity limit) at the trip; NaN for a
  /// non-finite state.
  double fault_value() const;
  /// Advances one control period (no-op unless playing); in lockstep the caller steps only while
  /// the ring has room (!ring_full()), in real time a full ring drops the period's sample.
  void step();
  /// The run's time [s] (control periods since the start).
  double time() const;
  double control_period() const { return 1.0 / control_rate_hz_; }
  /// Samples a run of `run_periods` periods of `period_s` [s] at `sample_rate` [Hz] records (the
  /// scenario's rests included): what the ring must hold to record it whole (trace mode).
  long run_samples(double run_periods, double period_s, double sample_rate) const;

  /// Ring buffer: samples with seq >= acked() not yet freed, oldest first.
  const SimulatedRing& ring() const;
  std::uint32_t acked() const;
  /// Frees samples with seq < seq_end (ignored if it would skip unrecorded samples).
  void ack(std::uint32_t seq_end);
  bool ring_full() const;
  /// Samples the ring holds, 1..kRingCapacity (a real drive's trace buffer is often far smaller;
  /// `dyncal drive --ring-samples`); false (unchanged) while playing or out of range.
  bool set_ring_capacity(long samples);
  long ring_capacity() const;
  /// Lockstep mode: the drive waits for the host instead of dropping samples when the ring is full.
  bool lockstep = true;
  std::uint32_t produced() const;
  std::uint32_t overruns() const;

  /// Decodes and checks the table (format, CRC, robot, a model this drive runs, value ranges),
  /// replaces the table file (write a temporary file, fsync, rename, fsync the directory), reads it
  /// back and makes what it holds active. On any failure the active table and the file stay as they
  /// were; store_failed: the file could not be written (store_error() says why) or did not read back.
  TableStatus commit(const std::uint8_t* bytes, int size);
  /// Why the last table write failed (empty when it did not).
  const std::string& store_error() const;
  std::vector<std::uint8_t> active_table_bytes() const;
  /// Incremented each time the active table changes.
  std::uint32_t table_generation() const;
  const ParameterTable& active_table() const;
  const std::string& startup_note() const { return startup_note_; }
  /// Milliseconds to sleep after each 64-byte chunk written to the table file (0: none); lets tests
  /// kill the drive in the middle of a flash.
  void set_flash_chunk_delay(int ms);

  /// Per joint RMS of tau_cmd - tau_ff [Nm] since start(): the drive's own model error.
  JointArray model_error_rms() const;

  using PlantSample = host::PlantSample;
  /// If set, every recorded sample also appends the exact plant state of its period here (not
  /// through the ring).
  std::vector<PlantSample>* plant_log = nullptr;
  /// Standard parameters of the plant (10 N, generated StandardParam order); nominal by default.
  /// Only while not playing. Throws InputError on a size mismatch.
  void set_plant_parameters(const std::vector<double>& phi_standard);
  /// PD gains of the control law (set by each start from M(q0) of the simulated arm, load
  /// included, plus the motors' rotor inertia, unless fixed here; the known control law IDIM-IV
  /// simulates). Only while not playing.
  void fix_gains(const JointArray& kp, const JointArray& kd);
  JointArray kp() const;
  JointArray kd() const;
  /// The collision monitor (drive_plant.hpp MonitorSettings, docs/monitor.md "On the drive") for
  /// the runs started after it: while one is watched, every control period's measured torque goes
  /// through lib/'s observer with the active table, and a residual beyond its threshold stops the
  /// trajectory with fault collision (fault_joint the joint furthest beyond it, fault_value its
  /// r - mean [Nm]; time() the drive time of the detection, which judges the state D = round(1 /
  /// (K dt)) periods back). An empty string when taken, else why not (then unchanged): playing, or
  /// a value check_monitor_settings refuses.
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
  double control_rate_hz() const { return control_rate_hz_; }
  /// Every input register but commit_result and commit_counter, and the ring window
  /// (register_server.hpp's Drive).
  void publish_inputs(std::uint16_t* input) const;
  void publish_window(std::uint16_t* window) const;

 private:
  drive::RunSettings run_settings() const;

  std::unique_ptr<FileParameterStore> store_;  ///< the flash (before plant_, which holds it)
  std::unique_ptr<DrivePlant> plant_;          ///< the robot's compiled drive (drive_plant.hpp)
  double control_rate_hz_;
  std::string startup_note_;
  MonitorSettings monitor_{};
};

/// The table of robot `robot`'s nominal (CAD) base parameters with Eq. 7 friction Fc [Nm], beta
/// [Nm s/rad] per joint: with zero friction, the drive's factory table; with a scenario's, the
/// survey's set-parameter feed-forward (Fig. 3). Throws InputError for a robot not compiled in.
ParameterTable nominal_table(const std::string& robot, const JointArray& Fc = {}, const JointArray& beta = {});

}  // namespace dyncal::host
