#include "candidates.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

#include "dyncal/friction.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/signal.hpp"
#include "harmonic_fit.hpp"

namespace dyncal::host::detail {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

std::string J(int j) {
  return std::to_string(j + 1);
}

/// A candidate whose columns are lib/'s effect_columns of `kind` on joint i (and, for a coupling,
/// joint j with the motor's sign), with the load torque `tau_load` (S N) where the kind reads one.
Candidate table_candidate(const CandidateContext& c, Effect effect, EffectKind kind, std::vector<int> joints,
                          std::vector<std::string> names, double shape, double sign,
                          const VectorXd* tau_load = nullptr) {
  const StackedData& d = c.data;
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  Candidate out;
  out.effect = effect;
  out.joints = std::move(joints);
  out.names = std::move(names);
  out.columns = MatrixXd::Zero(S * N, static_cast<Index>(out.names.size()));
  out.shape = shape;
  out.sign = sign;
  const int i = out.joints.front(), j = out.joints.back();
  double cols[3];
  for (Index s = 0; s < S; ++s) {
    const double load = tau_load ? (*tau_load)[s * N + i] : 0.0;
    const int m =
        effect_columns(kind, shape, sign, d.q(s, i), d.qd(s, i), d.qdd(s, i), d.qd(s, j), d.qdd(s, j), load, cols);
    for (int k = 0; k < m; ++k) {
      out.columns(s * N + i, k) = cols[k];
      if (kind == EffectKind::coupling) out.columns(s * N + j, k) = sign * cols[k];
    }
  }
  return out;
}

/// Of one-column alternatives, the one whose column explains most of the residual (its
/// projection), counted as a search over all of them.
Candidate best_of(std::vector<Candidate> alternatives, const VectorXd& residual) {
  size_t best = 0;
  double best_gain = -1;
  for (size_t i = 0; i < alternatives.size(); ++i) {
    const VectorXd col = alternatives[i].columns.col(0);
    const double gain = std::pow(col.dot(residual), 2) / std::max(1e-300, col.squaredNorm());
    if (gain > best_gain) {
      best_gain = gain;
      best = i;
    }
  }
  Candidate c = std::move(alternatives[best]);
  c.searched = static_cast<int>(alternatives.size());
  return c;
}

bool has(const CandidateContext& c, const std::string& name) {
  return std::find(c.model_names.begin(), c.model_names.end(), name) != c.model_names.end();
}

// --- generators: the candidates of one kind for joint i (coupling: joints i < j)

void stribeck(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  // Static friction: the best velocity scale of a small grid, relative to the joint's top speed.
  const double vmax = c.data.qd.col(i).cwiseAbs().maxCoeff();
  std::vector<Candidate> alternatives;
  for (double frac : {0.02, 0.05, 0.1, 0.2}) {
    const double qds = frac * vmax;
    alternatives.push_back(table_candidate(c, Effect::stribeck, EffectKind::stribeck, {i}, {"Fs" + J(i)}, qds, 1.0));
    alternatives.back().detail = "velocity scale " + std::to_string(qds).substr(0, 5) + " rad/s";
  }
  out.push_back(best_of(std::move(alternatives), c.residual));
}

void asymmetric_friction(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  out.push_back(table_candidate(c, Effect::asymmetric_friction, EffectKind::asymmetric_friction, {i},
                                {"Fc+" + J(i), "Fv+" + J(i)}, 0.0, 1.0));
}

void velocity_power(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  out.push_back(table_candidate(c, Effect::velocity_power, EffectKind::velocity_power, {i}, {"Fp" + J(i)}, 0.0, 1.0));
}

void load_friction(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  // The load torque that explains the residual better (counted as a search).
  std::vector<Candidate> alternatives;
  for (const auto& [what, tau_load] : c.load_torques) {
    alternatives.push_back(
        table_candidate(c, Effect::load_friction, EffectKind::load_friction, {i}, {"Fl" + J(i)}, 0.0, 1.0, &tau_load));
    alternatives.back().detail = what;
  }
  out.push_back(best_of(std::move(alternatives), c.residual));
}

void rotor_inertia(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  if (has(c, "Ia" + J(i))) return;
  out.push_back(table_candidate(c, Effect::rotor_inertia, EffectKind::rotor_inertia, {i}, {"Ia" + J(i)}, 0.0, 1.0));
}

void offset(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  if (has(c, "offset" + J(i))) return;
  out.push_back(table_candidate(c, Effect::offset, EffectKind::offset, {i}, {"offset" + J(i)}, 0.0, 1.0));
}

void position_periodic(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  // Spectral search of the residual over q_i (integer cycles per revolution).
  const StackedData& d = c.data;
  const int N = static_cast<int>(d.q.cols());
  int best_k = 0;
  double best_power = -1;
  for (int k = 1; k <= c.max_cycles; ++k) {
    const std::optional<double> power =
        harmonic_rss_reduction(d.q, i, k, [&](Index s) { return c.residual[s * N + i]; });
    if (power && *power > best_power) {
      best_power = *power;
      best_k = k;
    }
  }
  if (best_k == 0) return;
  out.push_back(table_candidate(c, Effect::position_periodic, EffectKind::position_periodic, {i},
                                {"A" + J(i) + "_sin", "A" + J(i) + "_cos"}, best_k, 1.0));
  out.back().detail = std::to_string(best_k) + " cycles per revolution";
  out.back().searched = c.max_cycles;
}

/// The model's columns local to joints i and j (non-zero only on their rows: their friction,
/// rotor inertia, offset and effect terms), the ones a coupling's columns trade off with.
std::vector<Index> local_columns(const CandidateContext& c, int i, int j) {
  const MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(c.data.q.cols());
  std::vector<Index> out;
  for (Index k = 0; k < X.cols(); ++k) {
    bool on_pair = false, elsewhere = false;
    for (Index r = 0; r < X.rows() && !elsewhere; ++r) {
      if (X(r, k) == 0.0) continue;
      const int joint = static_cast<int>(r % N);
      if (joint == i || joint == j)
        on_pair = true;
      else
        elsewhere = true;
    }
    if (on_pair && !elsewhere) out.push_back(k);
  }
  return out;
}

/// How much of the weighted residual of joints i and j a motor turning with qd_i + r qd_j explains
/// once it is fitted jointly with the model's columns local to the pair (Frisch-Waugh: the residual
/// is already orthogonal to them, so the gain is g^T S^-1 g with S the Schur complement of their
/// Gram). Its columns: sgn(v), v, a (v = qd_i + r qd_j, a = qdd_i + r qdd_j) on joint i and r times
/// them on joint j. Returns the weighted RSS it removes.
double coupling_gain(const CandidateContext& c, int i, int j, const std::vector<Index>& local, double r) {
  const StackedData& d = c.data;
  const MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(d.q.cols());
  const Index k = static_cast<Index>(local.size());
  const double w2[2] = {c.joint_weights[i] * c.joint_weights[i], c.joint_weights[j] * c.joint_weights[j]};
  MatrixXd LL = MatrixXd::Zero(k, k), LC = MatrixXd::Zero(k, 3);
  Eigen::Matrix3d CC = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  VectorXd l(k);
  for (Index s = 0; s < d.t.size(); ++s) {
    const double v = d.qd(s, i) + r * d.qd(s, j), a = d.qdd(s, i) + r * d.qdd(s, j);
    const Eigen::Vector3d x(v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0), v, a);
    const int joints[2] = {i, j};
    const double scale[2] = {1.0, r};
    for (int p = 0; p < 2; ++p) {
      const Index row = s * N + joints[p];
      const Eigen::Vector3d cx = scale[p] * x;
      for (Index q = 0; q < k; ++q) l[q] = X(row, local[static_cast<size_t>(q)]);
      LL.noalias() += w2[p] * l * l.transpose();
      LC.noalias() += w2[p] * l * cx.transpose();
      CC.noalias() += w2[p] * cx * cx.transpose();
      g += w2[p] * c.residual[row] * cx;
    }
  }
  const double ridge = 1e-12 * std::max(1.0, CC.diagonal().maxCoeff());
  Eigen::Matrix3d schur = CC;
  if (k > 0) {
    LL.diagonal().array() += 1e-12 * std::max(1.0, LL.diagonal().maxCoeff());
    schur -= LC.transpose() * LL.ldlt().solve(LC);
  }
  schur.diagonal().array() += ridge;
  return std::max(0.0, g.dot(schur.ldlt().solve(g)));
}

