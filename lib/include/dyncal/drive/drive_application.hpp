#pragma once
// The drive application: what a drive does between its register server (register_server.hpp) and
// its arm. Run control (start, stop, trip, fault, reset; the watchdog's trip is the caller's, from
// RegisterServer::owner_last_request), the control law of the survey's Fig. 3 (feed-forward of the
// active parameter table plus PD on the tracking error), the limit trips against the robot's
// ratings, the recording into a fixed sample ring in lockstep (a period runs only while the ring has
// room: no sample is ever dropped), the drive's own model error RMS(tau_cmd - tau_ff), and the
// parameter table (checked against the models the drive runs, stored through the port, read back).
// It is the `Drive` of register_server.hpp. Heap-free, exception-free; it reaches the outside only
// through lib/'s port interfaces (port.hpp: ParameterStore, Joints). Compiled into the Cortex-M
// drive images (float on the M4F, double on the M7) over a simulated arm; a drive maker's firmware
// gives it its encoders and current loop instead.
//
// Around lib/'s estimators: the collision monitor (collision_monitor.hpp: the momentum observer on
// the active table every control period, a residual beyond its threshold trips the run) and the
// payload run (payload_run.hpp: the last link's load identified on the recorded samples, written
// into the active table at the run's end when its mass is determined). The Linux simulated drive
// runs it too, in double, over its scenario's plant (host_sim/drive): one source for every drive.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include "dyncal/drive/collision_monitor.hpp"
#include "dyncal/drive/monitor_settings.hpp"
#include "dyncal/drive/payload_run.hpp"
#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/ring_window.hpp"
#include "dyncal/drive/sample_ring.hpp"
#include "dyncal/drive/stop_and_go.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/port.hpp"
#include "dyncal/table_check.hpp"

namespace dyncal::drive {

/// `Models`: the term sets the drive runs (term_sets.hpp); `Scalar`: float or double;
/// `RingCapacity`: samples the ring holds (port::DriveSample, 88 bytes each).
template <class Models, typename Scalar, std::size_t RingCapacity>
class DriveApplication {
 public:
  static constexpr int N = Models::kNumJoints;
  using Robot = typename Models::RobotType;
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  using Mat = Eigen::Matrix<Scalar, N, N>;
  using Trajectory = FourierTrajectory<Scalar, N, modbus_map::kMaxHarmonics>;

  /// What the drive is: its loop and its robot.
  struct Settings {
    double control_rate_hz = 1000;  ///< control periods per second [Hz]
    /// The PD loop's natural frequency [Hz] and damping: gains from the inertia of the arm the loop
    /// is tuned on at the run's first pose, M_jj(q0) of `loop_standard` (else `nominal_standard`)
    /// plus the motor's reflected rotor inertia (survey Fig. 3).
    double bandwidth_hz = 8, damping = 1;
    /// The motors' rotor inertias reflected to the joints, J_m N^2 [kg m^2] (the motor data sheet's;
    /// 0: none), for the gains: motor m adds Ia_m T_m^T T_m to the arm's inertia.
    double rotor_inertia[N] = {};
    /// The transmission, motor velocities v = T qd (robot.json's motor_velocity_map): N x N,
    /// row-major, row m motor m's; nullptr: the identity (every motor turns with its own joint).
    const double* motor_map = nullptr;
    /// The robot's ratings (robot.json, joint side): the limit trips (q_min, q_max, qd_max), the
    /// tables' plausibility, the torque's full scale in the ring (2 tau_max).
    JointRatings<N> ratings{};
    float q_resolution[N] = {};  ///< the encoder's quantum, joint side [rad or m]
    /// The torque measurement's noise std per joint [Nm] (the current sensor's): the payload
    /// run's measurement variance.
    double tau_noise_std[N] = {};
    const double* nominal_standard = nullptr;  ///< the robot's CAD standard parameters [kNumStandard]
    /// The standard parameters [kNumStandard] of the arm the loop is tuned on, as commissioning
    /// tunes a drive on its arm, load included (read at each start; nullptr: nominal_standard).
    const double* loop_standard = nullptr;
    /// How the ring window packs a sample (set_ring_format).
    modbus_map::RingFormat ring_format = modbus_map::RingFormat::counts;
    /// The trajectory's clock (stop_and_go.hpp; off by default): a run plays its periods in moves
    /// with rests between, q_d = q(u), qd_d = w qd(u), qdd_d = w^2 qdd(u) + w' qd(u), and lasts
    /// longer by the rests.
    StopAndGo stop_and_go{};
  };

