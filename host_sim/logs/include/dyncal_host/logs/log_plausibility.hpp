#pragma once
// Physical plausibility of a measured log against the robot's own ratings (robot.json): a corrupt
// cell (a value of 1e300, a unit slip) must not pass as data and make a perfect or absurd fit.

#include <string>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// How far outside its ratings a value may lie and still be a measurement. A position may overrun
/// the software limits [q_min, q_max] by kPositionMargin of the joint's range (hard stops and
/// encoder offsets lie beyond the software limits, never a range further); a velocity,
/// acceleration or torque may reach kRatingMultiple times qd_max, qdd_max or tau_max (drives peak
/// at two to three times their rating; tau_max may be derived from the nominal model, a scale
/// rather than a rating, hence the wide multiple). Values beyond are not measurements of the arm.
inline constexpr double kPositionMargin = 0.1;
inline constexpr double kRatingMultiple = 10.0;

/// One implausible value: 1-based data row (the first row after the header is 1), its column
/// ("q3", "tau1", ...), the value and the bound it breaks, in words.
struct ImplausibleValue {
  long row = 0;
  std::string column;
  double value = 0;
  std::string bound;
};

/// The implausible values of `log` (q, measured qd and qdd, tau) against `robot`'s limits, in row
/// order. robot.tau_max must be set (derive_tau_max).
std::vector<ImplausibleValue> find_implausible(const JointLog& log, const RobotDescription& robot);

/// Checks `log` against `robot`. Without `drop`: throws InputError naming the first implausible
/// value (row, column, value, bound) and how many there are. With `drop`: replaces each by linear
/// interpolation between the nearest plausible values of its column (held at the ends), so the
/// sampling stays uniform, and returns one line per replaced value for the report; throws
/// InputError when a column has no plausible value at all. Returns no lines for a clean log.
std::vector<std::string> check_plausibility(JointLog& log, const RobotDescription& robot, bool drop);

}  // namespace dyncal::host
