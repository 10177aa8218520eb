#include "dyncal_host/logs/uniform_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/number_text.hpp"
#include "dyncal_host/logs/sample_clock.hpp"

namespace dyncal::host {
namespace {

using Index = Eigen::Index;

/// Natural cubic spline through (x_i, Y.row(i)) for every column of Y at once (Thomas algorithm on
/// the tridiagonal system of the second derivatives; M_0 = M_n = 0).
class NaturalCubicSpline {
 public:
  NaturalCubicSpline(const Eigen::VectorXd& x, const Eigen::MatrixXd& y) : x_(x), y_(y) {
    const Index n = x.size() - 1;
    m_ = Eigen::MatrixXd::Zero(n + 1, y.cols());
    if (n < 2) return;
    Eigen::VectorXd c(n + 1);  // modified super-diagonal
    Eigen::MatrixXd d(n + 1, y.cols());
    for (Index i = 1; i < n; ++i) {
      const double h0 = x[i] - x[i - 1], h1 = x[i + 1] - x[i];
      const double lower = (i > 1) ? h0 : 0.0;
      const double diag = 2.0 * (h0 + h1) - lower * (i > 1 ? c[i - 1] : 0.0);
      c[i] = h1 / diag;
      d.row(i) = 6.0 * ((y.row(i + 1) - y.row(i)) / h1 - (y.row(i) - y.row(i - 1)) / h0);
      if (i > 1) d.row(i) -= lower * d.row(i - 1);
      d.row(i) /= diag;
    }
    m_.row(n - 1) = d.row(n - 1);
    for (Index i = n - 2; i >= 1; --i) m_.row(i) = d.row(i) - c[i] * m_.row(i + 1);
  }

  /// Values at the increasing times `at` into out (rows = at.size()).
  void evaluate(const Eigen::VectorXd& at, Eigen::Ref<Eigen::MatrixXd> out) const {
    Index i = 0;
    const Index n = x_.size() - 1;
    for (Index k = 0; k < at.size(); ++k) {
      while (i < n - 1 && at[k] > x_[i + 1]) ++i;
      const double h = x_[i + 1] - x_[i];
      const double A = (x_[i + 1] - at[k]) / h, B = 1.0 - A;
      out.row(k) = A * y_.row(i) + B * y_.row(i + 1) +
                   ((A * A * A - A) * m_.row(i) + (B * B * B - B) * m_.row(i + 1)) * (h * h / 6.0);
    }
  }