  DriveApplication(port::ParameterStore& store, port::Joints<Scalar>& joints, const Settings& s) noexcept
      : store_(store), joints_(joints), settings_(s), payload_(link_nominal(s.nominal_standard)) {
    for (int i = 0; i < Robot::kNumStandard; ++i)
      phi_nominal_[i] = s.nominal_standard ? static_cast<Scalar>(s.nominal_standard[i]) : Scalar(0);
    for (int j = 0; j < N; ++j) {
      resolution_.q[j] = s.q_resolution[j];
      resolution_.tau[j] = 2.0f * s.ratings.tau_max[j] / static_cast<float>(modbus_map::kTauFullScale);
    }
    set_ring_format(s.ring_format);
    payload_verdict_ = PayloadVerdict::unknown();  // NaN until a payload run ends
  }
  DriveApplication(const DriveApplication&) = delete;
  DriveApplication& operator=(const DriveApplication&) = delete;

  // --- the parameter table

  /// Makes the store's table active (its status when it has none or it does not pass the check).
  TableStatus load() noexcept {
    TableStatus st = TableStatus::ok;
    if (store_.read(staged_, &st) != port::PortStatus::ok) return st;
    st = Models::check(staged_, settings_.ratings);
    return st == TableStatus::ok ? activate(staged_) : st;
  }
  /// Makes `t` active without storing it (the factory table of a drive whose store holds none).
  TableStatus activate(const ParameterTable& t) noexcept {
    const TableStatus st = encode_table(t, active_bytes_, kTableMaxBytes, &active_size_);
    if (st != TableStatus::ok) return st;
    active_ = t;
    ++generation_;
    return TableStatus::ok;
  }
  const ParameterTable& active_table() const noexcept { return active_; }
  /// The active table as encoded (parameter_table.hpp), *size its bytes.
  const std::uint8_t* active_table_bytes(int* size) const noexcept {
    *size = active_size_;
    return active_bytes_;
  }
  /// +1 each time a table becomes active.
  std::uint32_t table_generation() const noexcept { return generation_; }

  // --- settings of the runs started after them (false, unchanged, while a run plays)

  /// The samples the ring holds, 1..RingCapacity (a drive's trace buffer may be smaller than the
  /// type's; the register ring_capacity shows it).
  bool set_ring_limit(long samples) noexcept {
    if (state_ == modbus_map::DriveState::playing || samples < 1 || samples > static_cast<long>(RingCapacity))
      return false;
    ring_limit_ = samples;
    return true;
  }
  /// How the ring window packs a sample (docs/modbus.md "Measurement stream"); counts needs every
  /// joint's torque resolution (a tau_max rating): without one the drive packs float32.
  bool set_ring_format(modbus_map::RingFormat f) noexcept {
    if (state_ == modbus_map::DriveState::playing) return false;
    ring_format_ = f;
    for (int j = 0; j < N; ++j)
      if (!(resolution_.tau[j] > 0)) ring_format_ = modbus_map::RingFormat::float32;
    return true;
  }
  modbus_map::RingFormat ring_format() const noexcept { return ring_format_; }
  /// Holds the PD gains kp [Nm/rad], kd [Nm s/rad] instead of setting them from M(q0) at each
  /// start: a drive whose loop is tuned (the known law IDIM-IV simulates, survey Eq. 17).
  bool fix_gains(const Vec& kp, const Vec& kd) noexcept {
    if (state_ == modbus_map::DriveState::playing) return false;
    kp_ = kp;
    kd_ = kd;
    gains_fixed_ = true;
    return true;
  }

