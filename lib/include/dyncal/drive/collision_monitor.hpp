#pragma once
// The drive's collision monitor (docs/monitor.md "On the drive"): lib/'s generalised-momentum
// observer (De Luca & Mattone 2005; Haddadin et al. 2017, momentum_observer.hpp) on the active
// table at the control rate, fed each period's measured q and torque through the centred slope
// (centred_slope.hpp: D = round(1 / (K dt)) periods, so it judges the state D periods back; the
// torque held over its period, TorqueHold::zero_order), the friction the model cannot know at low
// speed widening each threshold (friction_uncertainty.hpp's weight times the table's |Fc_j|). A
// residual r_j - mean_j beyond threshold_j + widening_j trips the run with fault collision on the
// joint furthest beyond its limit. The settings and their rule: monitor_settings.hpp. One
// implementation for every drive: the drive application (drive_application.hpp) and the Linux
// simulated drive's plant run it. Heap-free, exception-free.

#include <Eigen/Core>
#include <cmath>

#include "dyncal/centred_slope.hpp"
#include "dyncal/drive/monitor_settings.hpp"
#include "dyncal/friction_uncertainty.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/parameter_table.hpp"

namespace dyncal::drive {

template <class Robot, typename Scalar>
class CollisionMonitor {
 public:
  static constexpr int N = Robot::kNumJoints;
  using Vec = Eigen::Matrix<Scalar, N, 1>;

  /// A collision: `joint` 0-based, `value` its r - mean [Nm].
  struct Collision {
    bool tripped = false;
    int joint = 0;
    Scalar value = 0;
  };

  /// Starts watching a run with `settings` (which passed check_monitor_settings) on table `active`
  /// (`coulomb`: its |Fc_j| per joint [Nm], 0 where it has none) at control period dt [s]. Off when
  /// the gain is 0; refused when the observer or the window cannot take the table or the period
  /// (the run is then not watched, and says so: state()).
  modbus_map::MonitorState begin(const MonitorSettings& settings, const ParameterTable& active, const Vec& coulomb,
                                 Scalar dt) noexcept {
    settings_ = settings;
    residual_.setZero();
    widening_.setZero();
    state_ = modbus_map::MonitorState::off;
    if (!(settings.gain > 0)) return state_;
    const Scalar gain = static_cast<Scalar>(settings.gain);
    if (observer_.configure(active, Vec::Constant(gain), dt) != UpdateStatus::ok ||
        slope_.reset(centred_slope_half_width(gain, dt), dt, N, TorqueHold::zero_order) != UpdateStatus::ok ||
        uncertainty_.reset(gain, dt, N) != UpdateStatus::ok) {
      state_ = modbus_map::MonitorState::refused;
      return state_;
    }
    static_friction_ = coulomb.cwiseAbs();
    state_ = modbus_map::MonitorState::watching;
    return state_;
  }

  /// One control period: the measured q [rad] and the torque [Nm] measured with the period's
  /// command. No collision while not watching or while the window fills; a sample the observer
  /// refuses (non-finite) is skipped.
  Collision update(const Vec& q_measured, const Vec& tau_measured) noexcept {
    Collision c;
    if (state_ != modbus_map::MonitorState::watching) return c;
    Vec q, qd, tau;
    typename Slope::Flags still;
    if (slope_.update(q_measured, tau_measured, q, qd, tau, still) != UpdateStatus::ok) return c;
    Vec qd_friction = qd;
    for (int j = 0; j < N; ++j)
      if (std::fabs(qd[j]) < static_cast<Scalar>(settings_.band[static_cast<std::size_t>(j)])) qd_friction[j] = 0;
    if (observer_.update(q, qd, qd_friction, tau) != UpdateStatus::ok) return c;
    Vec weight;
    if (uncertainty_.update(qd_friction, still, weight) != UpdateStatus::ok) return c;
    Scalar worst = 1;
    for (int j = 0; j < N; ++j) {
      const auto k = static_cast<std::size_t>(j);
      residual_[j] = observer_.residual()[j] - static_cast<Scalar>(settings_.mean[k]);
      if (!(settings_.threshold[k] > 0)) continue;
      widening_[j] = weight[j] * static_friction_[j];
      const Scalar limit = static_cast<Scalar>(settings_.threshold[k]) + widening_[j];
      if (std::fabs(residual_[j]) > worst * limit) {
        worst = std::fabs(residual_[j]) / limit;
        c = {true, j, residual_[j]};
      }
    }
    return c;
  }

  modbus_map::MonitorState state() const noexcept { return state_; }
  /// The last period's r - mean [Nm] (0 while off or filling the window).
  const Vec& residual() const noexcept { return residual_; }
  /// What the last period widened each threshold by [Nm].
  const Vec& widening() const noexcept { return widening_; }

 private:
  using Slope = CentredSlope<Scalar, N, modbus_map::kMonitorMaxHalfWidth>;
  MonitorSettings settings_{};
  MomentumObserver<Robot, Scalar> observer_;
  Slope slope_;
  FrictionUncertainty<Scalar, N> uncertainty_;
  modbus_map::MonitorState state_ = modbus_map::MonitorState::off;
  Vec static_friction_ = Vec::Zero(), residual_ = Vec::Zero(), widening_ = Vec::Zero();
};

}  // namespace dyncal::drive
