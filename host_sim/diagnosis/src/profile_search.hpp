#pragma once
// A profile search of a shape parameter (private to host_sim/diagnosis): the gain maximised over a
// log grid, refined by golden section, with a 95 % profile-likelihood interval; several searches side
// by side, their values asked for in batches (the gains: shape_search.hpp's batch_gains).

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace dyncal::host::detail {

/// The grid values profile searches ask for together (profile_searches): the filter runs their
/// stepping columns interleaved, four at a time (butterworth.hpp).
constexpr size_t kShapeBatch = 4;

/// One value a profile search asks the gain of: search `search`'s log value x.
struct ShapeQuery {
  size_t search = 0;
  double x = 0;
};

/// The log range a profile search scans: `points` log-spaced values in [lo_log, hi_log].
struct SearchRange {
  double lo_log = 0, hi_log = 0;
  int points = 2;
};

/// A shape found by profile search: log of its value, the gain there, and the 95 % interval.
struct ShapeFit {
  double log_value = 0, gain = -1, lo_log = 0, hi_log = 0;
  /// The interval reaches an end of the searched range, or the estimate is an end of its own
  /// interval (no value beyond it on that side fits as well: the gain stops there, as where the
  /// physical signs cut it): the data do not bound the value.
  bool unbounded = false;
};

namespace profile {

/// A 95 % bound's search: from the estimate out by doubling widths (from an eighth of the grid
/// step) to the first value outside, then 10 bisections; `query` is its next value.
struct Bound {
  double dir = 1, in = 0, width = 0, outside = 0, query = 0;
  int bisections = -1;  // -1 while stepping out
  bool done = false;

  Bound(double direction, double estimate, double first_width, const SearchRange& r)
      : dir(direction), in(estimate), width(first_width) {
    query = std::clamp(estimate + dir * width, r.lo_log, r.hi_log);
  }

  /// Takes whether `query` lies inside the interval and sets the next query (or done).
  void answer(bool inside, double estimate, const SearchRange& r) {
    if (bisections < 0 && inside) {  // still inside: step out further, unless at an end of the range
      in = query;
      done = query == r.lo_log || query == r.hi_log;
      width *= 2;
      query = std::clamp(estimate + dir * width, r.lo_log, r.hi_log);
      return;
    }
    if (bisections < 0) {  // the first value outside
      outside = query, bisections = 0;
    } else {
      (inside ? in : outside) = query;
      done = ++bisections == 10;
    }
    query = 0.5 * (in + outside);
  }
};

/// Golden-section refinement between a grid maximum's neighbours [a, b]: its first two values, then
/// 20 steps, each one new value (`query`, which becomes x1 or x2).
struct Golden {
  double a = 0, b = 0, x1 = 0, x2 = 0, f1 = 0, f2 = 0, query = 0;
  bool query_is_x1 = true;

  /// The value to evaluate at step `step` (0 and 1: x1 and x2; then the section moves).
  double next(int step) {
    const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
    if (step == 0) {
      x1 = b - phi * (b - a), x2 = a + phi * (b - a);
      query_is_x1 = true;
    } else if (step == 1) {
      query_is_x1 = false;
    } else if (f1 > f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - phi * (b - a), query_is_x1 = true;
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + phi * (b - a), query_is_x1 = false;
    }
    return query = query_is_x1 ? x1 : x2;
  }
  void answer(double g) { (query_is_x1 ? f1 : f2) = g; }
};

}  // namespace profile

/// Profile searches run side by side (a coupling's two signs): each maximises the gain over its
/// range's log-spaced values, refines by golden section between the best point's neighbours, and
/// gives the 95 % profile interval: the values whose RSS a likelihood-ratio test (chi^2_1 3.84 with
/// n_eff samples, against rss) cannot tell from the best's, stepping out from the best (doubling
/// from an eighth of the grid step) to the first value outside and bisecting; clipped to the
/// searched range (an open bound). gains(queries) gives the gain at each query (a batch_gains):
/// the grids go in batches of kShapeBatch, every search's next golden step and both bounds' next
/// values together. Each search takes the values it would take alone.
template <class Gains>
std::vector<ShapeFit> profile_searches(Gains gains, const std::vector<SearchRange>& ranges, double rss, double n_eff) {
  const size_t K = ranges.size();
  std::vector<ShapeFit> fits(K);
  std::vector<double> steps(K);
  std::vector<ShapeQuery> grid;
  for (size_t k = 0; k < K; ++k) {
    const SearchRange& r = ranges[k];
    steps[k] = (r.hi_log - r.lo_log) / (r.points - 1);
    for (int i = 0; i < r.points; ++i) grid.push_back({k, r.lo_log + i * steps[k]});
  }
  for (size_t from = 0; from < grid.size(); from += kShapeBatch) {
    const std::vector<ShapeQuery> batch(
        grid.begin() + static_cast<std::ptrdiff_t>(from),
        grid.begin() + static_cast<std::ptrdiff_t>(std::min(grid.size(), from + kShapeBatch)));
    const std::vector<double> g = gains(batch);
    for (size_t i = 0; i < batch.size(); ++i) {
      ShapeFit& f = fits[batch[i].search];
      if (g[i] > f.gain) f.gain = g[i], f.log_value = batch[i].x;
    }
  }
  std::vector<profile::Golden> golden(K);
  for (size_t k = 0; k < K; ++k) {
    golden[k].a = std::max(ranges[k].lo_log, fits[k].log_value - steps[k]);
    golden[k].b = std::min(ranges[k].hi_log, fits[k].log_value + steps[k]);
  }
  for (int step = 0; step < 22; ++step) {
    std::vector<ShapeQuery> batch;
    for (size_t k = 0; k < K; ++k) batch.push_back({k, golden[k].next(step)});
    const std::vector<double> g = gains(batch);
    for (size_t k = 0; k < K; ++k) golden[k].answer(g[k]);
  }
  std::vector<double> rss_best(K);
  std::vector<profile::Bound> bounds;
  for (size_t k = 0; k < K; ++k) {
    ShapeFit& f = fits[k];
    const profile::Golden& q = golden[k];
    if (std::max(q.f1, q.f2) > f.gain) f.log_value = q.f1 > q.f2 ? q.x1 : q.x2, f.gain = std::max(q.f1, q.f2);
    rss_best[k] = std::max(1e-300, rss - f.gain);
    bounds.emplace_back(-1.0, f.log_value, steps[k] / 8, ranges[k]);
    bounds.emplace_back(1.0, f.log_value, steps[k] / 8, ranges[k]);
  }
  for (;;) {
    std::vector<ShapeQuery> batch;
    std::vector<size_t> asked;
    for (size_t i = 0; i < bounds.size(); ++i)
      if (!bounds[i].done) batch.push_back({i / 2, bounds[i].query}), asked.push_back(i);
    if (batch.empty()) break;
    const std::vector<double> g = gains(batch);
    for (size_t n = 0; n < asked.size(); ++n) {
      const size_t k = asked[n] / 2;
      const bool inside = n_eff * std::log(std::max(1e-300, rss - g[n]) / rss_best[k]) <= 3.84;
      bounds[asked[n]].answer(inside, fits[k].log_value, ranges[k]);
    }
  }
  for (size_t k = 0; k < K; ++k) {
    ShapeFit& f = fits[k];
    const SearchRange& r = ranges[k];
    f.lo_log = bounds[2 * k].in;
    f.hi_log = bounds[2 * k + 1].in;
    f.unbounded = f.lo_log <= r.lo_log || f.hi_log >= r.hi_log || f.lo_log == f.log_value || f.hi_log == f.log_value;
  }
  return fits;
}

/// One profile search (profile_searches) over `points` log-spaced values in [lo_log, hi_log].
template <class Gains>
ShapeFit profile_search(Gains gains, double lo_log, double hi_log, int points, double rss, double n_eff) {
  return profile_searches(gains, {SearchRange{lo_log, hi_log, points}}, rss, n_eff)[0];
}

}  // namespace dyncal::host::detail