  // --- the Drive of register_server.hpp

  modbus_map::DriveState state() const noexcept { return state_; }
  std::uint32_t acked() const noexcept { return acked_; }
  std::uint32_t produced() const noexcept { return produced_; }
  long ring_capacity_samples() const noexcept { return ring_limit_; }
  /// The samples a run of `periods` periods of `period_s` [s] at `fs` [Hz] records (the rests of
  /// the trajectory's clock included): what the ring must hold to record it whole.
  long run_samples(double periods, double period_s, double fs) const noexcept {
    const long per_sample = steps_per_sample(fs), total = run_steps(periods * period_s);
    return (total + per_sample - 1) / per_sample;
  }
  double control_rate_hz() const noexcept { return settings_.control_rate_hz; }

  void ack(std::uint32_t seq_end) noexcept {
    if (seq_end < acked_ || seq_end > produced_) return;
    while (!ring_.empty() && ring_.front().seq < seq_end) ring_.pop_front();
    acked_ = seq_end;
  }

  /// Starts a run (start or trace: the ring records every sample in lockstep either way;
  /// identify_payload: the payload run besides), watched by the collision monitor when its gain is
  /// above 0. A run whose table the observer cannot take plays unwatched and the monitor state says
  /// refused. False (nothing starts) only for monitor settings check_monitor_settings refuses (the
  /// register server refuses them at the write and at the start already).
  bool start(modbus_map::Command c, const RunSettings& run, const MonitorSettings& monitor) noexcept {
    if (check_monitor_settings(monitor, 1.0 / settings_.control_rate_hz).refusal != MonitorRefusal::none) return false;
    trajectory_.f_f = static_cast<Scalar>(run.trajectory.f_f);
    trajectory_.harmonics = run.trajectory.harmonics;
    trajectory_.q0 = run.trajectory.q0.template head<N>().template cast<Scalar>();
    trajectory_.a = run.trajectory.a.template topRows<N>().template cast<Scalar>();
    trajectory_.b = run.trajectory.b.template topRows<N>().template cast<Scalar>();
    per_sample_ = steps_per_sample(run.sample_rate_hz);
    total_steps_ = run_steps(run.periods * static_cast<double>(run.trajectory.period()));
    Vec q0, qd0, qdd0;
    trajectory_.evaluate(Scalar(0), q0, qd0, qdd0);
    if (!gains_fixed_) set_gains(q0);
    joints_.place(q0.data(), qd0.data());
    Vec q;
    joints_.sense(q.data());
    q_previous_ = q - qd0 * dt();
    ring_.clear();
    acked_ = produced_ = overruns_ = 0;
    steps_ = 0;
    time_ = 0;
    for (int j = 0; j < N; ++j) error_sq_[j] = 0;
    error_n_ = 0;
    clear_fault();
    Vec coulomb;
    Models::coulomb(active_, coulomb);
    monitor_.begin(monitor, active_, coulomb, dt());
    if (c == modbus_map::Command::identify_payload) {
      payload_.begin();
      payload_state_ = modbus_map::PayloadState::running;
      payload_verdict_ = PayloadVerdict::unknown();
      ++payload_generation_;
    }
    state_ = modbus_map::DriveState::playing;
    return true;
  }
  /// Stops a playing run (no further period runs); a payload run's estimate so far stays readable,
  /// the table is not touched.
  void stop() noexcept {
    if (state_ != modbus_map::DriveState::playing) return;
    state_ = modbus_map::DriveState::finished;
    if (payload_state_ != modbus_map::PayloadState::running) return;
    payload_verdict_ = payload_.verdict();
    ++payload_generation_;
    payload_state_ = modbus_map::PayloadState::not_written;
  }
  void reset() noexcept {
    if (state_ != modbus_map::DriveState::fault) return;
    state_ = modbus_map::DriveState::idle;
    clear_fault();
  }
  /// Stops a playing run with `fault` (joint 1-based, 0: none; `value` in its unit): no further
  /// period runs and no sample is recorded (holding the arm, by brake or position loop, is the
  /// drive's own, below this application). The watchdog's trip (communication_lost, the silence [s]).
  void trip(modbus_map::DriveFault fault, int joint, double value) noexcept {
    if (state_ != modbus_map::DriveState::playing) return;
    state_ = modbus_map::DriveState::fault;
    fault_ = fault;
    fault_joint_ = joint;
    fault_value_ = value;
    if (payload_state_ == modbus_map::PayloadState::running) payload_state_ = modbus_map::PayloadState::not_written;
  }

