#pragma once
// Point-to-point operation of a designed trajectory: played for a while, stopped, held, started
// again, as a robot moves between stations. The drive application's trajectory clock
// (drive_application.hpp Settings::stop_and_go; the Linux simulated drive's scenario "stop_and_go",
// docs/modbus.md "Scenario file") and the tests' simulated logs. Heap-free, exception-free.

#include <cmath>

namespace dyncal::drive {

/// The trajectory's clock u(t) [s] against the run's time t [s]: each cycle of `move` + `rest`
/// seconds plays `move` seconds of the trajectory at full speed, slows to a stop over the last
/// `ramp` seconds of the move (the clock decelerating at 1 / ramp), holds still, and starts again
/// over the last `ramp` seconds of the rest. The speed w = du/dt steps its slope at each ramp's ends:
/// the joints' acceleration jumps there (w' qd of the trajectory: no jerk limit), as on robots whose
/// point-to-point moves have trapezoidal velocity profiles. u advances `move` per cycle.
/// Off (u = t) unless rest > 0.
struct StopAndGo {
  double move = 3.0, rest = 0.0, ramp = 0.4;  ///< [s]

  bool on() const noexcept { return rest > 0; }

  /// True when the parameters describe a clock: ramp > 0, move >= ramp, rest >= ramp (each ramp
  /// inside its phase), or off.
  bool valid() const noexcept {
    if (!on()) return rest == 0.0;
    return ramp > 0 && move >= ramp && rest >= ramp && std::isfinite(move) && std::isfinite(rest);
  }

  /// At run time t >= 0: u, w = du/dt and dw/dt.
  void at(double t, double& u, double& w, double& wd) const noexcept {
    u = t, w = 1, wd = 0;
    if (!on()) return;
    const double cycle = move + rest;
    const double n = std::floor(t / cycle), x = t - n * cycle;
    const double base = n * move;
    if (x < move - ramp) {  // moving
      u = base + x;
    } else if (x < move) {  // slowing down
      const double y = x - (move - ramp);
      u = base + move - ramp + y - y * y / (2 * ramp), w = 1 - y / ramp, wd = -1 / ramp;
    } else if (x < cycle - ramp) {  // at rest
      u = base + move - ramp / 2, w = 0;
    } else {  // starting
      const double y = x - (cycle - ramp);
      u = base + move - ramp / 2 + y * y / (2 * ramp), w = y / ramp, wd = 1 / ramp;
    }
  }

  /// The run time [s] at which the clock reaches u >= 0 (the first such t).
  double run_time(double u) const noexcept {
    if (!on()) return u;
    const double cycle = move + rest;
    const double n = std::floor(u / move), v = u - n * move;
    if (v <= move - ramp) return n * cycle + v;
    if (v <= move - ramp / 2) {  // on the slowing ramp: v = move - ramp + y - y^2 / (2 ramp)
      const double z = v - (move - ramp);
      return n * cycle + move - ramp + ramp * (1 - std::sqrt(std::fmax(0.0, 1 - 2 * z / ramp)));
    }
    // On the starting ramp: v = move - ramp / 2 + y^2 / (2 ramp).
    const double z = v - (move - ramp / 2);
    return n * cycle + cycle - ramp + std::sqrt(2 * ramp * z);
  }
};

}  // namespace dyncal::drive
