#pragma once
// A candidate's shape parameter (a Stribeck velocity scale, a coupling's ratio) found by a profile
// search (private to host_sim/diagnosis): the weighted residual RSS the candidate's columns remove,
// fitted jointly with the model's columns local to its joints (Frisch-Waugh), maximised over a log
// grid, refined by golden section, with a 95 % profile-likelihood interval.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "candidates.hpp"
#include "dyncal_host/identification/signal.hpp"

namespace dyncal::host::detail {

/// The model's columns local to `joints` (non-zero only on their rows: their friction, rotor
/// inertia, offset and effect terms), the ones a candidate on those joints trades off with.
inline std::vector<Eigen::Index> local_columns(const CandidateContext& c, const std::vector<int>& joints) {
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(c.data.q.cols());
  std::vector<Eigen::Index> out;
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    bool on = false, elsewhere = false;
    for (Eigen::Index r = 0; r < X.rows() && !elsewhere; ++r) {
      if (X(r, k) == 0.0) continue;
      if (std::find(joints.begin(), joints.end(), static_cast<int>(r % N)) != joints.end())
        on = true;
      else
        elsewhere = true;
    }
    if (on && !elsewhere) out.push_back(k);
  }
  return out;
}

/// The weighted RSS that M columns remove from the residual of `joints` when fitted with the local
/// columns `local` (the residual is already orthogonal to those, so the gain is g^T S^-1 g, S the
/// Schur complement of their Gram). columns(s, p, x) writes joint joints[p]'s row of the M columns
/// at sample s into x. A fit whose coefficients (S^-1 g, those of the joint fit) are not
/// physical(coefficients) removes nothing: the search looks only among physical shapes.
template <int M, class Columns, class Physical>
double local_gain(const CandidateContext& c, EffectKind kind, const std::vector<int>& joints,
                  const std::vector<Eigen::Index>& local, Columns columns, Physical physical) {
  using Vec = Eigen::Matrix<double, M, 1>;
  const StackedData& d = c.data;
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(d.q.cols());
  const Eigen::Index k = static_cast<Eigen::Index>(local.size());
  // The columns over time, filtered as the regressor was (filter_in_time: kind's columns).
  const Eigen::Index S = d.t.size(), P = static_cast<Eigen::Index>(joints.size());
  Eigen::MatrixXd series(S, M * P);
  Vec x;
  for (Eigen::Index s = 0; s < S; ++s)
    for (Eigen::Index p = 0; p < P; ++p) {
      columns(s, static_cast<size_t>(p), x);
      series.row(s).segment(p * M, M) = x.transpose();
    }
  filter_in_time(c, series, kind, M);
  // Weighted rows of the pair: local columns L, candidate columns C, residual r; the Grams by
  // matrix products.
  const Eigen::Index R = S * P;
  Eigen::MatrixXd L(R, k), C(R, M);
  Eigen::VectorXd r(R);
  for (Eigen::Index s = 0; s < S; ++s) {
    for (Eigen::Index p = 0; p < P; ++p) {
      const int j = joints[static_cast<size_t>(p)];
      const Eigen::Index row = s * N + j, out = s * P + p;
      const double w = c.joint_weights[j];
      for (Eigen::Index q = 0; q < k; ++q) L(out, q) = w * X(row, local[static_cast<size_t>(q)]);
      C.row(out) = w * series.row(s).segment(p * M, M);
      r[out] = w * c.residual[row];
    }
  }
  Eigen::MatrixXd LL(k, k), LC(k, M);
  if (k > 0) {
    LL.noalias() = L.transpose() * L;
    LC.noalias() = L.transpose() * C;
  }
  const Eigen::Matrix<double, M, M> CC = C.transpose() * C;
  const Vec g = C.transpose() * r;
  Eigen::Matrix<double, M, M> schur = CC;
  if (k > 0) {
    LL.diagonal().array() += 1e-12 * std::max(1.0, LL.diagonal().maxCoeff());
    schur -= LC.transpose() * LL.ldlt().solve(LC);
  }
  schur.diagonal().array() += 1e-12 * std::max(1.0, CC.diagonal().maxCoeff());
  const Vec beta = schur.ldlt().solve(g);
  if (!physical(beta)) return 0.0;
  return std::max(0.0, g.dot(beta));
}

/// A shape found by profile search: log of its value, the gain there, and the 95 % interval.
struct ShapeFit {
  double log_value = 0, gain = -1, lo_log = 0, hi_log = 0;
};

/// The weighted RSS of `joints`' residual (the profile's reference) and its effective samples (the
/// joints' mean, effective_samples).
inline void residual_scale(const CandidateContext& c, const std::vector<int>& joints, double& rss, double& n_eff) {
  const int N = static_cast<int>(c.data.q.cols());
  const Eigen::Index S = c.data.t.size();
  rss = 0;
  n_eff = 0;
  Eigen::VectorXd r(S);
  for (int j : joints) {
    for (Eigen::Index s = 0; s < S; ++s) r[s] = c.residual[s * N + j];
    rss += c.joint_weights[j] * c.joint_weights[j] * r.squaredNorm();
    n_eff += effective_samples(r) / static_cast<double>(joints.size());
  }
}

/// Maximises gain(log x) over `points` log-spaced values in [lo_log, hi_log], refines by golden
/// section between the best point's neighbours, and gives the 95 % profile interval: the values
/// whose RSS a likelihood-ratio test (chi^2_1 3.84 with n_eff samples) cannot tell from the best's,
/// stepping out from the best (doubling from an eighth of the grid step) to the first value outside
/// and bisecting; clipped to the searched range (an open bound).
template <class Gain>
ShapeFit profile_search(Gain gain, double lo_log, double hi_log, int points, double rss, double n_eff) {
  const double step = (hi_log - lo_log) / (points - 1);
  ShapeFit f;
  for (int k = 0; k < points; ++k) {
    const double g = gain(lo_log + k * step);
    if (g > f.gain) f.gain = g, f.log_value = lo_log + k * step;
  }
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double a = std::max(lo_log, f.log_value - step), b = std::min(hi_log, f.log_value + step);
  double x1 = b - phi * (b - a), x2 = a + phi * (b - a), f1 = gain(x1), f2 = gain(x2);
  for (int it = 0; it < 20; ++it) {
    if (f1 > f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - phi * (b - a), f1 = gain(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + phi * (b - a), f2 = gain(x2);
    }
  }
  if (std::max(f1, f2) > f.gain) f.log_value = f1 > f2 ? x1 : x2, f.gain = std::max(f1, f2);
  const double rss_best = std::max(1e-300, rss - f.gain);
  auto inside = [&](double lx) { return n_eff * std::log(std::max(1e-300, rss - gain(lx)) / rss_best) <= 3.84; };
  auto bound = [&](int dir) {
    double in = f.log_value, width = step / 8;
    for (;;) {
      const double next = std::clamp(f.log_value + dir * width, lo_log, hi_log);
      if (!inside(next)) {
        double outside = next;
        for (int it = 0; it < 10; ++it) {
          const double mid = 0.5 * (in + outside);
          (inside(mid) ? in : outside) = mid;
        }
        return in;
      }
      in = next;
      if (next == lo_log || next == hi_log) return next;
      width *= 2;
    }
  };
  f.lo_log = bound(-1);
  f.hi_log = bound(+1);
  return f;
}

}  // namespace dyncal::host::detail