  /// Decodes, checks against the models this drive runs and the robot's ratings, stores through
  /// the port (which keeps the old table when it fails), reads the store back and makes what it
  /// holds active when it is the table written (store_failed otherwise: the registers show what the
  /// store holds, never what it was asked to hold).
  TableStatus commit(const std::uint8_t* bytes, int size) noexcept {
    const TableStatus st = decode_table(bytes, size, staged_);
    return st == TableStatus::ok ? commit_staged() : st;
  }

  /// Every input register but commit_result and commit_counter (the register server's).
  void publish_inputs(std::uint16_t* in) const noexcept {
    namespace mm = modbus_map;
    in[mm::kMapVersionReg] = mm::kMapVersion;
    in[mm::kNumJointsReg] = static_cast<std::uint16_t>(N);
    mm::set_u32(in + mm::kRobotIdReg, Robot::kRobotId);
    mm::set_u32(in + mm::kActiveModelIdReg, active_.model_id);
    in[mm::kActiveCountReg] = active_.count;
    in[mm::kStateReg] = static_cast<std::uint16_t>(state_);
    mm::set_f32(in + mm::kSimTimeReg, static_cast<float>(time_));
    mm::set_u32(in + mm::kProducedReg, produced_);
    mm::set_u32(in + mm::kOverrunReg, overruns_);
    for (int j = 0; j < N; ++j) {
      mm::set_f32(in + mm::kModelErrorReg + 2 * j, static_cast<float>(model_error_rms(j)));
      mm::set_f32(in + mm::kGainKpReg + 2 * j, static_cast<float>(kp_[j]));
      mm::set_f32(in + mm::kGainKdReg + 2 * j, static_cast<float>(kd_[j]));
      mm::set_f32(in + mm::kQResolutionReg + 2 * j, resolution_.q[j]);
      mm::set_f32(in + mm::kTauResolutionReg + 2 * j, resolution_.tau[j]);
    }
    in[mm::kFaultReg] = static_cast<std::uint16_t>(fault_);
    in[mm::kFaultJointReg] = static_cast<std::uint16_t>(fault_joint_);
    mm::set_f32(in + mm::kFaultValueReg, static_cast<float>(fault_value_));
    mm::set_f32(in + mm::kControlRateReg, static_cast<float>(settings_.control_rate_hz));
    in[mm::kPayloadStateReg] = static_cast<std::uint16_t>(payload_state_);
    in[mm::kMonitorStateReg] = static_cast<std::uint16_t>(monitor_.state());
    if (published_payload_ != payload_generation_) {  // they change at a payload run's start and end only
      for (int i = 0; i < 10; ++i) {
        mm::set_f32(in + mm::kPayloadReg + 2 * i, static_cast<float>(payload_verdict_.value[i]));
        mm::set_f32(in + mm::kPayloadStdReg + 2 * i, static_cast<float>(payload_verdict_.std[i]));
      }
      published_payload_ = payload_generation_;
    }
    in[mm::kRingFormatReg] = static_cast<std::uint16_t>(ring_format_);
    mm::set_u32(in + mm::kRingCapacityReg, static_cast<std::uint32_t>(ring_limit_));
    if (published_ == generation_) return;  // the table registers change with the table only
    mm::set_u32(in + mm::kActiveCrcReg,
                active_size_ >= 4 ? dyncal::detail::get_u32(active_bytes_ + active_size_ - 4) : 0);
    in[mm::kActiveTableSizeReg] = static_cast<std::uint16_t>(active_size_);
    for (int k = 0; k < mm::kTableWords; ++k) in[mm::kActiveTableReg + k] = 0;
    mm::bytes_to_regs(active_bytes_, active_size_, in + mm::kActiveTableReg);
    published_ = generation_;
  }
  /// The ring window (ring_window.hpp) of this instant.
  void publish_window(std::uint16_t* w) const noexcept {
    RingWindowHeader header;
    header.state = state_;
    header.produced = produced_;
    header.overruns = overruns_;
    encode_ring_window(ring_, ring_.size(), header, N, ring_format_, resolution_, w);
  }