 private:
  const Eigen::VectorXd& x_;
  const Eigen::MatrixXd& y_;
  Eigen::MatrixXd m_;
};

/// The raw log's columns side by side: q | [qd] | [qdd] | tau.
Eigen::MatrixXd columns_of(const JointLog& log, Index a, Index b) {
  const int n = log.joints();
  const int blocks = 2 + (log.has_qd ? 1 : 0) + (log.has_qdd ? 1 : 0);
  Eigen::MatrixXd m(b - a, blocks * n);
  int c = 0;
  auto put = [&](const Eigen::MatrixXd& x) {
    m.middleCols(c, n) = x.middleRows(a, b - a);
    c += n;
  };
  put(log.q);
  if (log.has_qd) put(log.qd);
  if (log.has_qdd) put(log.qdd);
  put(log.tau);
  return m;
}

/// Each piece of `raw` ([first, end) rows, at least 3 samples spanning 3 grid samples; shorter ones
/// dropped) sampled at times[first] + k T by a natural cubic spline through (times, the raw
/// columns): q only with q_only. The pieces kept into kept_pieces (grid rows), the grid samples
/// beyond the raw ones into missing.
JointLog resample(const JointLog& raw, const Eigen::VectorXd& times, double T,
                  const std::vector<std::pair<Index, Index>>& pieces, bool q_only,
                  std::vector<std::pair<Index, Index>>& kept_pieces, long& missing) {
  std::vector<Eigen::VectorXd> grids;
  std::vector<std::pair<Index, Index>> kept;
  Index total = 0;
  missing = 0;
  for (const auto& [a, b] : pieces) {
    const Index n = static_cast<Index>(std::floor((times[b - 1] - times[a]) / T * (1 + 1e-12))) + 1;
    if (n < 3 || b - a < 3) continue;
    grids.push_back(times[a] + T * Eigen::VectorXd::LinSpaced(n, 0.0, static_cast<double>(n - 1)).array());
    kept.emplace_back(a, b);
    total += n;
    missing += std::max<long>(0, static_cast<long>(n - (b - a)));
  }
  JointLog out;
  out.source = raw.source;
  out.has_qd = raw.has_qd && !q_only;
  out.has_qdd = raw.has_qdd && !q_only;
  out.period = T;
  const int nj = raw.joints();
  out.t.resize(total);
  out.q.resize(total, nj);
  if (!q_only) out.tau.resize(total, nj);
  if (out.has_qd) out.qd.resize(total, nj);
  if (out.has_qdd) out.qdd.resize(total, nj);
  kept_pieces.clear();
  Index row = 0;
  for (size_t k = 0; k < kept.size(); ++k) {
    const auto [a, b] = kept[k];
    const Eigen::VectorXd& g = grids[k];
    if (row > 0) out.segment_starts.push_back(row);
    kept_pieces.emplace_back(row, row + g.size());
    const Eigen::VectorXd x = times.segment(a, b - a);
    const Eigen::MatrixXd y = q_only ? Eigen::MatrixXd(raw.q.middleRows(a, b - a)) : columns_of(raw, a, b);
    Eigen::MatrixXd v(g.size(), y.cols());
    NaturalCubicSpline(x, y).evaluate(g, v);
    out.t.segment(row, g.size()) = g;
    int c = 0;
    auto take = [&](Eigen::MatrixXd& to) {
      to.middleRows(row, g.size()) = v.middleCols(c, nj);
      c += nj;
    };
    take(out.q);
    if (out.has_qd) take(out.qd);
    if (out.has_qdd) take(out.qdd);
    if (!q_only) take(out.tau);
    row += g.size();
  }
  return out;
}

}  // namespace

namespace {

/// The log's sampling period [s]: the total time over the number of periods spanned, each step
/// counting as its nearest multiple of the period (gaps longer than max_gap left out). Throws
/// InputError for input segments (several logs) of different rates.
double log_period(const JointLog& raw, const std::vector<std::pair<Index, Index>>& input_segments, double max_gap) {
  // Input segments (several logs) must share one rate: interpolating one onto another's grid would
  // alias (no anti-alias filter on the way down) or invent samples (on the way up).
  double T = 0;
  for (const auto& seg : input_segments) {
    const double step = median_step(raw.t, {seg});
    if (!(step > 0)) throw InputError(raw.source + ": a log segment has fewer than 2 samples");
    if (T == 0) T = step;
    if (std::abs(step - T) > 0.01 * T) {
      throw InputError(raw.source + ": logs of different rates (" + number_text(1.0 / T) + " Hz and " +
                       number_text(1.0 / step) + " Hz at data row " + std::to_string(seg.first + 1) +
                       "): give logs of one rate");
    }
  }
  // The median step is biased by missing samples (their steps are 2T, 3T, ...) and jitter; the
  // period is the total time over the number of periods spanned, each step counting as its nearest
  // multiple of the period (twice, from the median and then from the first estimate).
  T = median_step(raw.t, input_segments);
  for (int pass = 0; pass < 2; ++pass) {
    double spanned = 0, periods = 0;
    for (const auto& [a, b] : input_segments) {
      for (Index i = a + 1; i < b; ++i) {
        const double step = raw.t[i] - raw.t[i - 1];
        const double m = std::round(step / T);
        if (m < 1 || step > std::max(max_gap, 1.5 * T)) continue;  // gaps say nothing of the period
        spanned += step;
        periods += m;
      }
    }
    if (periods > 0) T = spanned / periods;
  }
  return T;
}

/// The input segments split at gaps longer than max_gap (report's gaps, gap_seconds, jitter_rms);
/// `uniform` cleared when a step is a gap or off the period by more than kUniformStepTolerance.
std::vector<std::pair<Index, Index>> pieces_between_gaps(const JointLog& raw,
                                                         const std::vector<std::pair<Index, Index>>& input_segments,
                                                         double T, double max_gap, SamplingReport& report,
                                                         bool& uniform) {
  // Jitter: each step's distance to its nearest multiple of
  // the period (at least one). The grid only needs T to be the spacing it uses: the spline reads the
  // raw time stamps as they are, so a period a little off the logger's nominal one costs nothing.
  std::vector<std::pair<Index, Index>> pieces;
  double jitter2 = 0;
  long steps = 0;
  auto add_piece = [&](Index a, Index b) {
    pieces.emplace_back(a, b);
    for (Index i = a + 1; i < b; ++i) {
      const double step = raw.t[i] - raw.t[i - 1];
      const double e = step - std::max(1.0, std::round(step / T)) * T;
      jitter2 += e * e;
      ++steps;
    }
  };
  for (const auto& [a, b] : input_segments) {
    Index start = a;
    for (Index i = a + 1; i < b; ++i) {
      const double step = raw.t[i] - raw.t[i - 1];
      if (step > max_gap) {
        add_piece(start, i);
        start = i;
        ++report.gaps;
        report.gap_seconds += step;
        uniform = false;
        continue;
      }
      if (std::abs(step - T) > kUniformStepTolerance * T) uniform = false;
    }
    add_piece(start, b);
  }
  report.jitter_rms = steps > 0 ? std::sqrt(jitter2 / static_cast<double>(steps)) / T : 0.0;
  return pieces;
}

/// How much rougher the positions are on the stamps than on the estimated clock: the geometric mean
/// over the joints that move of the third-difference power's ratio clock / stamps (< 1: the clock is
/// smoother).
double roughness_ratio(const JointLog& on_stamps, const JointLog& on_clock) {
  const Eigen::VectorXd r_stamps = third_difference_power(on_stamps.q, on_stamps.segments());
  const Eigen::VectorXd r_clock = third_difference_power(on_clock.q, on_clock.segments());
  double log_ratio = 0;
  int moving = 0;
  for (Index j = 0; j < r_stamps.size(); ++j) {
    if (!(r_stamps[j] > 0.0) || !(r_clock[j] > 0.0)) continue;
    log_ratio += std::log(r_clock[j] / r_stamps[j]);
    ++moving;
  }
  return moving > 0 ? std::exp(log_ratio / moving) : 1.0;
}

}  // namespace

JointLog to_uniform_grid(JointLog raw, double max_gap, SamplingReport& report) {
  report = SamplingReport{};
  const Index S = raw.samples();
  report.raw_samples = static_cast<long>(S);
  if (S < 3) throw InputError(raw.source + ": fewer than 3 samples");
  for (Index i = 1; i < S; ++i) {
    if (!(raw.t[i] > raw.t[i - 1])) {
      throw InputError(raw.source + ": time is not strictly increasing at data row " + std::to_string(i + 1) +
                       " (t = " + number_text(raw.t[i]) + " s after " + number_text(raw.t[i - 1]) + " s)");
    }
  }
  report.repeated = drop_repeated_samples(raw);
  if (raw.samples() < 3) throw InputError(raw.source + ": fewer than 3 samples after its repeated rows");
  const auto input_segments = raw.segments();
  double T = log_period(raw, input_segments, max_gap);
  report.period = T;
  report.raw_rate_hz = 1.0 / T;
  max_gap = std::max(max_gap, 1.5 * T);  // a single period is never a gap
  // Pieces: input segments split at gaps.
  bool uniform = true;
  const std::vector<std::pair<Index, Index>> pieces =
      pieces_between_gaps(raw, input_segments, T, max_gap, report, uniform);
  if (uniform) {
    report.grid_samples = report.raw_samples;
    report.segments = static_cast<int>(input_segments.size());
    raw.period = T;
    return raw;  // moved: a uniform log is not copied
  }
  report.resampled = true;
  // The sampling instants: the stamps, or the logger's regular clock estimated from them
  // (sample_clock.hpp), whichever puts the positions on the grid more smoothly (third-difference
  // power, geometric mean over the joints that move): a stamp error dt adds qd dt of white noise.
  const SampleClock clock = estimate_sample_clock(raw.t, input_segments, T);
  report.stamp_jitter = clock.stamp_jitter;
  report.clock_missing = clock.missing;
  std::vector<std::pair<Index, Index>> grid_pieces;
  long missing = 0;
  const JointLog on_stamps = resample(raw, raw.t, T, pieces, true, grid_pieces, missing);
  const JointLog on_clock = resample(raw, clock.t, clock.period, pieces, true, grid_pieces, missing);
  report.roughness_ratio = roughness_ratio(on_stamps, on_clock);
  report.clock_used = report.roughness_ratio < 1.0;
  if (report.clock_used) {
    raw.t = clock.t;
    T = clock.period;
    report.period = T;
    report.raw_rate_hz = 1.0 / T;
  }
  JointLog out = resample(raw, raw.t, T, pieces, false, grid_pieces, missing);
  if (out.t.size() == 0) throw InputError(raw.source + ": no stretch of at least 3 samples without a gap");
  report.missing = missing;
  report.grid_samples = static_cast<long>(out.t.size());
  report.segments = static_cast<int>(grid_pieces.size());
  return out;
}

std::string describe(const SamplingReport& r, double max_gap) {
  char repeated[400] = "";
  if (r.repeated.dropped > 0)
    std::snprintf(repeated, sizeof repeated,
                  "; %ld repeated rows dropped (%ld run%s identical to the row before while the arm moved, the longest "
                  "%ld rows from t = %.6g s: a logger re-writing its last reading), treated as missing samples",
                  r.repeated.dropped, r.repeated.runs, r.repeated.runs == 1 ? "" : "s", r.repeated.longest,
                  r.repeated.longest_at);
  if (r.repeated.kept_at_rest > 0)
    std::snprintf(repeated + std::strlen(repeated), sizeof repeated - std::strlen(repeated),
                  "; %ld repeated rows kept (the arm at rest across them)", r.repeated.kept_at_rest);
  char line[512];
  if (!r.resampled) {
    std::snprintf(line, sizeof line, "sampling: %.6g Hz, uniform, %ld samples in %d segment%s", r.raw_rate_hz,
                  r.grid_samples, r.segments, r.segments == 1 ? "" : "s");
    return line + std::string(repeated);
  }
  std::snprintf(
      line, sizeof line,
      "sampling: raw %.6g Hz (period %.4g ms), step jitter RMS %.3g %% of the period; resampled to a "
      "uniform grid by cubic spline: %ld raw -> %ld grid samples (%ld, %.2g %%, more: missing samples bridged); "
      "%d gap%s longer than %.4g ms (%.4g s in all) split the log: %d segment%s",
      r.raw_rate_hz, 1e3 * r.period, 100.0 * r.jitter_rms, r.raw_samples, r.grid_samples, r.missing,
      100.0 * static_cast<double>(r.missing) / static_cast<double>(std::max(1L, r.grid_samples)), r.gaps,
      r.gaps == 1 ? "" : "s", 1e3 * max_gap, r.gap_seconds, r.segments, r.segments == 1 ? "" : "s");
  char clock[400];
  std::snprintf(clock, sizeof clock,
                "; sampling instants: %s (the stamps lie %.3g %% of the period RMS off a regular clock with %ld "
                "ticks missing; positions on the grid %.3g times as rough through the clock as through the "
                "stamps)",
                r.clock_used ? "the logger's regular clock estimated from the stamps" : "the time stamps",
                100.0 * r.stamp_jitter, r.clock_missing, r.roughness_ratio);
  return std::string(line) + clock + repeated;
}

JointLog stack_logs(std::vector<JointLog> logs) {
  if (logs.empty()) throw InputError("no log given");
  if (logs.size() == 1) return std::move(logs.front());
  const JointLog& first = logs.front();
  Index total = 0;
  for (const JointLog& l : logs) {
    if (l.joints() != first.joints() || l.has_qd != first.has_qd || l.has_qdd != first.has_qdd)
      throw InputError(l.source + ": columns differ from " + first.source +
                       " (joints, measured qd, qdd): stacked logs must have the same columns");
    if (l.samples() < 3) throw InputError(l.source + ": fewer than 3 samples");
    total += l.samples();
  }
  JointLog out = sized_like(first, total);
  out.source.clear();
  Index row = 0;
  double shift_to = 0;
  for (const JointLog& l : logs) {
    const Index m = l.samples();
    if (row > 0) {
      out.segment_starts.push_back(row);
      out.source += " + ";
    }
    for (const Index s : l.segment_starts) out.segment_starts.push_back(row + s);
    out.source += l.source;
    out.t.segment(row, m) = l.t.array() - l.t[0] + shift_to;
    out.q.middleRows(row, m) = l.q;
    out.tau.middleRows(row, m) = l.tau;
    if (out.has_qd) out.qd.middleRows(row, m) = l.qd;
    if (out.has_qdd) out.qdd.middleRows(row, m) = l.qdd;
    shift_to = out.t[row + m - 1] + l.sample_period();
    row += m;
  }
  return out;
}

}  // namespace dyncal::host
