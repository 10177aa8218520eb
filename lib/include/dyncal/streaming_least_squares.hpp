#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "estimator_size.hpp"
#include "finite.hpp"
#include "multiply_add.hpp"
#include "status.hpp"

namespace dyncal {

/// Ordinary / weighted least squares (the pseudo-inverse of survey Eq. 15, IDIM-OLS / IDIM-WLS) in
/// streaming form with fixed memory: every row is folded into an upper-triangular factor R
/// (P x P) and z = Q^T tau by Givens rotations, so that R^T R = W^T W and the solution of
/// R phi = z is exactly the batch least-squares answer, without storing samples.
///
/// Memory: (P + 3) * P + P scalars, owned by the object; no heap, no exceptions.
/// Weighted rows: each row is multiplied by its weight w (use w = 1 / sigma_joint for WLS).
///
/// P is fixed at compile time, or P = Eigen::Dynamic: the number of parameters is then set at run
/// time by reset(size), 1..MaxP, and the storage is that of MaxP (Eigen's fixed-capacity dynamic
/// matrices, still no heap). The same loops run to size(), and every product-sum is a
/// multiply_add (fused where the target has it), so both give the same numbers bit for bit.
template <typename Scalar, int P, int MaxP = P>
class StreamingLeastSquares {
  static_assert(P == Eigen::Dynamic ? MaxP > 0 : (P > 0 && MaxP == P), "P > 0, or P = Eigen::Dynamic and MaxP > 0");

 public:
  static constexpr bool kDynamic = P == Eigen::Dynamic;
  /// Most parameters: P, or MaxP at the run-time size.
  static constexpr int kCapacity = kDynamic ? MaxP : P;
  using Vector = ParamVectorOf<Scalar, P, kCapacity>;
  using Matrix = std::conditional_t<kDynamic, Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, 0, MaxP, MaxP>,
                                    Eigen::Matrix<Scalar, P, P>>;
  /// The N x P regressor of one sample (update()).
  template <int N>
  using Regressor = RegressorOf<Scalar, N, P, kCapacity>;

  /// Ready for rows at a fixed P; at the run-time size, empty until reset(size).
  StreamingLeastSquares() noexcept { reset(); }

  /// The number of parameters: P, or the run-time size (0 before reset(size)).
  int size() const noexcept {
    if constexpr (kDynamic) {
      return n_;
    } else {
      return P;
    }
  }

  /// Forgets every row (the size stays).
  void reset() noexcept {
    if constexpr (kDynamic) {
      R_.resize(n_, n_);
      z_.resize(n_);
      row_.resize(n_);
    }
    R_.setZero();
    z_.setZero();
    rss_ = Scalar(0);
    rows_ = 0;
  }

  /// Forgets every row and sets the number of parameters: 1..MaxP at the run-time size, P at a fixed
  /// size. invalid_argument otherwise (nothing changes).
  UpdateStatus reset(int size) noexcept {
    if (size < 1 || size > kCapacity || (!kDynamic && size != P)) return UpdateStatus::invalid_argument;
    if constexpr (kDynamic) n_ = size;
    reset();
    return UpdateStatus::ok;
  }

  /// Folds one equation  y = k^T phi  (k: size() regressor entries, y [Nm]) with weight w > 0.
  /// Errors: rejected_non_finite (NaN/inf in k, y or w), invalid_argument (w <= 0, or k not of
  /// size() entries); the state is unchanged on error.
  template <typename Derived>
  UpdateStatus add_row(const Eigen::MatrixBase<Derived>& k, Scalar y, Scalar w = Scalar(1)) noexcept {
    if (k.size() != size()) return UpdateStatus::invalid_argument;
    if (!all_finite(k) || !std::isfinite(y) || !std::isfinite(w)) return UpdateStatus::rejected_non_finite;
    if (!(w > Scalar(0))) return UpdateStatus::invalid_argument;
    for (int i = 0; i < size(); ++i) row_[i] = w * k(i);
    Scalar rhs = w * y;
    rotate_in(rhs);
    rss_ = multiply_add(rhs, rhs, rss_);
    ++rows_;
    return UpdateStatus::ok;
  }

  /// Folds the N equations tau = K phi of one sample (K: N x P, tau: N), row j weighted by
  /// weights[j]. All rows are checked before any is folded: on error nothing changes.
  template <int N>
  UpdateStatus update(const Regressor<N>& K, const Eigen::Matrix<Scalar, N, 1>& tau,
                      const Eigen::Matrix<Scalar, N, 1>& weights) noexcept {
    if (K.cols() != size()) return UpdateStatus::invalid_argument;
    if (!all_finite(K) || !all_finite(tau) || !all_finite(weights)) return UpdateStatus::rejected_non_finite;
    for (int j = 0; j < N; ++j) {
      if (!(weights[j] > Scalar(0))) return UpdateStatus::invalid_argument;
    }
    for (int j = 0; j < N; ++j) add_row(K.row(j).transpose(), tau[j], weights[j]);
    return UpdateStatus::ok;
  }