  // --- the control loop

  /// Whether a control period is due: a run plays and the ring has room for its sample (lockstep:
  /// the drive waits for the host to acknowledge rather than drop a sample).
  bool wants_period() const noexcept {
    return state_ == modbus_map::DriveState::playing && static_cast<long>(ring_.size()) < ring_limit_;
  }

  /// One control period (no-op unless playing): sense, check the limits, control law, actuate,
  /// record. The run finishes after its last period.
  void period() noexcept {
    if (state_ != modbus_map::DriveState::playing) return;
    if (steps_ >= total_steps_) {
      state_ = modbus_map::DriveState::finished;
      finish_payload();
      return;
    }
    Vec q, qd, q_d, qd_d, qdd_d, tau_ff, tau_cmd, tau_measured;
    joints_.sense(q.data());
    qd = (q - q_previous_) / dt();
    q_previous_ = q;
    if (check_limits(q, qd)) return;
    desired(time_, q_d, qd_d, qdd_d);
    if (!Models::torque(active_, q_d, qd_d, qdd_d, tau_ff)) tau_ff.setZero();  // active tables passed the check
    tau_cmd = tau_ff + kp_.cwiseProduct(q_d - q) + kd_.cwiseProduct(qd_d - qd);
    joints_.actuate(tau_cmd.data(), tau_measured.data());
    const typename Monitor::Collision collision = monitor_.update(q, tau_measured);
    if (collision.tripped) {
      trip(modbus_map::DriveFault::collision, collision.joint + 1, static_cast<double>(collision.value));
      return;
    }
    for (int j = 0; j < N; ++j) {
      const double e = static_cast<double>(tau_cmd[j] - tau_ff[j]);
      error_sq_[j] += e * e;
    }
    ++error_n_;
    if (steps_ % per_sample_ == 0) {
      port::DriveSample s{};
      s.seq = produced_++;
      for (int j = 0; j < N; ++j) {
        s.q[j] = static_cast<float>(q[j]);
        s.qd[j] = static_cast<float>(qd[j]);
        s.tau[j] = static_cast<float>(tau_measured[j]);
      }
      // A full ring drops the sample (the host sees the gap in seq): only when the caller ran a
      // period it did not want (real time).
      if (static_cast<long>(ring_.size()) >= ring_limit_ || !ring_.push_back(s)) ++overruns_;
      if (payload_state_ == modbus_map::PayloadState::running) update_payload(q, qd_d, qdd_d, tau_measured);
    }
    ++steps_;
    time_ += 1.0 / settings_.control_rate_hz;
  }

