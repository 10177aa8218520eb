#pragma once
// The gain of a candidate's shape parameter (a Stribeck velocity scale, a coupling's ratio) for its
// profile search (profile_search.hpp; private to host_sim/diagnosis): the weighted residual RSS the
// candidate's columns remove, fitted jointly with the model's columns local to its joints
// (Frisch-Waugh), evaluated for a batch of values at a time.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "candidate_context.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "profile_search.hpp"

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

/// The columns of a shape at each query over time, side by side (S x (M queries.size()):
/// columns_at(query)(s, v) writes the M columns at sample s into v), filtered in time as `kind`'s
/// (filter_in_time) in one call, so the filter takes them together.
template <int M, class ColumnsAt>
Eigen::MatrixXd filtered_series_at(const CandidateContext& c, EffectKind kind, const std::vector<ShapeQuery>& queries,
                                   ColumnsAt columns_at) {
  const Eigen::Index S = c.data.t.size();
  Eigen::MatrixXd series(S, M * static_cast<Eigen::Index>(queries.size()));
  Eigen::Matrix<double, M, 1> v;
  for (size_t b = 0; b < queries.size(); ++b) {
    const auto columns = columns_at(queries[b]);
    const Eigen::Index first = M * static_cast<Eigen::Index>(b);
    for (Eigen::Index s = 0; s < S; ++s) {
      columns(s, v);
      series.block<1, M>(s, first) = v.transpose();
    }
  }
  filter_in_time(c, series, kind, M);
  return series;
}

/// A search's fixed rows, joint by joint (the shape's columns act on each joint times its weight and
/// a factor): for joint p of `joints` its weighted model columns A(p) (S x k, the same k for all) and
/// weighted residual b(p) (S), side by side in Ab[p] (one matrix product covers both).
struct JointRows {
  std::vector<int> joints;
  std::vector<Eigen::MatrixXd> Ab;
  Eigen::Index k = 0;

  auto A(size_t p) const { return Ab[p].leftCols(k); }
  auto b(size_t p) const { return Ab[p].col(k); }
};

/// One evaluation of a batch (batch_gains): its filtered columns over time (series, S x M) and, per
/// joint p of the search's rows, A[p]^T series (k x M) and series^T b[p] (M).
struct BatchItem {
  Eigen::Ref<const Eigen::MatrixXd> series;
  std::vector<Eigen::MatrixXd> A_series;
  std::vector<Eigen::VectorXd> series_b;
};

/// The gains of profile_searches: at each query of a batch, gain(query, item) with the shape's
/// filtered columns there (columns_at(query), filtered_series_at: one batch filtered together) and
/// their products with `rows` (one matrix product per joint for the whole batch; none without rows).
template <int M, class ColumnsAt, class Gain>
auto batch_gains(const CandidateContext& c, EffectKind kind, const JointRows* rows, ColumnsAt columns_at, Gain gain) {
  return [&c, kind, rows, columns_at, gain](const std::vector<ShapeQuery>& queries) {
    const Eigen::MatrixXd series = filtered_series_at<M>(c, kind, queries, columns_at);
    const size_t P = rows ? rows->joints.size() : 0;
    std::vector<Eigen::MatrixXd> Ab_series(P);  // [A b]^T series: A^T series over (series^T b)^T
    for (size_t p = 0; p < P; ++p) Ab_series[p].noalias() = rows->Ab[p].transpose() * series;
    std::vector<double> out(queries.size());
    for (size_t b = 0; b < queries.size(); ++b) {
      const Eigen::Index first = M * static_cast<Eigen::Index>(b);
      BatchItem item{series.middleCols(first, M), {}, {}};
      for (size_t p = 0; p < P; ++p) {
        item.A_series.push_back(Ab_series[p].block(0, first, rows->k, M));
        item.series_b.push_back(Ab_series[p].block(rows->k, first, 1, M).transpose());
      }
      out[b] = gain(queries[b], item);
    }
    return out;
  };
}

/// A batch item's columns `use` (u of its M) acting on the rows' joint p times its weight and
/// factor[p] (1 on a motor's own joint, r on the other it turns with), C (rows joint by joint) not
/// formed: C^T C (u x u), A^T C (k x u) and C^T b (u) summed over the joints.
struct MotorProducts {
  Eigen::MatrixXd CC, AC;
  Eigen::VectorXd Cb;
};