void coupling(const CandidateContext& c, int i, int j, std::vector<Candidate>& out) {
  // A motor turning with q_i + r q_j whose friction and inertia act on joint i and, by the
  // transmission's transpose, r times on joint j. The ratio r is searched on a log grid of
  // kRatioGrid values per sign over [1 / kRatioSpan, kRatioSpan] (1 included), refined by golden
  // section between the best point's neighbours, and given a 95 % profile interval: the ratios
  // whose residual a likelihood-ratio test (chi^2_1, 3.84, with the pair's effective samples)
  // cannot tell from the best.
  constexpr int kRatioGrid = 33;
  constexpr double kRatioSpan = 5.0;
  const double step = 2.0 * std::log(kRatioSpan) / (kRatioGrid - 1);
  const std::vector<Index> local = local_columns(c, i, j);
  auto log_ratio = [&](int k) { return -std::log(kRatioSpan) + k * step; };
  double gains[2][kRatioGrid];
  double best_gain = -1, best_log = 0;
  int best_k = 0, best_side = 0;
  for (int side = 0; side < 2; ++side)
    for (int k = 0; k < kRatioGrid; ++k) {
      gains[side][k] = coupling_gain(c, i, j, local, (side == 0 ? 1.0 : -1.0) * std::exp(log_ratio(k)));
      if (gains[side][k] > best_gain) best_gain = gains[side][k], best_k = k, best_side = side;
    }
  const double best_sign = best_side == 0 ? 1.0 : -1.0;
  best_log = log_ratio(best_k);
  // Golden section on log r between the neighbours of the best grid point.
  auto gain_at = [&](double lr) { return coupling_gain(c, i, j, local, best_sign * std::exp(lr)); };
  double lo = best_log - step, hi = best_log + step;
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo), f1 = gain_at(x1), f2 = gain_at(x2);
  for (int it = 0; it < 20; ++it) {
    if (f1 > f2) {
      hi = x2, x2 = x1, f2 = f1, x1 = hi - phi * (hi - lo), f1 = gain_at(x1);
    } else {
      lo = x1, x1 = x2, f1 = f2, x2 = lo + phi * (hi - lo), f2 = gain_at(x2);
    }
  }
  if (std::max(f1, f2) > best_gain) best_log = f1 > f2 ? x1 : x2, best_gain = std::max(f1, f2);
  const double r = best_sign * std::exp(best_log);
  // Profile interval: the weighted RSS of the pair after the effect against the best's, walked out
  // on the grid and bisected at each boundary; clipped to the searched span.
  const int N = static_cast<int>(c.data.q.cols());
  double rss0 = 0;
  VectorXd ri(c.data.t.size()), rj(c.data.t.size());
  for (Index s = 0; s < c.data.t.size(); ++s) {
    ri[s] = c.residual[s * N + i];
    rj[s] = c.residual[s * N + j];
    rss0 += std::pow(c.joint_weights[i] * ri[s], 2) + std::pow(c.joint_weights[j] * rj[s], 2);
  }
  const double n_eff = 0.5 * (effective_samples(ri) + effective_samples(rj));
  const double rss_best = std::max(1e-300, rss0 - best_gain);
  auto inside_gain = [&](double gain) { return n_eff * std::log(std::max(1e-300, rss0 - gain) / rss_best) <= 3.84; };
  // Each bound: steps out from the best, doubling from step / 8, to the first ratio outside (or
  // the searched span's end: an open bound), then bisection.
  const double span_lo = log_ratio(0), span_hi = log_ratio(kRatioGrid - 1);
  auto bound = [&](int dir) {
    double in = best_log, width = step / 8;
    for (;;) {
      const double next = std::clamp(best_log + dir * width, span_lo, span_hi);
      if (!inside_gain(gain_at(next))) {
        double outside = next;
        for (int it = 0; it < 10; ++it) {
          const double mid = 0.5 * (in + outside);
          (inside_gain(gain_at(mid)) ? in : outside) = mid;
        }
        return in;
      }
      in = next;
      if (next == span_lo || next == span_hi) return next;
      width *= 2;
    }
  };
  const double lo_log = bound(-1), hi_log = bound(+1);
  const std::string tag = J(i) + (r > 0 ? "+" : "-") + J(j);
  Candidate cand =
      table_candidate(c, Effect::coupling, EffectKind::coupling, {i, j}, {"Fc" + tag, "Fv" + tag, "Ia" + tag}, 0.0, r);
  cand.sign = r > 0 ? 1.0 : -1.0;
  cand.shape = std::abs(r);
  cand.shape_interval = {std::exp(lo_log), std::exp(hi_log)};
  std::ostringstream detail;
  detail << std::setprecision(3) << "motor turning with q" << J(i) << (r > 0 ? " + " : " - ") << std::abs(r) << " q"
         << J(j) << " (ratio 95 % " << std::exp(lo_log) << ".." << std::exp(hi_log) << ")";
  cand.detail = detail.str();
  cand.searched = 2 * kRatioGrid;
  out.push_back(std::move(cand));
}

