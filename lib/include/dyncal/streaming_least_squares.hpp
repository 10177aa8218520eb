#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "finite.hpp"
#include "status.hpp"

namespace dyncal {

/// Ordinary / weighted least squares (the pseudo-inverse of survey Eq. 15, IDIM-OLS / IDIM-WLS) in
/// streaming form with fixed memory: every row is folded into an upper-triangular factor R
/// (P x P) and z = Q^T tau by Givens rotations, so that R^T R = W^T W and the solution of
/// R phi = z is exactly the batch least-squares answer, without storing samples.
///
/// Memory: (P + 3) * P + P scalars, owned by the object; no heap, no exceptions.
/// Weighted rows: each row is multiplied by its weight w (use w = 1 / sigma_joint for WLS).
template <typename Scalar, int P>
class StreamingLeastSquares {
 public:
  using Vector = Eigen::Matrix<Scalar, P, 1>;
  using Matrix = Eigen::Matrix<Scalar, P, P>;

  StreamingLeastSquares() noexcept { reset(); }

  /// Forgets every row.
  void reset() noexcept {
    R_.setZero();
    z_.setZero();
    rss_ = Scalar(0);
    rows_ = 0;
  }

  /// Folds one equation  y = k^T phi  (k: P regressor entries, y [Nm]) with weight w > 0.
  /// Errors: rejected_non_finite (NaN/inf in k, y or w), invalid_argument (w <= 0); the state is
  /// unchanged on error.
  template <typename Derived>
  UpdateStatus add_row(const Eigen::MatrixBase<Derived>& k, Scalar y, Scalar w = Scalar(1)) noexcept {
    if (!all_finite(k) || !std::isfinite(y) || !std::isfinite(w)) return UpdateStatus::rejected_non_finite;
    if (!(w > Scalar(0))) return UpdateStatus::invalid_argument;
    for (int i = 0; i < P; ++i) row_[i] = w * k(i);
    Scalar rhs = w * y;
    rotate_in(rhs);
    rss_ += rhs * rhs;
    ++rows_;
    return UpdateStatus::ok;
  }

  /// Folds the N equations tau = K phi of one sample (K: N x P, tau: N), row j weighted by
  /// weights[j]. All rows are checked before any is folded: on error nothing changes.
  template <int N>
  UpdateStatus update(const Eigen::Matrix<Scalar, N, P>& K, const Eigen::Matrix<Scalar, N, 1>& tau,
                      const Eigen::Matrix<Scalar, N, 1>& weights) noexcept {
    if (!all_finite(K) || !all_finite(tau) || !all_finite(weights)) return UpdateStatus::rejected_non_finite;
    for (int j = 0; j < N; ++j) {
      if (!(weights[j] > Scalar(0))) return UpdateStatus::invalid_argument;
    }
    for (int j = 0; j < N; ++j) add_row(K.row(j).transpose(), tau[j], weights[j]);
    return UpdateStatus::ok;
  }

  /// Unweighted form of update().
  template <int N>
  UpdateStatus update(const Eigen::Matrix<Scalar, N, P>& K, const Eigen::Matrix<Scalar, N, 1>& tau) noexcept {
    const Eigen::Matrix<Scalar, N, 1> ones = Eigen::Matrix<Scalar, N, 1>::Ones();
    return update(K, tau, ones);
  }

  /// Folds another accumulator's rows into this one (for example to combine cross-validation
  /// folds). Equivalent to having added all of its rows here.
  void merge(const StreamingLeastSquares& other) noexcept {
    for (int r = 0; r < P; ++r) {
      for (int i = 0; i < P; ++i) row_[i] = other.R_(r, i);
      Scalar rhs = other.z_[r];
      rotate_in(rhs);
      rss_ += rhs * rhs;
    }
    rss_ += other.rss_;
    rows_ += other.rows_;
  }

  /// Least-squares solution phi (P) of R phi = z by back substitution.
  /// rank_deficient when a diagonal |R_ii| <= P * eps * max|R_jj| (phi is then left unchanged).
  UpdateStatus solve(Vector& phi) const noexcept {
    if (!full_rank()) return UpdateStatus::rank_deficient;
    Vector x;
    for (int i = P - 1; i >= 0; --i) {
      Scalar s = z_[i];
      for (int j = i + 1; j < P; ++j) s -= R_(i, j) * x[j];
      x[i] = s / R_(i, i);
    }
    phi = x;
    return UpdateStatus::ok;
  }

  /// Diagonal of (W^T W)^-1 (multiply by the residual variance for the parameter variances):
  /// the squared row norms of R^-1, computed column by column of R^-1 into `diag`.
  UpdateStatus inverse_gram_diagonal(Vector& diag) const noexcept {
    if (!full_rank()) return UpdateStatus::rank_deficient;
    Vector d = Vector::Zero();
    for (int c = 0; c < P; ++c) {
      // column c of R^-1: solve R x = e_c (x_i = 0 for i > c)
      for (int i = c; i >= 0; --i) {
        Scalar s = (i == c) ? Scalar(1) : Scalar(0);
        for (int j = i + 1; j <= c; ++j) s -= R_(i, j) * row_[j];
        row_[i] = s / R_(i, i);
        d[i] += row_[i] * row_[i];
      }
    }
    diag = d;
    return UpdateStatus::ok;
  }

  /// True when every |R_ii| > P * eps * max|R_jj|.
  bool full_rank() const noexcept {
    using std::abs;
    Scalar max_diag(0);
    for (int i = 0; i < P; ++i) max_diag = abs(R_(i, i)) > max_diag ? abs(R_(i, i)) : max_diag;
    const Scalar tol = Scalar(P) * std::numeric_limits<Scalar>::epsilon() * max_diag;
    if (!(max_diag > Scalar(0))) return false;
    for (int i = 0; i < P; ++i) {
      if (!(abs(R_(i, i)) > tol)) return false;
    }
    return true;
  }

  /// Weighted residual sum of squares of the least-squares fit over all rows folded so far.
  Scalar residual_sum_of_squares() const noexcept { return rss_; }
  /// Number of rows folded.
  long rows() const noexcept { return rows_; }
  /// The triangular factor (R^T R = W^T W).
  const Matrix& r_factor() const noexcept { return R_; }
  /// The rotated right-hand side z: ||W phi - y||^2 = ||R phi - z||^2 + residual_sum_of_squares().
  const Vector& rotated_rhs() const noexcept { return z_; }

 private:
  // Rotates row_ (with right-hand side rhs) into R_, z_; rhs ends as the row's residual part.
  void rotate_in(Scalar& rhs) noexcept {
    using std::sqrt;
    for (int i = 0; i < P; ++i) {
      const Scalar h = row_[i];
      if (h == Scalar(0)) continue;
      const Scalar rii = R_(i, i);
      const Scalar r = sqrt(rii * rii + h * h);
      const Scalar c = rii / r;
      const Scalar s = h / r;
      R_(i, i) = r;
      for (int j = i + 1; j < P; ++j) {
        const Scalar a = R_(i, j);
        const Scalar b = row_[j];
        R_(i, j) = c * a + s * b;
        row_[j] = c * b - s * a;
      }
      const Scalar a = z_[i];
      z_[i] = c * a + s * rhs;
      rhs = c * rhs - s * a;
    }
  }

  Matrix R_;
  Vector z_;
  mutable Vector row_;
  Scalar rss_;
  long rows_;
};

}  // namespace dyncal