inline MotorProducts motor_products(const CandidateContext& c, const JointRows& rows, const BatchItem& item,
                                    const std::vector<int>& use, const std::vector<double>& factor) {
  const Eigen::Index u = static_cast<Eigen::Index>(use.size()), k = rows.k;
  MotorProducts m;
  m.AC = Eigen::MatrixXd::Zero(k, u);
  m.Cb = Eigen::VectorXd::Zero(u);
  double w2 = 0;
  for (size_t p = 0; p < rows.joints.size(); ++p) {
    const double w = c.joint_weights[rows.joints[p]] * factor[p];
    w2 += w * w;
    for (Eigen::Index q = 0; q < u; ++q) {
      const Eigen::Index col = use[static_cast<size_t>(q)];
      m.AC.col(q) += w * item.A_series[p].col(col);
      m.Cb[q] += w * item.series_b[p][col];
    }
  }
  m.CC.resize(u, u);
  for (Eigen::Index a = 0; a < u; ++a)
    for (Eigen::Index b = 0; b <= a; ++b)
      m.CC(a, b) = m.CC(b, a) =
          w2 * item.series.col(use[static_cast<size_t>(a)]).dot(item.series.col(use[static_cast<size_t>(b)]));
  return m;
}

/// `joints`' rows of X's columns `columns` and of `vector` (S N), weighted (JointRows).
inline JointRows joint_rows(const CandidateContext& c, const std::vector<int>& joints,
                            const std::vector<Eigen::Index>& columns, const Eigen::VectorXd& vector) {
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(c.data.q.cols());
  const Eigen::Index S = c.data.t.size(), k = static_cast<Eigen::Index>(columns.size());
  JointRows rows;
  rows.joints = joints;
  rows.k = k;
  for (int j : joints) {
    const double w = c.joint_weights[j];
    Eigen::MatrixXd Ab(S, k + 1);
    for (Eigen::Index s = 0; s < S; ++s) {
      for (Eigen::Index q = 0; q < k; ++q) Ab(s, q) = w * X(s * N + j, columns[static_cast<size_t>(q)]);
      Ab(s, k) = w * vector[s * N + j];
    }
    rows.Ab.push_back(std::move(Ab));
  }
  return rows;
}

/// The Gram A^T A of the rows' columns over all their joints.
inline Eigen::MatrixXd joint_gram(const JointRows& rows) {
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(rows.k, rows.k);
  for (size_t p = 0; p < rows.joints.size(); ++p) G.noalias() += rows.A(p).transpose() * rows.A(p);
  return G;
}

/// The part of local_gain that does not depend on the candidate's shape, built once per search: the
/// weighted rows of `joints` with the model's local columns and the residual, and the factorised
/// Gram of those columns (regularised by 1e-12 of its largest diagonal entry).
struct LocalSystem {
  JointRows rows;
  Eigen::LDLT<Eigen::MatrixXd> LL;
};

inline LocalSystem local_system(const CandidateContext& c, const std::vector<int>& joints,
                                const std::vector<Eigen::Index>& local) {
  LocalSystem sys;
  sys.rows = joint_rows(c, joints, local, c.residual);
  if (!local.empty()) {
    Eigen::MatrixXd LL = joint_gram(sys.rows);
    LL.diagonal().array() += 1e-12 * std::max(1.0, LL.diagonal().maxCoeff());
    sys.LL.compute(LL);
  }
  return sys;
}

/// The weighted RSS that M columns remove from the residual of the system's joints when fitted
/// with its local columns L (the residual is already orthogonal to those, so the gain is
/// g^T S^-1 g, S the Schur complement of their Gram). `item` holds the M columns over time,
/// filtered, and their products with the system's rows (batch_gains); they act on the system's
/// joint p times factor[p] (a coupling's motor: 1 on joint i, r on joint j). A fit whose
/// coefficients (S^-1 g, those of the joint fit) are not physical(coefficients) removes nothing:
/// the search looks only among physical shapes.
template <int M, class Physical>
double local_gain(const CandidateContext& c, const LocalSystem& sys, const std::vector<double>& factor,
                  const BatchItem& item, Physical physical) {
  using Vec = Eigen::Matrix<double, M, 1>;
  std::vector<int> all(M);
  for (int q = 0; q < M; ++q) all[static_cast<size_t>(q)] = q;
  const MotorProducts m = motor_products(c, sys.rows, item, all, factor);
  const Eigen::Matrix<double, M, M> CC = m.CC;
  const Vec g = m.Cb;
  Eigen::Matrix<double, M, M> schur = CC;
  if (m.AC.rows() > 0) schur -= m.AC.transpose() * sys.LL.solve(m.AC);
  schur.diagonal().array() += 1e-12 * std::max(1.0, CC.diagonal().maxCoeff());
  const Vec beta = schur.ldlt().solve(g);
  if (!physical(beta)) return 0.0;
  return std::max(0.0, g.dot(beta));
}