  /// The payload run's state and its estimate (at the run's end or stop; NaN before and where the
  /// run does not determine a parameter).
  modbus_map::PayloadState payload_state() const noexcept { return payload_state_; }
  const PayloadVerdict& payload() const noexcept { return payload_verdict_; }
  /// The collision monitor of the run started last.
  const CollisionMonitor<Robot, Scalar>& monitor() const noexcept { return monitor_; }
  /// The samples recorded and not yet acknowledged, oldest first.
  const SampleRing<RingCapacity>& ring() const noexcept { return ring_; }
  /// The PD gains of the run started last [Nm/rad], [Nm s/rad].
  const Vec& kp() const noexcept { return kp_; }
  const Vec& kd() const noexcept { return kd_; }
  modbus_map::DriveFault fault() const noexcept { return fault_; }
  int fault_joint() const noexcept { return fault_joint_; }
  double fault_value() const noexcept { return fault_value_; }
  /// The run's time [s]: control periods played since the start.
  double time() const noexcept { return time_; }
  /// Samples dropped by a full ring since the start (0 in lockstep).
  std::uint32_t overruns() const noexcept { return overruns_; }
  /// Joint j's (0-based) RMS of tau_cmd - tau_ff since the start [Nm]: the drive's own model error.
  double model_error_rms(int j) const noexcept {
    return error_n_ > 0 ? std::sqrt(error_sq_[j] / static_cast<double>(error_n_)) : 0.0;
  }

 private:
  Scalar dt() const noexcept { return static_cast<Scalar>(1.0 / settings_.control_rate_hz); }
  /// Control periods of a run playing `play_s` seconds of the trajectory (its clock's rests included).
  long run_steps(double play_s) const noexcept {
    return std::lround(settings_.stop_and_go.run_time(play_s) * settings_.control_rate_hz);
  }
  /// The desired state at run time t [s], on the trajectory's clock.
  void desired(double t, Vec& q, Vec& qd, Vec& qdd) const noexcept {
    double u = t, w = 1, wd = 0;
    settings_.stop_and_go.at(t, u, w, wd);
    trajectory_.evaluate(static_cast<Scalar>(u), q, qd, qdd);
    if (!settings_.stop_and_go.on()) return;
    qdd = static_cast<Scalar>(w * w) * qdd + static_cast<Scalar>(wd) * qd;
    qd *= static_cast<Scalar>(w);
  }
  long steps_per_sample(double fs) const noexcept {
    const long k = fs > 0 ? std::lround(settings_.control_rate_hz / fs) : 1;
    return k < 1 ? 1 : k;
  }
  using Monitor = CollisionMonitor<Robot, Scalar>;

  /// The last link's nominal standard parameters (the payload's scales), from the CAD ones.
  static const double* link_nominal(const double* standard) noexcept {
    static const double none[10] = {};
    return standard ? standard + Robot::kNumStandard - 10 : none;
  }

  /// staged_ checked against the models and the ratings, stored, read back and made active.
  TableStatus commit_staged() noexcept {
    TableStatus st = Models::check(staged_, settings_.ratings);
    if (st != TableStatus::ok) return st;
    if (store_.write(staged_, &st) != port::PortStatus::ok)
      return st != TableStatus::ok ? st : TableStatus::store_failed;
    if (store_.read(read_back_, &st) != port::PortStatus::ok || !same_table(read_back_, staged_))
      return TableStatus::store_failed;
    return activate(read_back_);
  }

  /// One recorded sample of a payload run: the residual of the active table's torque at the
  /// measured position with the trajectory's velocity and acceleration; the variance the sensor's
  /// noise, at least its float32 register's resolution.
  void update_payload(const Vec& q, const Vec& qd_d, const Vec& qdd_d, const Vec& tau_measured) noexcept {
    Vec tau_model, r;
    if (!Models::torque(active_, q, qd_d, qdd_d, tau_model)) return;
    for (int j = 0; j < N; ++j) {
      const double noise = settings_.tau_noise_std[j];
      const double resolution = 6e-8 * std::fmax(1.0, std::fabs(static_cast<double>(tau_measured[j])));
      r[j] = static_cast<Scalar>(std::fmax(noise * noise, resolution * resolution));
    }
    payload_.update(q, qd_d, qdd_d, tau_measured - tau_model, r);
  }

