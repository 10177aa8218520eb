#pragma once
// The drive's collision monitor settings (docs/monitor.md "On the drive") and the one rule a drive
// takes them by: the register check (Modbus exception 03 when written and again at a start) and
// the drive that runs them apply the same function, so a setting the drive acknowledges is the
// setting it runs. The monitor itself: lib/'s generalised-momentum observer (momentum_observer.hpp,
// De Luca & Mattone 2005; Haddadin et al. 2017) fed through centred_slope.hpp. Heap-free.

#include <array>
#include <cmath>
#include <cstdint>

#include "dyncal/centred_slope.hpp"
#include "dyncal/modbus_map.hpp"

namespace dyncal::drive {

/// An alarm when |r_j - mean_j| exceeds threshold_j (widened by the active table's |Fc_j| where
/// joint j's encoder stalled within the slope's window); thresholds come from the calibration's
/// residual statistics (dyncal monitor), never tuned on the drive. Joint slots past the robot's
/// joints are 0.
struct MonitorSettings {
  double gain = 0;                                         ///< K [1/s] on every joint; 0: the monitor is off
  std::array<double, modbus_map::kMaxJoints> threshold{};  ///< [Nm]; 0: the joint is not watched
  std::array<double, modbus_map::kMaxJoints> mean{};       ///< the residual's mean on contact-free motion [Nm]
  std::array<double, modbus_map::kMaxJoints> band{};       ///< standstill band of the friction terms [rad/s]
};

/// Why monitor settings are refused.
enum class MonitorRefusal : std::uint8_t {
  none = 0,
  gain,         ///< the gain is not 0 (off) nor a finite number > 0
  gain_step,    ///< K dt > 1: the discrete observer is unstable
  gain_window,  ///< the centred slope's window, 2 round(1 / (K dt)) + 1, is longer than the drive's
  joint,        ///< a joint slot's threshold or band is not a finite number >= 0, or its mean not finite
};

struct MonitorCheck {
  MonitorRefusal refusal = MonitorRefusal::none;
  int joint = 0;  ///< the 0-based slot refused (refusal joint)
};

/// The rule: gain 0 (off) or 0 < K with K dt <= 1 and a centred-slope window of at most
/// 2 modbus_map::kMonitorMaxHalfWidth + 1 periods (dt: the control period [s]); every slot's
/// threshold and band finite and >= 0, its mean finite.
inline MonitorCheck check_monitor_settings(const MonitorSettings& m, double dt) noexcept {
  if (!std::isfinite(m.gain) || !(m.gain >= 0)) return {MonitorRefusal::gain, 0};
  if (m.gain > 0) {
    if (!(m.gain * dt <= 1.0)) return {MonitorRefusal::gain_step, 0};
    if (centred_slope_half_width(m.gain, dt) > modbus_map::kMonitorMaxHalfWidth)
      return {MonitorRefusal::gain_window, 0};
  }
  for (int j = 0; j < modbus_map::kMaxJoints; ++j) {
    const auto k = static_cast<std::size_t>(j);
    if (!std::isfinite(m.threshold[k]) || !std::isfinite(m.mean[k]) || !std::isfinite(m.band[k]) ||
        m.threshold[k] < 0 || m.band[k] < 0)
      return {MonitorRefusal::joint, j};
  }
  return {};
}

/// The settings as the holding registers hold them (monitor_gain, monitor_threshold, monitor_mean,
/// monitor_band; `h` the whole holding bank, f32 big-endian words).
inline MonitorSettings monitor_from_registers(const std::uint16_t* h) noexcept {
  namespace mm = modbus_map;
  MonitorSettings m;
  m.gain = mm::get_f32(h + mm::kMonitorGainReg);
  for (int j = 0; j < mm::kMaxJoints; ++j) {
    const auto k = static_cast<std::size_t>(j);
    m.threshold[k] = mm::get_f32(h + mm::kMonitorThresholdReg + 2 * j);
    m.mean[k] = mm::get_f32(h + mm::kMonitorMeanReg + 2 * j);
    m.band[k] = mm::get_f32(h + mm::kMonitorBandReg + 2 * j);
  }
  return m;
}

}  // namespace dyncal::drive