/// A replacement's fixed part during its shape search (replacement_gain): the weighted rows of
/// `joints` with the model's local columns less the `removed` ones (L) and the residual with the
/// removed columns' share of the fit given back (r1), their products, and the residual's r0^T r0.
struct ReplacementSystem {
  JointRows rows;  ///< A: L, b: r1
  Eigen::MatrixXd LL;
  Eigen::VectorXd Lr1;
  double r0_sq = 0, r1_sq = 0;
};

inline ReplacementSystem replacement_system(const CandidateContext& c, const std::vector<int>& joints,
                                            const std::vector<Eigen::Index>& local,
                                            const std::vector<Eigen::Index>& removed) {
  const Eigen::MatrixXd& X = *c.model_X;
  const Eigen::VectorXd& phi = *c.model_phi;
  std::vector<Eigen::Index> kept;
  for (Eigen::Index q : local)
    if (std::find(removed.begin(), removed.end(), q) == removed.end()) kept.push_back(q);
  Eigen::VectorXd given_back = c.residual;
  for (Eigen::Index q : removed) given_back += X.col(q) * phi[q];
  ReplacementSystem sys;
  sys.rows = joint_rows(c, joints, kept, given_back);
  sys.LL = joint_gram(sys.rows);
  sys.Lr1 = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(kept.size()));
  const int N = static_cast<int>(c.data.q.cols());
  for (size_t p = 0; p < joints.size(); ++p) {
    sys.Lr1.noalias() += sys.rows.A(p).transpose() * sys.rows.b(p);
    sys.r1_sq += sys.rows.b(p).squaredNorm();
    const double w = c.joint_weights[joints[p]];
    for (Eigen::Index s = 0; s < c.data.t.size(); ++s) sys.r0_sq += std::pow(w * c.residual[s * N + joints[p]], 2);
  }
  return sys;
}

/// The weighted RSS of the system's joints removed when its removed columns give way to the columns
/// `use` (indices into M) of a motor's M filtered columns over time (item, batch_gains), acting on
/// the system's joint p times factor[p] (a coupled motor: 1 on its own joint, r on the other), and
/// fitted with the other local columns: r0^T r0 - (r1^T r1 - b^T beta) for [L C] beta = r1 in least
/// squares. Negative when the replacement fits worse; 0 when the new coefficients are not
/// physical(coefficients) (no replacement).
template <class Physical>
double replacement_gain(const CandidateContext& c, const ReplacementSystem& sys, const std::vector<int>& use,
                        const std::vector<double>& factor, const BatchItem& item, Physical physical) {
  const Eigen::Index k = sys.LL.rows(), u = static_cast<Eigen::Index>(use.size());
  const MotorProducts m = motor_products(c, sys.rows, item, use, factor);
  Eigen::MatrixXd G(k + u, k + u);
  G.topLeftCorner(k, k) = sys.LL;
  G.topRightCorner(k, u) = m.AC;
  G.bottomLeftCorner(u, k) = m.AC.transpose();
  G.bottomRightCorner(u, u) = m.CC;
  G.diagonal().array() += 1e-12 * std::max(1.0, G.diagonal().maxCoeff());
  Eigen::VectorXd b(k + u);
  b << sys.Lr1, m.Cb;
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
/// `use` of a motor's filtered columns over time (series) on `joints` (times factor[p]; as for
/// replacement_gain), every other column refitted: rss_now - (y^T W^2 y - b^T beta). The exact
/// criterion that replacement_gain approximates on the pair's rows (there the rigid body stays at its
/// current fit); 0 when the new coefficients are not physical.
template <class Physical>
double full_replacement_gain(const CandidateContext& c, const FullReplacement& f, const std::vector<int>& joints,
                             const std::vector<int>& use, const std::vector<double>& factor, const BatchItem& item,
                             Physical physical) {
  const Eigen::Ref<const Eigen::MatrixXd>& series = item.series;
  const StackedData& d = c.data;
  const Eigen::MatrixXd& X = *c.model_X;
  const int N = static_cast<int>(d.q.cols());
  const Eigen::Index S = d.t.size(), P = static_cast<Eigen::Index>(joints.size());
  const Eigen::Index k = static_cast<Eigen::Index>(f.kept.size()), u = static_cast<Eigen::Index>(use.size());
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

}  // namespace dyncal::host::detail
