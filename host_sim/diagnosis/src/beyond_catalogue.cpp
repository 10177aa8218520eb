#include "beyond_catalogue.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "dyncal_host/common/jackknife.hpp"
#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/common/normal_quantile.hpp"
#include "dyncal_host/common/spline_basis.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/identification/methods/signal.hpp"

namespace dyncal::host::detail {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// The model's prediction of joint i at the kept samples (S).
VectorXd model_torque(const CandidateContext& c, int i) {
  const int N = static_cast<int>(c.data.q.cols());
  const Index S = c.data.t.size();
  VectorXd p(S);
  for (Index s = 0; s < S; ++s) p[s] = c.model_X->row(s * N + i).dot(*c.model_phi);
  return p;
}

/// d/dt of x (S, at the kept samples t) by central differences inside each segment, one-sided at
/// its ends.
VectorXd time_derivative(const VectorXd& t, const std::vector<std::pair<Index, Index>>& segments, const VectorXd& x) {
  VectorXd out = VectorXd::Zero(x.size());
  for (const auto& [a, b] : segments) {
    if (b - a < 2) continue;
    for (Index s = a; s < b; ++s) {
      const Index lo = std::max(a, s - 1), hi = std::min(b - 1, s + 1);
      out[s] = (x[hi] - x[lo]) / (t[hi] - t[lo]);
    }
  }
  return out;
}

constexpr int kKnotCounts[] = {4, 8, 16};
/// Interior knots of the screening's splines (the middle of kKnotCounts).
constexpr int kScreenKnots = 8;
/// The penalised shapes: kPenalisedKnots interior knots, each penalty lambda set so that the
/// penalty's trace is rho times the (unpenalised) Gram's trace of the shape's columns, per fitted row
/// (scale-free: the variable's unit and the torque's cancel), for rho in kPenaltyRatios.
constexpr int kPenalisedKnots = 24;
constexpr double kPenaltyRatios[] = {1e-1, 1, 10, 100, 1000, 1e4};

/// The local fit of joint i's residual r (S) on columns C (S x m) alone: its BIC change against r,
/// n_eff log(RSS after / RSS before) + m log(n_eff), with n_eff the effective samples of the
/// residual after the fit (*n_eff_after): the noise's, not the structured residual's, whose long
/// correlation would make any evidence impossible on the joint where the effect is largest.
double local_bic(const MatrixXd& C, const VectorXd& r, double* n_eff_after) {
  const MatrixXd G = C.transpose() * C;
  const Eigen::LDLT<MatrixXd> f(G + 1e-12 * G.diagonal().maxCoeff() * MatrixXd::Identity(G.rows(), G.cols()));
  const VectorXd left = r - C * f.solve(C.transpose() * r);
  const double before = r.squaredNorm(), after = std::max(1e-300 * before, left.squaredNorm());
  const double n_eff = std::max(2.0, effective_samples(left));
  *n_eff_after = n_eff;
  return n_eff * std::log(after / before) + static_cast<double>(C.cols()) * std::log(n_eff);
}

}  // namespace

void torque_delay(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  const std::string name = "delay" + std::to_string(i + 1);
  if (std::find(c.model_names.begin(), c.model_names.end(), name) != c.model_names.end() ||
      std::find(c.refused.begin(), c.refused.end(), name) != c.refused.end())
    return;
  const int N = static_cast<int>(c.data.q.cols());
  const Index S = c.data.t.size();
  const VectorXd column_i = delay_column(c.data.t, c.segments, model_torque(c, i), 0.0);  // -d tau_model_i / dt
  Candidate k;
  k.effect = Effect::torque_delay;
  k.joints = {i};
  k.names = {name};
  k.columns = MatrixXd::Zero(S * N, 1);
  for (Index s = 0; s < S; ++s) k.columns(s * N + i, 0) = column_i[s];
  VectorXd r(S);
  MatrixXd column(S, 1);
  for (Index s = 0; s < S; ++s) {
    const bool fit = c.data.fit_row[s * N + i];
    r[s] = fit ? c.residual[s * N + i] : 0.0;
    column(s, 0) = fit ? column_i[s] : 0.0;
  }
  local_bic(column, r, &k.n_eff_after);
  out.push_back(std::move(k));
}