  /// The end of a payload run: the verdict, and the loaded table committed when the mass is
  /// determined (written), else the table unchanged (not_written).
  void finish_payload() noexcept {
    if (payload_state_ != modbus_map::PayloadState::running) return;
    payload_state_ = modbus_map::PayloadState::not_written;
    payload_verdict_ = payload_.verdict();
    ++payload_generation_;
    if (!payload_verdict_.mass_determined) return;
    staged_ = PayloadRun<Robot, Scalar>::loaded(active_, payload_verdict_);
    if (commit_staged() == TableStatus::ok) payload_state_ = modbus_map::PayloadState::written;
  }

  static bool same_table(const ParameterTable& a, const ParameterTable& b) noexcept {
    if (a.robot_id != b.robot_id || a.model_id != b.model_id || a.count != b.count || a.effect_count != b.effect_count)
      return false;
    for (int i = 0; i < a.count; ++i)
      if (dyncal::detail::float_bits(a.values[i]) != dyncal::detail::float_bits(b.values[i])) return false;
    for (int i = 0; i < a.effect_count; ++i) {
      const EffectTerm &x = a.effects[i], &y = b.effects[i];
      if (x.kind != y.kind || x.joint != y.joint || x.joint2 != y.joint2 || x.sign != y.sign ||
          dyncal::detail::float_bits(x.shape) != dyncal::detail::float_bits(y.shape))
        return false;
      for (int k = 0; k < 3; ++k)
        if (dyncal::detail::float_bits(x.c[k]) != dyncal::detail::float_bits(y.c[k])) return false;
    }
    return true;
  }
  void clear_fault() noexcept {
    fault_ = modbus_map::DriveFault::none;
    fault_joint_ = 0;
    fault_value_ = 0;
  }

  /// The first limit the measurements break (a non-finite state, then q outside [q_min, q_max],
  /// then |qd| above qd_max; joint 1 first) trips the run; true when it did.
  bool check_limits(const Vec& q, const Vec& qd) noexcept {
    const JointRatings<N>& r = settings_.ratings;
    for (int j = 0; j < N; ++j)
      if (!std::isfinite(q[j]) || !std::isfinite(qd[j])) {
        trip(modbus_map::DriveFault::non_finite_state, j + 1, NAN);
        return true;
      }
    for (int j = 0; j < N; ++j)
      if (r.q_max[j] > r.q_min[j] && (q[j] < r.q_min[j] || q[j] > r.q_max[j])) {
        trip(modbus_map::DriveFault::position_limit, j + 1, static_cast<double>(q[j]));
        return true;
      }
    for (int j = 0; j < N; ++j)
      if (r.qd_max[j] > 0 && std::fabs(qd[j]) > r.qd_max[j]) {
        trip(modbus_map::DriveFault::velocity_limit, j + 1, static_cast<double>(qd[j]));
        return true;
      }
    return false;
  }

