#pragma once
// The logger's sample clock estimated from its time stamps (docs/accuracy.md, "Real logs"). A PC
// that stamps samples on arrival stamps them late by a varying delay while the robot sampled them
// on its own regular clock; splining positions through such stamps and differentiating twice turns
// the stamp error into acceleration noise. Whether the stamps or the estimated clock are the
// sampling instants is decided from the data (to_uniform_grid).

#include <Eigen/Core>
#include <utility>
#include <vector>

namespace dyncal::host {

/// A regular clock t = offset + period n fitted to the stamps of each segment.
struct SampleClock {
  Eigen::VectorXd t;        ///< the clock's time of every raw sample [s] (stamps' size)
  double period = 0;        ///< [s], least squares over every segment (the logger's rate, drift included)
  double stamp_jitter = 0;  ///< RMS of stamp - clock, / period
  long missing = 0;         ///< clock ticks without a sample (dropped rows), summed over the segments
};

/// The median step between consecutive stamps `t` inside each of `segments` ([first, end) rows)
/// [s]: the period estimate estimate_sample_clock starts from. 0 when no segment has two samples.
double median_step(const Eigen::VectorXd& t, const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments);

/// Estimates the clock of stamps `t` (strictly increasing) in each of `segments` ([first, end) rows)
/// from the period estimate `period`: each sample's tick n (n_0 = 0, every step at least one tick,
/// the nearest whole number of periods from the previous sample's clock time), then offset and
/// period of each segment by least squares of t on n (a constant rate difference between the
/// stamping clock and the robot's, i.e. a slow drift, is in the period), twice.
SampleClock estimate_sample_clock(const Eigen::VectorXd& t,
                                  const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments, double period);

/// Roughness of sampled signals on a uniform grid: per column, the mean square of the third
/// difference over the rows of each piece ([first, end) rows, at least 4), pooled. A smooth signal's
/// third difference is of order T^3 q'''; a time-base error dt adds qd dt of white noise, whose third
/// difference has 20 times its variance.
Eigen::VectorXd third_difference_power(const Eigen::MatrixXd& x,
                                       const std::vector<std::pair<Eigen::Index, Eigen::Index>>& pieces);

}  // namespace dyncal::host