std::vector<char> torque_step_samples(const StackedData& d, const std::vector<std::pair<Index, Index>>& segments, int j,
                                      const VectorXd& p) {
  const Index S = d.t.size();
  std::vector<char> near(static_cast<size_t>(S), 0);
  if (d.tau_raw.rows() != S || d.cutoff_hz <= 0) return near;
  struct Pair {
    Index s, a, b;  // samples s, s + 1 of segment [a, b)
  };
  std::vector<Pair> at;
  std::vector<double> jump;
  for (const auto& [a, b] : segments)
    for (Index s = a; s + 1 < b; ++s) {
      at.push_back({s, a, b});
      jump.push_back((d.tau_raw(s + 1, j) - d.tau_raw(s, j)) - (p[s + 1] - p[s]));
    }
  if (jump.size() < 8) return near;
  std::vector<double> dev(jump.size());
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  const double centre = median(jump);
  for (size_t k = 0; k < jump.size(); ++k) dev[k] = std::abs(jump[k] - centre);
  const double scale = 1.4826 * median(dev);
  if (!(scale > 0)) return near;
  const Index span = static_cast<Index>(std::ceil(d.rate_hz / d.cutoff_hz));
  // A reversal's friction step is left in: the velocity crosses zero at a phase of its own each time,
  // so what each one's sampling misplaces averages out over them. A start or a stop (the sign to or
  // from 0, at rest) is not: a planned motion's starts and stops keep the controller's clock.
  auto reverses = [&](const Pair& k) {
    if (d.qd_raw.rows() != S) return false;
    bool up = false, down = false;
    for (Index s = std::max(k.a, k.s - span); s < std::min(k.b, k.s + 1 + span); ++s) {
      const double sign = friction_sign(d.qd_raw(s, j), d.standstill_band[j]);
      up = up || sign > 0, down = down || sign < 0;
    }
    return up && down;
  };
  for (size_t k = 0; k < at.size(); ++k) {
    if (dev[k] <= kStandstillQuantile * scale || reverses(at[k])) continue;
    for (Index s = std::max(at[k].a, at[k].s - span); s < std::min(at[k].b, at[k].s + 1 + span); ++s)
      near[static_cast<size_t>(s)] = 1;
  }
  return near;
}

VectorXd delay_column(const VectorXd& t, const std::vector<std::pair<Index, Index>>& segments, const VectorXd& p,
                      double delta0) {
  if (delta0 == 0.0) return -time_derivative(t, segments, p);
  VectorXd out = VectorXd::Zero(p.size());
  for (const auto& segment : segments) {
    const Index a = segment.first, b = segment.second;
    if (b - a < 4) continue;
    const double h = (t[b - 1] - t[a]) / static_cast<double>(b - a - 1);
    auto at = [&](Index k) { return p[std::clamp(k, a, b - 1)]; };
    for (Index s = a; s < b; ++s) {
      const double x = static_cast<double>(s - a) - delta0 / h;  // the instant t - delta0 in samples
      const Index k = static_cast<Index>(std::floor(x));
      const double u = x - static_cast<double>(k);
      const double p0 = at(a + k - 1), p1 = at(a + k), p2 = at(a + k + 1), p3 = at(a + k + 2);
      const double v = p1 + 0.5 * u * (p2 - p0 + u * (2 * p0 - 5 * p1 + 4 * p2 - p3 + u * (3 * (p1 - p2) + p3 - p0)));
      out[s] = (v - p[s]) / delta0;
    }
  }
  return out;
}

