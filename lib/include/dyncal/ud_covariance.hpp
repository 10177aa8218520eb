#pragma once

#include <Eigen/Core>
#include <cmath>

#include "regressor_structure.hpp"
#include "status.hpp"

namespace dyncal {

/// Covariance P = U D U^T in UD factors (U unit upper triangular, D diagonal), updated by
/// Bierman's scalar measurement update (G. J. Bierman, "Factorization Methods for Discrete
/// Sequential Estimation", 1977). P stays symmetric and positive definite by construction, also in
/// float: it is never formed, and D is updated by ratios of positive numbers.
///
/// Compared with PackedCovariance (the default of KalmanFilter and RlsForgetting) this is slower —
/// N passes of 3P^2/2 multiply-adds per sample, no use of H's sparsity — but it holds a P whose
/// variances span more than float's 7 digits: use it in float when the prior variance exceeds the
/// posterior one by more than about 1e6 (tiny r, huge p0), where the covariance form reports
/// not_positive_definite.
///
/// Memory: P*P + 5*P scalars in the object; no heap. Strictly upper part of U_ is used.
template <typename Scalar, int P>
class UdCovariance {
 public:
  static constexpr int kCapacity = P;  ///< fixed size only (PackedCovariance also takes a run-time size)
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

  /// Same contract as PackedCovariance::reset (the structure is accepted and checked, not exploited).
  template <int N>
  UpdateStatus reset(const Vector& p0, const RegressorStructure<P>& structure) noexcept {
    for (int c = 0; c < P; ++c) {
      if (structure.first[c] <= structure.last[c] && (structure.first[c] < 0 || structure.last[c] >= N))
        return UpdateStatus::invalid_argument;
    }
    return reset(p0);
  }

  /// Same contract as PackedCovariance::assimilate: a sample of N measurements y = H phi + v,
  /// v ~ N(0, diag(r)), as N sequential Bierman updates, then P <- scale * P. Gating uses the
  /// prior innovation variances of all rows, checked before anything changes. Errors leave phi
  /// and P unchanged except a numerical failure after the first row (reported, not expected for
  /// r > 0 and finite data).
  template <int N>
  UpdateStatus assimilate(const Eigen::Matrix<Scalar, N, P>& H, const Eigen::Matrix<Scalar, N, 1>& y,
                          const Eigen::Matrix<Scalar, N, 1>& r, Scalar gate, Scalar scale, Vector& phi) noexcept {
    for (int j = 0; j < P; ++j) {
      for (int k = 0; k < N; ++k) {
        if (!std::isfinite(H(k, j))) return UpdateStatus::rejected_non_finite;
      }
    }
    for (int k = 0; k < N; ++k) {
      if (!std::isfinite(y[k]) || !std::isfinite(r[k])) return UpdateStatus::rejected_non_finite;
      if (!(r[k] > Scalar(0))) return UpdateStatus::not_positive_definite;
    }
    if (gate > Scalar(0)) {
      for (int k = 0; k < N; ++k) {
        h_ = H.row(k).transpose();
        const Scalar e = y[k] - h_.dot(phi);
        if (e * e > gate * gate * innovation_variance(h_, r[k])) return UpdateStatus::rejected_outlier;
      }
    }
    for (int k = 0; k < N; ++k) {
      h_ = H.row(k).transpose();
      const UpdateStatus s = assimilate(h_, y[k], r[k], phi);
      if (s != UpdateStatus::ok) return s;
    }
    if (scale != Scalar(1)) d_ *= scale;
    return UpdateStatus::ok;
  }

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
  Vector f_, g_, b_, gain_, h_;
};

}  // namespace dyncal