void drift(const CandidateContext& c, int i, int, std::vector<Candidate>& out) {
  // Viscous friction and offset changing linearly over the log (temperature).
  const StackedData& d = c.data;
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  const double duration = static_cast<double>(S) / d.rate_hz;
  Candidate k;
  k.effect = Effect::drift;
  k.joints = {i};
  k.names = {"dFv" + J(i), "doffset" + J(i)};
  k.columns = MatrixXd::Zero(S * N, 2);
  for (Index s = 0; s < S; ++s) {
    const double tau_t = (d.t[s] - d.t[0]) / duration;  // 0..1 over the log
    k.columns(s * N + i, 0) = tau_t * d.qd(s, i);
    k.columns(s * N + i, 1) = tau_t;
  }
  out.push_back(std::move(k));
}

// --- physical signs of the fitted parameters

bool any_sign(const VectorXd&) {
  return true;
}
/// Static friction exceeds Coulomb friction (Eq. 4), rotor inertia is positive, load-dependent
/// friction opposes motion.
bool first_positive(const VectorXd& added) {
  return added[0] > 0;
}
/// A coupled motor's friction opposes motion (its inertia may be about 0).
bool friction_non_negative(const VectorXd& added) {
  return added[0] >= 0 && added[1] >= 0;
}

// --- explanations