std::vector<std::string> shape_variables(int i, int num_joints) {
  const std::string J = std::to_string(i + 1);
  std::vector<std::string> v = {"t", "q" + J, "qd" + J, "qdd" + J, "tau_model" + J};
  for (int k : {i - 1, i + 1}) {
    if (k < 0 || k >= num_joints) continue;
    v.push_back("q" + std::to_string(k + 1));
    v.push_back("qd" + std::to_string(k + 1));
  }
  for (const std::string& x : {std::string("t"), "q" + J, "tau_model" + J}) v.push_back("sgn(qd" + J + ")*" + x);
  return v;
}

namespace {

/// The spline columns (S x m) of the variable `name` with `interior` interior knots on joint i's
/// rows (knots: spline_knots' vector; empty columns when the variable gives fewer than 3):
/// effect_model.hpp's shape_series, 0 on rows outside the fit. tau: the model's torque of joint i
/// (model_torque), read by a variable of tau_model.
MatrixXd shape_columns(const CandidateContext& c, int i, const std::string& name, int interior, const VectorXd& tau,
                       std::vector<double>& knots) {
  const StackedData& d = c.data;
  const int N = static_cast<int>(d.q.cols());
  const ShapeVariable v = parse_shape_variable(name, i, N);
  const VectorXd x = shape_variable_values(d, v, tau);
  knots = spline_knots(x, interior);
  if (knots.size() < 8) return MatrixXd();  // fewer than 3 columns: no shape to speak of
  MatrixXd series = shape_series(d, i, v, x, knots);
  for (Index s = 0; s < series.rows(); ++s)
    if (!d.fit_row[s * N + i]) series.row(s).setZero();
  return series;
}

/// Whether the model (its parameter names) already has a shape of `variable` on joint i: its
/// smoothness was chosen by cross-validation then, and a second spline of it would refit the same
/// function on other knots.
bool has_shape_of(const std::vector<std::string>& model_names, int i, const std::string& variable) {
  ModelEffect e;
  e.kind = EffectKind::shape;
  e.joint = i;
  e.variable = variable;
  e.knots = {0, 0, 0, 0, 1, 1, 1, 1};
  std::string prefix = effect_param_names(e).front();
  prefix.erase(prefix.find_last_of('_') + 1);  // "shape3_q3_2" -> "shape3_q3_"
  return std::any_of(model_names.begin(), model_names.end(), [&](const std::string& n) {
    return n.compare(0, prefix.size(), prefix) == 0 && n.size() > prefix.size() &&
           n.find_first_not_of("0123456789", prefix.size()) == std::string::npos;
  });
}

}  // namespace

