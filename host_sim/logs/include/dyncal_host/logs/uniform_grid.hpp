#pragma once
// Real loggers jitter and drop samples: a time-stamped log put on a uniform time grid, split into
// segments at gaps too long to bridge, before filtering and differentiation (docs/accuracy.md,
// "Real logs").

#include <string>
#include <vector>

#include "dyncal_host/logs/joint_log.hpp"
#include "dyncal_host/logs/repeated_samples.hpp"

namespace dyncal::host {

/// What to_uniform_grid found in the raw time stamps.
struct SamplingReport {
  double raw_rate_hz = 0;  ///< 1 / period
  double period = 0;       ///< grid period [s]: time spanned / periods spanned (see to_uniform_grid)
  double jitter_rms = 0;   ///< RMS of each step's distance to its nearest multiple (>= 1) of the period, / period
  long raw_samples = 0;    ///< rows of the raw log
  long grid_samples = 0;   ///< samples on the grid (all segments)
  long missing = 0;        ///< grid samples beyond the raw samples, summed over the pieces: missing samples bridged
  int segments = 1;        ///< segments of the result (input segments and splits at gaps)
  int gaps = 0;            ///< splits at steps longer than max_gap
  double gap_seconds = 0;  ///< total duration of those gaps [s]
  bool resampled = false;  ///< false: the raw log was already uniform (within 1e-6 of the period) and is kept as is
  /// Resampled logs: the stamps' RMS distance to the regular clock estimated from them
  /// (sample_clock.hpp), / period, and that clock's ticks without a sample.
  double stamp_jitter = 0;
  long clock_missing = 0;
  /// Third-difference power of the positions on the grid through the clock over that through the
  /// stamps (geometric mean over the joints that move); < 1: the clock is used (clock_used).
  double roughness_ratio = 1;
  bool clock_used = false;
  RepeatedSamples repeated;  ///< rows a logger re-wrote while the arm moved, dropped first (repeated_samples.hpp)
};

/// Relative deviation of every step from the median step under which a log counts as uniform and is
/// used as it is (time stamps printed with 7 or more significant digits of their step).
inline constexpr double kUniformStepTolerance = 1e-6;

/// The largest step bridged by interpolation for a model kept below `cutoff_hz`: 1 / (2 cutoff).
/// A signal limited to the band below the cut-off is fixed by samples closer than half its shortest
/// period (sampling theorem), so a gap up to that length loses nothing the fit uses; a longer one
/// splits the log.
inline double bridgeable_gap(double cutoff_hz) {
  return 0.5 / cutoff_hz;
}

/// `raw` (time strictly increasing, finite values; any number of input segments), its repeated rows
/// dropped first (drop_repeated_samples: a logger that re-wrote its last reading), on a uniform grid
/// of period T: the median step refined twice as the time spanned over the periods spanned (each
/// step counting as its nearest multiple of T; missing samples bias the median up; exact while each
/// step is within T/2 of a multiple, and a T off the logger's nominal period costs nothing but grid
/// density, since the spline reads the raw time stamps). In each segment, the steps longer than max_gap [s] split it,
/// and every piece is sampled at t0 + k T (t0 its first time stamp, up to its last) by a natural cubic spline through
/// the raw samples of each column (q, measured qd and qdd, tau; error O(h^4) for smooth signals, and exact at the raw
/// samples). The spline's abscissae are the stamps or, when it puts the positions on the grid more smoothly (the stamps
/// were taken on arrival, the samples on the logger's clock), the regular clock estimated from the stamps
/// (sample_clock.hpp; report.clock_used). A piece shorter than three grid samples is dropped (counted in the report). A
/// log already uniform (every
/// step within kUniformStepTolerance T of T, no gap) is returned unchanged (report.resampled false). Throws InputError:
/// fewer than 3 samples, time not increasing (with the row), input segments of different rates (median steps more than
/// 1 % apart), nothing left.
JointLog to_uniform_grid(JointLog raw, double max_gap, SamplingReport& report);

/// One line for the identify report: raw rate, jitter, missing samples, gaps and segments.
std::string describe(const SamplingReport& report, double max_gap);

/// Several logs of one robot as one log of several segments (each log its own segment, never filtered
/// across): times of each later log shifted to follow the previous one. Every log must have the same
/// columns (measured qd, qdd) and joint count. Throws InputError naming the log that differs.
JointLog stack_logs(std::vector<JointLog> logs);

}  // namespace dyncal::host
