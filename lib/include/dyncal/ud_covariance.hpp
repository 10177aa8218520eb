#pragma once

#include <Eigen/Core>

#include "status.hpp"

namespace dyncal {

/// Covariance P = U D U^T in UD factors (U unit upper triangular, D diagonal), updated by
/// Bierman's scalar measurement update (G. J. Bierman, "Factorization Methods for Discrete
/// Sequential Estimation", 1977). P stays symmetric and positive definite by construction, also in
/// float: it is never formed, and D is updated by ratios of positive numbers.
///
/// Memory: P*P + 3*P scalars in the object; no heap. Strictly upper part of U_ is used.
template <typename Scalar, int P>
class UdCovariance {
 public:
  using Vector = Eigen::Matrix<Scalar, P, 1>;

  /// P = diag(p0) (every p0_i > 0, else invalid_argument and nothing changes).
  UpdateStatus reset(const Vector& p0) noexcept {
    for (int i = 0; i < P; ++i) {
      if (!(p0[i] > Scalar(0))) return UpdateStatus::invalid_argument;
    }
    U_.setIdentity();
    d_ = p0;
    return UpdateStatus::ok;
  }

  /// Innovation variance h^T P h + r of a scalar measurement (h: P, r > 0), without changing P.
  Scalar innovation_variance(const Vector& h, Scalar r) const noexcept {
    Scalar alpha = r;
    for (int j = 0; j < P; ++j) {
      Scalar f = h[j];
      for (int i = 0; i < j; ++i) f += U_(i, j) * h[i];
      alpha += d_[j] * f * f;
    }
    return alpha;
  }

  /// Bierman update for y = h^T x + v, var(v) = r. Writes the Kalman gain (P) and returns the
  /// innovation variance in `alpha`. not_positive_definite if r <= 0 or a D entry would not stay
  /// positive (P unchanged then).
  UpdateStatus update(const Vector& h, Scalar r, Vector& gain, Scalar& alpha) noexcept {
    if (!(r > Scalar(0))) return UpdateStatus::not_positive_definite;
    // f = U^T h, g = D f
    for (int j = 0; j < P; ++j) {
      Scalar f = h[j];
      for (int i = 0; i < j; ++i) f += U_(i, j) * h[i];
      f_[j] = f;
      g_[j] = d_[j] * f;
    }
    // Dry run of the D recursion so that a failure leaves U, D untouched.
    Scalar a = r;
    for (int j = 0; j < P; ++j) {
      const Scalar next = a + f_[j] * g_[j];
      if (!(next > Scalar(0)) || !(a > Scalar(0))) return UpdateStatus::not_positive_definite;
      a = next;
    }
    a = r;
    for (int j = 0; j < P; ++j) {
      const Scalar beta = a;
      a = a + f_[j] * g_[j];
      const Scalar lambda = -f_[j] / beta;
      d_[j] = d_[j] * beta / a;
      for (int i = 0; i < j; ++i) {
        const Scalar u = U_(i, j);
        U_(i, j) = u + b_[i] * lambda;
        b_[i] = b_[i] + u * g_[j];
      }
      b_[j] = g_[j];
    }
    gain = b_ / a;
    alpha = a;
    return UpdateStatus::ok;
  }

  /// Folds the scalar measurement y = h^T phi + v, var(v) = r, into the estimate `phi` and P:
  /// phi += gain * (y - h^T phi). Errors as update(); phi and P unchanged on error.
  UpdateStatus assimilate(const Vector& h, Scalar y, Scalar r, Vector& phi) noexcept {
    const Scalar e = y - h.dot(phi);
    Scalar alpha;
    const UpdateStatus s = update(h, r, gain_, alpha);
    if (s != UpdateStatus::ok) return s;
    phi.noalias() += gain_ * e;
    return UpdateStatus::ok;
  }

  /// P <- P / mu (exponential forgetting, survey Eq. 23), mu in (0, 1].
  void scale(Scalar inverse_mu) noexcept { d_ *= inverse_mu; }

  /// trace(P) = sum_j d_j * sum_i U_ij^2.
  Scalar trace() const noexcept {
    Scalar t(0);
    for (int j = 0; j < P; ++j) {
      Scalar s(1);
      for (int i = 0; i < j; ++i) s += U_(i, j) * U_(i, j);
      t += d_[j] * s;
    }
    return t;
  }

  /// Diagonal of P (parameter variances): P_ii = sum_{j >= i} U_ij^2 d_j.
  void diagonal(Vector& out) const noexcept {
    for (int i = 0; i < P; ++i) {
      Scalar s = d_[i];
      for (int j = i + 1; j < P; ++j) s += U_(i, j) * U_(i, j) * d_[j];
      out[i] = s;
    }
  }

  /// The full covariance U D U^T into `out` (host-side diagnostics and tests).
  void to_dense(Eigen::Matrix<Scalar, P, P>& out) const noexcept {
    for (int r = 0; r < P; ++r) {
      for (int c = r; c < P; ++c) {
        Scalar s(0);
        for (int k = c; k < P; ++k) s += (k == r ? Scalar(1) : U_(r, k)) * d_[k] * (k == c ? Scalar(1) : U_(c, k));
        out(r, c) = s;
        out(c, r) = s;
      }
    }
  }

  const Vector& d() const noexcept { return d_; }

 private:
  Eigen::Matrix<Scalar, P, P> U_;
  Vector d_;
  Vector f_, g_, b_, gain_;
};

}  // namespace dyncal