void shape(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  const StackedData& d = c.data;
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  const std::vector<std::string> vars = shape_variables(i, N);
  const VectorXd tau = model_torque(c, i);
  VectorXd r(S);
  for (Index s = 0; s < S; ++s) r[s] = d.fit_row[s * N + i] ? c.residual[s * N + i] : 0.0;
  // Screening: every variable scored by the local BIC of its spline with kScreenKnots interior
  // knots on the joint's residual; the best goes to the cross-validated weighing with every knot
  // count (the weighing chooses it), each candidate counted as a search over the whole family.
  size_t best = vars.size();
  double best_bic = INFINITY, unused = 0;
  for (size_t v = 0; v < vars.size(); ++v) {
    if (has_shape_of(c.model_names, i, vars[v])) continue;
    std::vector<double> knots;
    const MatrixXd series = shape_columns(c, i, vars[v], kScreenKnots, tau, knots);
    if (series.cols() == 0) continue;
    const double bic = local_bic(series, r, &unused);
    if (bic < best_bic) best_bic = bic, best = v;
  }
  if (best == vars.size()) return;
  const int searched = static_cast<int>(vars.size() * (std::size(kKnotCounts) + std::size(kPenaltyRatios)));
  std::vector<int> fits(std::begin(kKnotCounts), std::end(kKnotCounts));
  // A shape of time is not penalised: a rich basis of t, smoothed only by the penalty, reaches the
  // cross-validation's blocks (0.5 s), and a function of t fitted on the neighbouring blocks then
  // predicts each held-out one by interpolation, whatever the residual's cause.
  if (!shape_of_time(vars[best])) fits.push_back(-kPenalisedKnots);  // penalised
  for (const int fit : fits) {
    const int interior = std::abs(fit);
    Candidate k;
    const MatrixXd series = shape_columns(c, i, vars[best], interior, tau, k.knots);
    if (series.cols() == 0) continue;
    local_bic(series, r, &k.n_eff_after);
    k.effect = Effect::shape;
    k.joints = {i};
    k.variable = vars[best];
    k.searched = searched;
    k.detail = "a cubic spline of " + k.variable + " with " + std::to_string(k.knots.size() - 8) + " interior knots";
    if (fit < 0) {
      k.roughness = shape_roughness_rows(k.knots, shape_without_linear(k.variable));
      double rows = 0;
      for (Index s = 0; s < S; ++s) rows += d.fit_row[s * N + i] ? 1.0 : 0.0;
      const double roughness = k.roughness.squaredNorm();  // tr(L^T L)
      if (!(roughness > 0) || rows < 1) continue;
      for (const double rho : kPenaltyRatios) k.penalty_grid.push_back(rho * series.squaredNorm() / (rows * roughness));
    }
    k.columns = MatrixXd::Zero(S * N, series.cols());
    ModelEffect effect;
    effect.kind = EffectKind::shape;
    effect.joint = i;
    effect.variable = k.variable;
    effect.knots = k.knots;
    k.names = effect_param_names(effect);
    for (Index b = 0; b < series.cols(); ++b)
      for (Index s = 0; s < S; ++s) k.columns(s * N + i, b) = series(s, b);
    out.push_back(std::move(k));
  }
}

std::pair<double, double> delay_interval(const StackedData& d, const MatrixXd& X, const VectorXd& phi,
                                         const VectorXd& weights, int j, double n_eff_j,
                                         const std::vector<double>& fold_delays, const std::vector<char>& steps,
                                         double raw_period, double* step_share) {
  const int N = static_cast<int>(d.q.cols());
  const Index rows = X.rows(), p = X.cols();
  MatrixXd A(rows, p - 1);
  VectorXd c(rows), r(rows);
  double rss_j = 0, n_j = 0;
  for (Index k = 0; k < rows; ++k) {
    const double w = d.fit_row[k] ? weights[k % N] : 0.0;
    A.row(k) = w * X.row(k).head(p - 1);
    c[k] = w * X(k, p - 1);
    r[k] = w * (d.y[k] - X.row(k).dot(phi));
    if (k % N == j && d.fit_row[k]) {
      rss_j += r[k] * r[k];
      n_j += 1;
    }
  }
  const VectorXd c_perp = c - A * A.colPivHouseholderQr().solve(c);
  const double s2 = rss_j / std::max(1.0, n_j - 1);
  const double se = std::sqrt(s2 / std::max(1e-300, c_perp.squaredNorm()) * n_j / std::max(1.0, n_eff_j));
  const double delta = phi[p - 1];
  double half = kZ95 * se;
  const size_t K = fold_delays.size();
  if (K >= 2) half = std::max(half, jackknife_half_width(K, [&](size_t k) { return fold_delays[k]; }));
  double from_steps = 0, all = 0;
  for (Index k = j; k < rows; k += N) {
    const double info = c_perp[k] * c_perp[k];
    all += info;
    if (steps[static_cast<size_t>(k / N)]) from_steps += info;
  }
  *step_share = all > 0 ? from_steps / all : 0.0;
  half += *step_share * 0.5 * raw_period;
  return {delta - half, delta + half};
}

}  // namespace dyncal::host::detail
