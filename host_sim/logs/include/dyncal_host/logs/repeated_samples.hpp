#pragma once
// A PC logger that polls faster than the robot updates, or a link that stalls, re-writes the last
// reading: rows identical in every value to the row before, under advancing time stamps. Read as
// samples, they hold the position still and then jump, which differentiation turns into velocity and
// acceleration spikes (docs/accuracy.md, "Real logs": repeated samples).

#include <Eigen/Core>

#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// What drop_repeated_samples found.
struct RepeatedSamples {
  long dropped = 0;       ///< repeated rows dropped: the arm moved across their run
  long runs = 0;          ///< runs of dropped rows
  long longest = 0;       ///< rows in the longest dropped run
  double longest_at = 0;  ///< time of that run's first repeated row [s]
  long kept_at_rest = 0;  ///< repeated rows kept: the arm did not move across their run
};

/// Joint j's quantum [log units]: the smallest non-zero |q_j(k+1) - q_j(k)| inside a segment (an
/// encoder's count); 0 when q_j never changes.
Eigen::VectorXd position_quanta(const JointLog& log);

/// Removes the stale rows of `log`: in each segment, every run of rows identical in every column (q,
/// measured qd and qdd, tau) to the row just before the run, when the arm moved across the run: the
/// first row after it differs from the run's position by at least two quanta on some joint
/// (position_quanta). A real sensor at rest can repeat every value (quantised positions and
/// currents), and then its rows are kept; a moving arm cannot keep its position through a run and
/// jump by two counts or more at its end. Each dropped row is a missing sample for the uniform grid
/// (uniform_grid.hpp: bridged, or a gap that splits the log). A run that ends its segment has no row
/// after it and is kept. Segment starts are renumbered.
RepeatedSamples drop_repeated_samples(JointLog& log);

}  // namespace dyncal::host
