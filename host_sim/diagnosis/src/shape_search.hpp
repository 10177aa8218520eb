#pragma once
// A candidate's shape parameter (a Stribeck velocity scale, a coupling's ratio) found by a profile
// search (private to host_sim/diagnosis): the weighted residual RSS the candidate's columns remove,
// fitted jointly with the model's columns local to its joints (Frisch-Waugh), maximised over a log
// grid, refined by golden section, with a 95 % profile-likelihood interval.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "candidate_context.hpp"
#include "dyncal_host/identification/methods/signal.hpp"

namespace dyncal::host::detail {

/// Per column of X ((S N) x p): bit j set where it is non-zero on joint j's rows.
inline std::vector<std::uint32_t> column_joint_masks(const Eigen::MatrixXd& X, int N) {
  std::vector<std::uint32_t> out(static_cast<size_t>(X.cols()), 0);
  for (Eigen::Index k = 0; k < X.cols(); ++k)
    for (Eigen::Index r = 0; r < X.rows(); ++r)
      if (X(r, k) != 0.0) out[static_cast<size_t>(k)] |= 1u << (r % N);
  return out;
}

/// The model's columns local to `joints` (non-zero only on their rows: their friction, rotor
/// inertia, offset and effect terms), the ones a candidate on those joints trades off with.
inline std::vector<Eigen::Index> local_columns(const CandidateContext& c, const std::vector<int>& joints) {
  std::uint32_t mask = 0;
  for (int j : joints) mask |= 1u << j;
  std::vector<Eigen::Index> out;
  for (size_t k = 0; k < c.column_joints.size(); ++k)
    if (c.column_joints[k] != 0 && (c.column_joints[k] & ~mask) == 0) out.push_back(static_cast<Eigen::Index>(k));
  return out;
}

/// A motor's M columns over time (S x M), columns(s, x) sample by sample, filtered in time as
/// `kind`'s (filter_in_time).
template <int M, class Columns>
Eigen::MatrixXd filtered_series(const CandidateContext& c, EffectKind kind, Columns columns) {
  const Eigen::Index S = c.data.t.size();
  Eigen::MatrixXd series(S, M);
  Eigen::Matrix<double, M, 1> x;
  for (Eigen::Index s = 0; s < S; ++s) {
    columns(s, x);
    series.row(s) = x.transpose();
  }
  filter_in_time(c, series, kind, M);
  return series;
}

/// A motor's filtered columns (filtered_series: filtering is linear, once for every joint it acts
/// on) as rows of `joints`: on joint p the columns `use`
/// times its weight and factor[p] (1 on a motor's own joint, r on the other it turns with). Rows
/// s P + p (P joints).
template <int M, class Columns>
Eigen::MatrixXd motor_rows(const CandidateContext& c, const std::vector<int>& joints, EffectKind kind,
                           const std::vector<int>& use, const std::vector<double>& factor, Columns columns) {
  const Eigen::Index S = c.data.t.size(), P = static_cast<Eigen::Index>(joints.size());
  const Eigen::Index u = static_cast<Eigen::Index>(use.size());
  const Eigen::MatrixXd series = filtered_series<M>(c, kind, columns);
  Eigen::MatrixXd C(S * P, u);
  for (Eigen::Index s = 0; s < S; ++s)
    for (Eigen::Index p = 0; p < P; ++p) {
      const double w = c.joint_weights[joints[static_cast<size_t>(p)]] * factor[static_cast<size_t>(p)];
      for (Eigen::Index q = 0; q < u; ++q) C(s * P + p, q) = w * series(s, use[static_cast<size_t>(q)]);
    }
  return C;
}

/// The part of local_gain that does not depend on the candidate's shape, built once per search: the
/// weighted rows of `joints` with the model's local columns L and the residual r, and the
/// factorised Gram of L (regularised by 1e-12 of its largest diagonal entry).
struct LocalSystem {
  std::vector<int> joints;
  Eigen::MatrixXd L;
  Eigen::VectorXd r;
  Eigen::LDLT<Eigen::MatrixXd> LL;
};

inline LocalSystem local_system(const CandidateContext& c, const std::vector<int>& joints,
                                const std::vector<Eigen::Index>& local) {
  const StackedData& d = c.data;
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(d.q.cols());
  const Eigen::Index S = d.t.size(), P = static_cast<Eigen::Index>(joints.size());
  const Eigen::Index k = static_cast<Eigen::Index>(local.size()), R = S * P;
  LocalSystem sys;
  sys.joints = joints;
  sys.L.resize(R, k);
  sys.r.resize(R);
  for (Eigen::Index s = 0; s < S; ++s)
    for (Eigen::Index p = 0; p < P; ++p) {
      const int j = joints[static_cast<size_t>(p)];
      const Eigen::Index row = s * N + j, out = s * P + p;
      const double w = c.joint_weights[j];
      for (Eigen::Index q = 0; q < k; ++q) sys.L(out, q) = w * X(row, local[static_cast<size_t>(q)]);
      sys.r[out] = w * c.residual[row];
    }
  if (k > 0) {
    Eigen::MatrixXd LL(k, k);
    LL.noalias() = sys.L.transpose() * sys.L;
    LL.diagonal().array() += 1e-12 * std::max(1.0, LL.diagonal().maxCoeff());
    sys.LL.compute(LL);
  }
  return sys;
}

/// The weighted RSS that M columns remove from the residual of the system's joints when fitted
/// with its local columns (the residual is already orthogonal to those, so the gain is
/// g^T S^-1 g, S the Schur complement of their Gram). columns(s, x) writes the M columns at sample
/// s into x, called sample by sample; they act on the system's joint p times factor[p] (a
/// coupling's motor: 1 on joint i, r on joint j), filtered in time as `kind`'s (linear: once for
/// every joint). A fit whose coefficients (S^-1 g, those of the joint fit) are not
/// physical(coefficients) removes nothing: the search looks only among physical shapes.
template <int M, class Columns, class Physical>
double local_gain(const CandidateContext& c, const LocalSystem& sys, EffectKind kind, const std::vector<double>& factor,
                  Columns columns, Physical physical) {
  using Vec = Eigen::Matrix<double, M, 1>;
  const Eigen::Index k = sys.L.cols();
  std::vector<int> all(M);
  for (int q = 0; q < M; ++q) all[static_cast<size_t>(q)] = q;
  const Eigen::MatrixXd C = motor_rows<M>(c, sys.joints, kind, all, factor, columns);
  // Coefficient-wise products (lazyProduct): a few columns against long ones, where the blocked
  // product's packing of the long operand costs as much as the product.
  const Eigen::Matrix<double, M, M> CC = C.transpose().lazyProduct(C);
  const Vec g = C.transpose().lazyProduct(sys.r);
  Eigen::Matrix<double, M, M> schur = CC;
  if (k > 0) {
    Eigen::MatrixXd LC(k, M);
    LC.noalias() = sys.L.transpose().lazyProduct(C);
    schur -= LC.transpose() * sys.LL.solve(LC);
  }
  schur.diagonal().array() += 1e-12 * std::max(1.0, CC.diagonal().maxCoeff());
  const Vec beta = schur.ldlt().solve(g);
  if (!physical(beta)) return 0.0;
  return std::max(0.0, g.dot(beta));
}

/// A replacement's fixed part during its shape search (replacement_gain): the weighted rows of
/// `joints` with the model's local columns less the `removed` ones (L), the residual r0 and the
/// residual with the removed columns' share of the fit given back (r1), and their products.
struct ReplacementSystem {
  std::vector<int> joints;
  Eigen::MatrixXd L, LL;
  Eigen::VectorXd r1, Lr1;
  double r0_sq = 0, r1_sq = 0;
};

inline ReplacementSystem replacement_system(const CandidateContext& c, const std::vector<int>& joints,
                                            const std::vector<Eigen::Index>& local,
                                            const std::vector<Eigen::Index>& removed) {
  const StackedData& d = c.data;
  const Eigen::MatrixXd& X = *c.model_X;
  const Eigen::VectorXd& phi = *c.model_phi;
  const int N = static_cast<int>(d.q.cols());
  std::vector<Eigen::Index> kept;
  for (Eigen::Index q : local)
    if (std::find(removed.begin(), removed.end(), q) == removed.end()) kept.push_back(q);
  const Eigen::Index S = d.t.size(), P = static_cast<Eigen::Index>(joints.size());
  const Eigen::Index k = static_cast<Eigen::Index>(kept.size()), R = S * P;
  ReplacementSystem sys;
  sys.joints = joints;
  sys.L.resize(R, k);
  sys.r1.resize(R);
  for (Eigen::Index s = 0; s < S; ++s)
    for (Eigen::Index p = 0; p < P; ++p) {
      const int j = joints[static_cast<size_t>(p)];
      const Eigen::Index row = s * N + j, out = s * P + p;
      const double w = c.joint_weights[j];
      for (Eigen::Index q = 0; q < k; ++q) sys.L(out, q) = w * X(row, kept[static_cast<size_t>(q)]);
      double back = 0;
      for (Eigen::Index q : removed) back += X(row, q) * phi[q];
      sys.r0_sq += std::pow(w * c.residual[row], 2);
      sys.r1[out] = w * (c.residual[row] + back);
    }
  sys.LL = sys.L.transpose() * sys.L;
  sys.Lr1 = sys.L.transpose() * sys.r1;
  sys.r1_sq = sys.r1.squaredNorm();
  return sys;
}

/// The weighted RSS of the system's joints removed when its removed columns give way to the columns
/// `use` (indices into M) of a motor's M columns over time, columns(s, x), acting on the system's
/// joint p times factor[p] (a coupled motor: 1 on its own joint, r on the other), filtered in time
/// as `kind`'s, and fitted with the other local columns: r0^T r0 - (r1^T r1 - b^T beta) for
/// [L C] beta = r1 in least squares. Negative when the replacement fits worse; 0 when the new
/// coefficients are not physical(coefficients) (no replacement).
template <int M, class Columns, class Physical>
double replacement_gain(const CandidateContext& c, const ReplacementSystem& sys, EffectKind kind,
                        const std::vector<int>& use, const std::vector<double>& factor, Columns columns,
                        Physical physical) {
  const Eigen::Index k = sys.L.cols(), u = static_cast<Eigen::Index>(use.size());
  const Eigen::MatrixXd C = motor_rows<M>(c, sys.joints, kind, use, factor, columns);
  Eigen::MatrixXd G(k + u, k + u);
  G.topLeftCorner(k, k) = sys.LL;
  G.topRightCorner(k, u).noalias() = sys.L.transpose().lazyProduct(C);
  G.bottomLeftCorner(u, k) = G.topRightCorner(k, u).transpose();
  G.bottomRightCorner(u, u).noalias() = C.transpose().lazyProduct(C);
  G.diagonal().array() += 1e-12 * std::max(1.0, G.diagonal().maxCoeff());
  Eigen::VectorXd b(k + u);
  b << sys.Lr1, C.transpose().lazyProduct(sys.r1);
  const Eigen::VectorXd beta = G.ldlt().solve(b);
  if (!physical(Eigen::VectorXd(beta.tail(u)))) return 0.0;
  return sys.r0_sq - (sys.r1_sq - b.dot(beta));
}

/// The whole model's weighted fit when the columns `removed` of X give way to new columns (all
/// joints' rows, every model column refitted, the rigid body included): the part of the Gram that
/// does not depend on the new columns, built once.
struct FullReplacement {
  std::vector<Eigen::Index> kept;  ///< X's columns that stay
  Eigen::MatrixXd G;               ///< X_kept^T W^2 X_kept
  Eigen::VectorXd g;               ///< X_kept^T W^2 y
  double yy = 0, rss_now = 0;      ///< y^T W^2 y; the model's weighted RSS now
};

inline FullReplacement full_replacement(const CandidateContext& c, const std::vector<Eigen::Index>& removed) {
  const StackedData& d = c.data;
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(d.q.cols());
  FullReplacement f;
  for (Eigen::Index q = 0; q < X.cols(); ++q)
    if (std::find(removed.begin(), removed.end(), q) == removed.end()) f.kept.push_back(q);
  Eigen::VectorXd w(X.rows());
  for (Eigen::Index r = 0; r < X.rows(); ++r) w[r] = d.fit_row[static_cast<size_t>(r)] ? c.joint_weights[r % N] : 0.0;
  const Eigen::MatrixXd A = w.asDiagonal() * X(Eigen::all, f.kept);
  const Eigen::VectorXd wy = w.cwiseProduct(d.y);
  f.G = A.transpose() * A;
  f.g = A.transpose() * wy;
  f.yy = wy.squaredNorm();
  f.rss_now = w.cwiseProduct(c.residual).squaredNorm();
  return f;
}

/// The weighted RSS of the whole model removed when its replaced columns give way to the columns
/// `use` of a motor's M columns over time on `joints` (times factor[p]; columns(s, x) as for
/// replacement_gain), every other column refitted: rss_now - (y^T W^2 y - b^T beta). The exact
/// criterion that replacement_gain approximates on the pair's rows (there the rigid body stays at its
/// current fit); 0 when the new coefficients are not physical.
template <int M, class Columns, class Physical>
double full_replacement_gain(const CandidateContext& c, const FullReplacement& f, EffectKind kind,
                             const std::vector<int>& joints, const std::vector<int>& use,
                             const std::vector<double>& factor, Columns columns, Physical physical) {
  const StackedData& d = c.data;
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(d.q.cols());
  const Eigen::Index S = d.t.size(), P = static_cast<Eigen::Index>(joints.size());
  const Eigen::Index k = static_cast<Eigen::Index>(f.kept.size()), u = static_cast<Eigen::Index>(use.size());
  const Eigen::MatrixXd series = filtered_series<M>(c, kind, columns);
  Eigen::MatrixXd Gxc = Eigen::MatrixXd::Zero(k, u), Gcc = Eigen::MatrixXd::Zero(u, u);
  Eigen::VectorXd gc = Eigen::VectorXd::Zero(u), cr(u);
  for (Eigen::Index s = 0; s < S; ++s)
    for (Eigen::Index p = 0; p < P; ++p) {
      const int j = joints[static_cast<size_t>(p)];
      const Eigen::Index row = s * N + j;
      if (!d.fit_row[static_cast<size_t>(row)]) continue;
      const double w2 = c.joint_weights[j] * c.joint_weights[j], a = factor[static_cast<size_t>(p)];
      for (Eigen::Index q = 0; q < u; ++q) cr[q] = a * series(s, use[static_cast<size_t>(q)]);
      for (Eigen::Index q = 0; q < k; ++q) Gxc.row(q) += w2 * X(row, f.kept[static_cast<size_t>(q)]) * cr.transpose();
      Gcc.noalias() += w2 * cr * cr.transpose();
      gc += w2 * d.y[row] * cr;
    }
  Eigen::MatrixXd G(k + u, k + u);
  G << f.G, Gxc, Gxc.transpose(), Gcc;
  G.diagonal().array() += 1e-12 * std::max(1.0, G.diagonal().maxCoeff());
  Eigen::VectorXd b(k + u);
  b << f.g, gc;
  const Eigen::VectorXd beta = G.ldlt().solve(b);
  if (!physical(Eigen::VectorXd(beta.tail(u)))) return 0.0;
  return f.rss_now - (f.yy - b.dot(beta));
}

/// A shape found by profile search: log of its value, the gain there, and the 95 % interval.
struct ShapeFit {
  double log_value = 0, gain = -1, lo_log = 0, hi_log = 0;
  /// The interval reaches an end of the searched range, or the estimate is an end of its own
  /// interval (no value beyond it on that side fits as well: the gain stops there, as where the
  /// physical signs cut it): the data do not bound the value.
  bool unbounded = false;
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
  f.unbounded = f.lo_log <= lo_log || f.hi_log >= hi_log || f.lo_log == f.log_value || f.hi_log == f.log_value;
  return f;
}

}  // namespace dyncal::host::detail