std::string text(const std::ostringstream& s) {
  return s.str();
}

std::string explain_stribeck(const Candidate& c, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "extra torque at low speed with the sign of q_dot (" << c.detail
    << "), Fs - Fc = " << p[0] << " Nm - static friction / Stribeck";
  return text(s);
}
std::string explain_asymmetric(const Candidate&, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "friction differs with the direction of motion: +" << p[0] << " Nm, +" << p[1]
    << " Nm s/rad for q_dot > 0 - asymmetric friction";
  return text(s);
}
std::string explain_velocity_power(const Candidate&, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "friction grows with q_dot^(1/3), f1 = " << p[0] << " - velocity-power friction (Eq. 8)";
  return text(s);
}
std::string explain_load_friction(const Candidate& c, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "friction grows with the load torque (" << c.detail << "), f1 = " << p[0]
    << " - load-dependent friction (Eq. 9)";
  return text(s);
}
std::string explain_rotor_inertia(const Candidate&, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "residual follows q_ddot, Ia = " << p[0] << " kg m^2 - rotor inertia";
  return text(s);
}
std::string explain_offset(const Candidate&, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "constant torque " << p[0] << " Nm - torque offset";
  return text(s);
}
std::string explain_periodic(const Candidate& c, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "residual periodic in q" << c.joints[0] + 1 << " with " << c.detail << ", amplitude "
    << std::hypot(p[0], p[1]) << " Nm - cogging or gear ripple";
  return text(s);
}
std::string explain_coupling(const Candidate& c, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "a " << c.detail << " adds friction Fc " << p[0] << " Nm, Fv " << p[1]
    << " Nm s/rad and inertia " << p[2] << " kg m^2 shared by both joints - transmission coupling";
  return text(s);
}
std::string explain_drift(const Candidate&, const std::vector<double>& p) {
  std::ostringstream s;
  s << std::setprecision(3) << "viscous friction changes by " << p[0] << " Nm s/rad and the offset by " << p[1]
    << " Nm over the log - drift (temperature)";
  return text(s);
}