  /// PD gains from the tuned-on arm's inertia at the first pose, (M + R)_jj(q0) with the motors'
  /// R = sum_m Ia_m T_m^T T_m: natural frequency w, damping zeta. Capped where the arm is light: the
  /// loop closes on a backward-difference velocity and the discrete velocity loop needs
  /// kd dt / m_eff < 2 at every pose (m_eff = 1 / (M + R)^-1_jj, the joint's effective inertia);
  /// with half that margin the inertia the gains are set for is at most min over the trajectory of
  /// m_eff / (2 zeta w dt), on 400 points of one period.
  void set_gains(const Vec& q0) noexcept {
    constexpr int kGrid = 400;
    const Scalar w = static_cast<Scalar>(6.283185307179586 * settings_.bandwidth_hz);
    const Scalar zeta = static_cast<Scalar>(settings_.damping);
    Mat rotor = Mat::Zero();  // sum_m Ia_m T_m^T T_m
    for (int m = 0; m < N; ++m) {
      Vec t = Vec::Unit(m);
      if (settings_.motor_map)
        for (int k = 0; k < N; ++k) t[k] = static_cast<Scalar>(settings_.motor_map[N * m + k]);
      rotor += static_cast<Scalar>(settings_.rotor_inertia[m]) * t * t.transpose();
    }
    Eigen::Matrix<Scalar, Robot::kNumStandard, 1> phi = phi_nominal_;
    if (settings_.loop_standard)
      for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = static_cast<Scalar>(settings_.loop_standard[i]);
    Mat M;
    Robot::mass_matrix(q0, phi, M);
    M += rotor;
    Vec lightest = Vec::Constant(Scalar(1e30));
    for (int k = 0; k < kGrid; ++k) {
      Vec q, qd, qdd;
      trajectory_.evaluate(trajectory_.period() * static_cast<Scalar>(k) / Scalar(kGrid), q, qd, qdd);
      Mat Mk;
      Robot::mass_matrix(q, phi, Mk);
      Mk += rotor;
      const Eigen::LDLT<Mat> ldlt(Mk);
      for (int j = 0; j < N; ++j) {  // column by column: a matrix right-hand side would allocate
        const Vec column = ldlt.solve(Vec::Unit(j));
        lightest[j] = std::fmin(lightest[j], Scalar(1) / column[j]);
      }
    }
    for (int j = 0; j < N; ++j) {
      const Scalar m = std::fmin(M(j, j), lightest[j] / (Scalar(2) * zeta * w * dt()));
      kp_[j] = m * w * w;
      kd_[j] = Scalar(2) * zeta * m * w;
    }
  }

  port::ParameterStore& store_;
  port::Joints<Scalar>& joints_;
  Settings settings_;
  Eigen::Matrix<Scalar, Robot::kNumStandard, 1> phi_nominal_;
  RingResolution resolution_{};
  ParameterTable active_{}, staged_{}, read_back_{};
  std::uint8_t active_bytes_[kTableMaxBytes] = {};
  int active_size_ = 0;
  std::uint32_t generation_ = 0;                  ///< +1 per table made active
  mutable std::uint32_t published_ = 0xFFFFFFFF;  ///< the generation the input registers show
  modbus_map::DriveState state_ = modbus_map::DriveState::idle;
  modbus_map::DriveFault fault_ = modbus_map::DriveFault::none;
  int fault_joint_ = 0;
  double fault_value_ = 0;
  Trajectory trajectory_{};
  long per_sample_ = 1, total_steps_ = 0, steps_ = 0;
  long ring_limit_ = static_cast<long>(RingCapacity);
  modbus_map::RingFormat ring_format_ = modbus_map::RingFormat::counts;
  bool gains_fixed_ = false;
  /// The run's time [s]: + one control period per period played, in double on every target (a
  /// float clock would lose the period's digits within minutes).
  double time_ = 0;
  Vec q_previous_ = Vec::Zero(), kp_ = Vec::Zero(), kd_ = Vec::Zero();
  double error_sq_[N] = {};
  long error_n_ = 0;
  SampleRing<RingCapacity> ring_;
  Monitor monitor_;
  PayloadRun<Robot, Scalar> payload_;
  modbus_map::PayloadState payload_state_ = modbus_map::PayloadState::none;
  PayloadVerdict payload_verdict_{};
  std::uint32_t payload_generation_ = 0;                  ///< +1 per change of payload_verdict_
  mutable std::uint32_t published_payload_ = 0xFFFFFFFF;  ///< the one the input registers show
  std::uint32_t acked_ = 0, produced_ = 0, overruns_ = 0;
};

}  // namespace dyncal::drive