  /// Unweighted form of update().
  template <int N>
  UpdateStatus update(const Regressor<N>& K, const Eigen::Matrix<Scalar, N, 1>& tau) noexcept {
    const Eigen::Matrix<Scalar, N, 1> ones = Eigen::Matrix<Scalar, N, 1>::Ones();
    return update(K, tau, ones);
  }

  /// Folds another accumulator's rows into this one (for example to combine cross-validation
  /// folds). Equivalent to having added all of its rows here. invalid_argument when the two differ
  /// in size (nothing changes).
  UpdateStatus merge(const StreamingLeastSquares& other) noexcept {
    if (other.size() != size()) return UpdateStatus::invalid_argument;
    for (int r = 0; r < size(); ++r) {
      for (int i = 0; i < size(); ++i) row_[i] = other.R_(r, i);
      Scalar rhs = other.z_[r];
      rotate_in(rhs);
      rss_ = multiply_add(rhs, rhs, rss_);
    }
    rss_ += other.rss_;
    rows_ += other.rows_;
    return UpdateStatus::ok;
  }

  /// Least-squares solution phi (size()) of R phi = z by back substitution.
  /// rank_deficient when a diagonal |R_ii| <= size() * eps * max|R_jj| (phi is then left unchanged).
  UpdateStatus solve(Vector& phi) const noexcept {
    if (!full_rank()) return UpdateStatus::rank_deficient;
    Vector x = Vector::Zero(size());
    for (int i = size() - 1; i >= 0; --i) {
      Scalar s = z_[i];
      for (int j = i + 1; j < size(); ++j) s = multiply_add(-R_(i, j), x[j], s);
      x[i] = s / R_(i, i);
    }
    phi = x;
    return UpdateStatus::ok;
  }

  /// Diagonal of (W^T W)^-1 (multiply by the residual variance for the parameter variances):
  /// the squared row norms of R^-1, computed column by column of R^-1 into `diag`.
  UpdateStatus inverse_gram_diagonal(Vector& diag) const noexcept {
    if (!full_rank()) return UpdateStatus::rank_deficient;
    Vector d = Vector::Zero(size());
    for (int c = 0; c < size(); ++c) {
      // column c of R^-1: solve R x = e_c (x_i = 0 for i > c)
      for (int i = c; i >= 0; --i) {
        Scalar s = (i == c) ? Scalar(1) : Scalar(0);
        for (int j = i + 1; j <= c; ++j) s = multiply_add(-R_(i, j), row_[j], s);
        row_[i] = s / R_(i, i);
        d[i] = multiply_add(row_[i], row_[i], d[i]);
      }
    }
    diag = d;
    return UpdateStatus::ok;
  }

  /// True when every |R_ii| > size() * eps * max|R_jj| (false at size 0).
  bool full_rank() const noexcept {
    using std::abs;
    Scalar max_diag(0);
    for (int i = 0; i < size(); ++i) max_diag = abs(R_(i, i)) > max_diag ? abs(R_(i, i)) : max_diag;
    const Scalar tol = Scalar(size()) * std::numeric_limits<Scalar>::epsilon() * max_diag;
    if (!(max_diag > Scalar(0))) return false;
    for (int i = 0; i < size(); ++i) {
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
    for (int i = 0; i < size(); ++i) {
      const Scalar h = row_[i];
      if (h == Scalar(0)) continue;
      const Scalar rii = R_(i, i);
      const Scalar r = sqrt(multiply_add(rii, rii, h * h));
      // Both below sqrt(the smallest normal): their squares underflow to r = 0. Such an entry is
      // below the accumulator's resolution (a low-pass's tail ahead of a column's first motion):
      // left out rather than rotated by 0 / 0.
      if (!(r > Scalar(0))) continue;
      const Scalar c = rii / r;
      const Scalar s = h / r;
      R_(i, i) = r;
      for (int j = i + 1; j < size(); ++j) {
        const Scalar a = R_(i, j);
        const Scalar b = row_[j];
        R_(i, j) = multiply_add(c, a, s * b);
        row_[j] = multiply_add(c, b, -(s * a));
      }
      const Scalar a = z_[i];
      z_[i] = multiply_add(c, a, s * rhs);
      rhs = multiply_add(c, rhs, -(s * a));
    }
  }

  Matrix R_;
  Vector z_;
  mutable Vector row_;
  Scalar rss_;
  long rows_;
  int n_ = 0;  // the run-time size (unused at a fixed P)
};

}  // namespace dyncal