std::string joint_list(const std::vector<int>& joints) {
  std::string s;
  for (size_t i = 0; i < joints.size(); ++i)
    s += (i ? (i + 1 == joints.size() ? " and " : ", ") : "") + std::to_string(joints[i] + 1);
  return s;
}

}  // namespace

const std::vector<EffectSpec>& effect_specs() {
  static const std::vector<EffectSpec> table = {
      {Effect::stribeck, "stribeck", EffectKind::stribeck, false, stribeck, first_positive, explain_stribeck},
      {Effect::asymmetric_friction, "asymmetric_friction", EffectKind::asymmetric_friction, false, asymmetric_friction,
       any_sign, explain_asymmetric},
      {Effect::velocity_power, "velocity_power", EffectKind::velocity_power, false, velocity_power, any_sign,
       explain_velocity_power},
      {Effect::load_friction, "load_friction", EffectKind::load_friction, false, load_friction, first_positive,
       explain_load_friction},
      {Effect::rotor_inertia, "rotor_inertia", EffectKind::rotor_inertia, false, rotor_inertia, first_positive,
       explain_rotor_inertia},
      {Effect::offset, "offset", EffectKind::offset, false, offset, any_sign, explain_offset},
      {Effect::position_periodic, "position_periodic", EffectKind::position_periodic, false, position_periodic,
       any_sign, explain_periodic},
      {Effect::coupling, "coupling", EffectKind::coupling, true, coupling, friction_non_negative, explain_coupling},
      {Effect::drift, "drift", std::nullopt, false, drift, any_sign, explain_drift},
  };
  return table;
}

const EffectSpec& effect_spec(Effect e) {
  for (const EffectSpec& s : effect_specs())
    if (s.effect == e) return s;
  throw std::logic_error("effect without a table entry");
}

std::vector<Candidate> candidate_library(const CandidateContext& c) {
  const int N = static_cast<int>(c.data.q.cols());
  std::vector<Candidate> out;
  for (int i = 0; i < N; ++i)
    for (const EffectSpec& s : effect_specs())
      if (!s.per_pair) s.generate(c, i, i, out);
  for (int i = 0; i < N; ++i)
    for (int j = i + 1; j < N; ++j)
      for (const EffectSpec& s : effect_specs())
        if (s.per_pair) s.generate(c, i, j, out);
  return out;
}

std::string explain(const Candidate& c, const std::vector<double>& params) {
  return "joint" + std::string(c.joints.size() > 1 ? "s " : " ") + joint_list(c.joints) + ": " +
         effect_spec(c.effect).explain(c, params);
}

}  // namespace dyncal::host::detail

namespace dyncal::host {

const char* effect_name(Effect e) {
  return detail::effect_spec(e).name;
}

}  // namespace dyncal::host
