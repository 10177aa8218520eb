#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "regressor_structure.hpp"
#include "status.hpp"

// The short loops over the N measurements must be unrolled for the accumulators to live in
// registers (GCC does not unroll at -O2 by itself).
#if defined(__clang__)
#define DYNCAL_ALWAYS_INLINE inline __attribute__((always_inline))
#define DYNCAL_UNROLL _Pragma("unroll")
#elif defined(__GNUC__)
#define DYNCAL_ALWAYS_INLINE inline __attribute__((always_inline))
#define DYNCAL_UNROLL _Pragma("GCC unroll 16")
#else
#define DYNCAL_ALWAYS_INLINE inline
#define DYNCAL_UNROLL
#endif

namespace dyncal {

/// Covariance P (P x P, symmetric) in packed storage — the upper triangle row by row, P(P+1)/2
/// scalars — with the Kalman measurement update of a whole sample of N measurements at once
/// (survey Eq. 19, 21, 23, 24):
///   e = y - H phi,  V = P H^T,  S = H V + diag(r) = L L^T,  W = V L^-T,
///   phi += W L^-1 e,  P <- s (P - W W^T)   (s = 1, or 1/mu for exponential forgetting).
/// This is the same update as N sequential scalar updates (R diagonal) but passes over P once.
/// Work per sample: P * nnz(H) for V (the structural zeros of H — RegressorStructure — are
/// skipped) and N * P(P+1)/2 for the downdate; no heap, no exceptions.
///
/// Safeguards (every failure leaves phi and P exactly as they were): non-finite input, an entry
/// of H outside its declared structure, r <= 0, S not positive definite, a diagonal entry of the
/// updated P not positive (checked before P is written), and optional innovation gating.
template <typename Scalar, int P, int N>
class PackedCovariance {
 public:
  static constexpr int kPacked = P * (P + 1) / 2;
  using ParamVector = Eigen::Matrix<Scalar, P, 1>;
  using MeasVector = Eigen::Matrix<Scalar, N, 1>;
  using Regressor = Eigen::Matrix<Scalar, N, P>;

  /// Position of P(i, j), i <= j, in the packed array.
  static constexpr int index(int i, int j) noexcept { return i * P - (i * (i - 1)) / 2 + (j - i); }

  /// P = diag(p0) (every p0_i > 0 and finite) and the structure of H (rows within 0..N-1).
  /// invalid_argument otherwise, and nothing changes.
  template <int Rows = N>
  UpdateStatus reset(const ParamVector& p0, const RegressorStructure<P>& structure) noexcept {
    static_assert(Rows == N, "PackedCovariance is sized for N rows");
    for (int i = 0; i < P; ++i) {
      if (!(p0[i] > Scalar(0)) || !std::isfinite(p0[i])) return UpdateStatus::invalid_argument;
    }
    int runs = 0;
    for (int c = 0; c < P; ++c) {
      const int f = structure.first[c], l = structure.last[c];
      if (f > l) continue;  // an all-zero column
      if (f < 0 || l >= N) return UpdateStatus::invalid_argument;
      // A column is accumulated either as rows 0..l (code l) or as the single row f (code N + f).
      const int code = (f == l && f > 0) ? N + f : l;
      if (runs > 0 && runs_[runs - 1].end == c && runs_[runs - 1].code == code) {
        ++runs_[runs - 1].end;
      } else {
        runs_[runs++] =
            Run{static_cast<std::uint8_t>(c), static_cast<std::uint8_t>(c + 1), static_cast<std::uint8_t>(code)};
      }
    }
    num_runs_ = runs;
    num_outside_ = 0;
    for (int c = 0; c < P; ++c) {
      for (int k = 0; k < N; ++k) {
        if (k < structure.first[c] || k > structure.last[c])
          outside_[num_outside_++] = static_cast<std::uint16_t>(c * N + k);
      }
    }
    structure_ = structure;
    for (int k = 0; k < kPacked; ++k) p_[k] = Scalar(0);
    for (int i = 0; i < P; ++i) p_[index(i, i)] = p0[i];
    return UpdateStatus::ok;
  }

  /// Folds the sample y = H phi + v, v ~ N(0, diag(r)) into phi and P, then multiplies P by
  /// `scale` (1 for the Kalman filter, 1/mu for forgetting). H: N x P, y: N, r: N variances > 0.
  /// gate > 0 rejects the sample (rejected_outlier) when some e_k^2 > gate^2 S_kk.
  /// Errors (state unchanged): rejected_non_finite, invalid_argument (H nonzero outside its
  /// structure), not_positive_definite, rejected_outlier.
  UpdateStatus assimilate(const Regressor& H, const MeasVector& y, const MeasVector& r, Scalar gate, Scalar scale,
                          ParamVector& phi) noexcept {
    const Scalar* h = H.data();  // column-major: column c at h + c * N
    for (int n = 0; n < num_outside_; ++n) {
      const Scalar x = h[outside_[n]];
      if (x != Scalar(0)) return std::isfinite(x) ? UpdateStatus::invalid_argument : UpdateStatus::rejected_non_finite;
    }
    // Innovation e = y - H phi (non-finite H, y or phi shows up here).
    Scalar e[N];
    for (int k = 0; k < N; ++k) e[k] = y[k];
    for (int c = 0; c < P; ++c) {
      const Scalar pc = phi[c];
      for (int k = 0; k < N; ++k) e[k] -= h[c * N + k] * pc;
    }
    for (int k = 0; k < N; ++k) {
      if (!std::isfinite(e[k]) || !std::isfinite(r[k])) return UpdateStatus::rejected_non_finite;
      if (!(r[k] > Scalar(0))) return UpdateStatus::not_positive_definite;
    }
    compute_v(h);
    // S = H V + diag(r), lower triangle: S_ks = sum over columns c with H(k, c) != 0.
    Scalar S[N][N];
    for (int k = 0; k < N; ++k) {
      for (int s = 0; s <= k; ++s) S[k][s] = Scalar(0);
      S[k][k] = r[k];
    }
    for (int c = 0; c < P; ++c) {
      const int f = structure_.first[c], l = structure_.last[c];
      for (int k = f; k <= l; ++k) {
        const Scalar hk = h[c * N + k];
        for (int s = 0; s <= k; ++s) S[k][s] += hk * v_[c][s];
      }
    }
    for (int k = 0; k < N; ++k) {
      for (int s = 0; s <= k; ++s) {
        if (!std::isfinite(S[k][s])) return UpdateStatus::rejected_non_finite;
      }
    }
    if (gate > Scalar(0)) {
      for (int k = 0; k < N; ++k) {
        if (e[k] * e[k] > gate * gate * S[k][k]) return UpdateStatus::rejected_outlier;
      }
    }
    // Cholesky S = L L^T in place (lower), inv_d_ = 1 / L_kk.
    for (int k = 0; k < N; ++k) {
      for (int s = 0; s <= k; ++s) {
        Scalar x = S[k][s];
        for (int t = 0; t < s; ++t) x -= S[k][t] * S[s][t];
        if (s == k) {
          if (!(x > Scalar(0))) return UpdateStatus::not_positive_definite;
          const Scalar d = std::sqrt(x);
          S[k][k] = d;
          inv_d_[k] = Scalar(1) / d;
        } else {
          S[k][s] = x * inv_d_[s];
        }
      }
    }
    // z = L^-1 e.
    Scalar z[N];
    for (int k = 0; k < N; ++k) {
      Scalar x = e[k];
      for (int t = 0; t < k; ++t) x -= S[k][t] * z[t];
      z[k] = x * inv_d_[k];
    }
    // W = V L^-T row by row (in place), the parameter change W z, and the updated diagonal.
    for (int i = 0; i < P; ++i) {
      Scalar* w = v_[i];
      Scalar dphi = Scalar(0), ww = Scalar(0);
      for (int k = 0; k < N; ++k) {
        Scalar x = w[k];
        for (int t = 0; t < k; ++t) x -= S[k][t] * w[t];
        x *= inv_d_[k];
        w[k] = x;
        dphi += x * z[k];
        ww += x * x;
      }
      if (!(p_[index(i, i)] - ww > Scalar(0)) || !std::isfinite(dphi)) return UpdateStatus::not_positive_definite;
      dphi_[i] = dphi;
    }
    if (scale == Scalar(1)) {
      downdate<false>(Scalar(1));
    } else {
      downdate<true>(scale);
    }
    for (int i = 0; i < P; ++i) phi[i] += dphi_[i];
    return UpdateStatus::ok;
  }

  /// P(i, j) for any i, j.
  Scalar operator()(int i, int j) const noexcept { return i <= j ? p_[index(i, j)] : p_[index(j, i)]; }

  /// Diagonal of P (parameter variances).
  void diagonal(ParamVector& out) const noexcept {
    for (int i = 0; i < P; ++i) out[i] = p_[index(i, i)];
  }
  Scalar trace() const noexcept {
    Scalar t(0);
    for (int i = 0; i < P; ++i) t += p_[index(i, i)];
    return t;
  }
  /// The full P into `out` (host-side diagnostics and tests).
  void to_dense(Eigen::Matrix<Scalar, P, P>& out) const noexcept {
    for (int i = 0; i < P; ++i) {
      for (int j = i; j < P; ++j) out(i, j) = out(j, i) = p_[index(i, j)];
    }
  }

 private:
  struct Run {
    std::uint8_t begin, end, code;
  };

  template <int R0, int R1>
  static DYNCAL_ALWAYS_INLINE void mac2(Scalar p0, Scalar p1, const Scalar* h, Scalar* a0, Scalar* a1) noexcept {
    DYNCAL_UNROLL
    for (int k = R0; k <= R1; ++k) {
      a0[k] += p0 * h[k];
      a1[k] += p1 * h[k];
    }
  }

  /// Adds columns [b, e) of one run (rows R0..R1 of H) to rows i and i + 1 of V.
  template <int R0, int R1>
  DYNCAL_ALWAYS_INLINE void run2(int i, int b, int e, const Scalar* H, Scalar* a0, Scalar* a1) const noexcept {
    if (b >= i + 2) {  // the whole run right of the 2 x 2 diagonal block: rows i and i + 1, contiguous
      const Scalar* r0 = p_ + row_[i] + b;
      const Scalar* r1 = p_ + row_[i + 1] + b;
      const Scalar* h = H + b * N;
      for (int n = e - b; n > 0; --n, h += N) mac2<R0, R1>(*r0++, *r1++, h, a0, a1);
      return;
    }
    int c = b;
    const int lower_end = e < i ? e : i;
    if (c < lower_end) {  // P(c, i) and P(c, i + 1) are neighbours in row c
      const Scalar* q = p_ + row_[c] + i;
      const Scalar* h = H + c * N;
      for (; c < lower_end; ++c, h += N) {
        mac2<R0, R1>(q[0], q[1], h, a0, a1);
        q += P - 1 - c;
      }
    }
    for (; c < e && c < i + 2; ++c) {  // the 2 x 2 diagonal corner
      const Scalar pii = p_[row_[i] + i], pij = p_[row_[i] + i + 1], pjj = p_[row_[i + 1] + i + 1];
      if (c == i) {
        mac2<R0, R1>(pii, pij, H + c * N, a0, a1);
      } else {
        mac2<R0, R1>(pij, pjj, H + c * N, a0, a1);
      }
    }
    if (c < e) {  // rows i and i + 1, contiguous
      const Scalar* r0 = p_ + row_[i] + c;
      const Scalar* r1 = p_ + row_[i + 1] + c;
      const Scalar* h = H + c * N;
      for (; c < e; ++c, h += N) mac2<R0, R1>(*r0++, *r1++, h, a0, a1);
    }
  }

  template <int Code>
  DYNCAL_ALWAYS_INLINE void dispatch2(int code, int i, int b, int e, const Scalar* H, Scalar* a0,
                                      Scalar* a1) const noexcept {
    if constexpr (Code < 2 * N) {
      if (code == Code) {
        if constexpr (Code < N) {
          run2<0, Code>(i, b, e, H, a0, a1);
        } else {
          run2<Code - N, Code - N>(i, b, e, H, a0, a1);
        }
      } else {
        dispatch2<Code + 1>(code, i, b, e, H, a0, a1);
      }
    }
  }

  /// V = P H^T (rows of v_), two rows of P at a time, skipping H's structural zeros.
  void compute_v(const Scalar* H) noexcept {
    int i = 0;
    for (; i + 1 < P; i += 2) {
      Scalar a0[N], a1[N];
      DYNCAL_UNROLL
      for (int k = 0; k < N; ++k) a0[k] = a1[k] = Scalar(0);
      for (int n = 0; n < num_runs_; ++n) dispatch2<0>(runs_[n].code, i, runs_[n].begin, runs_[n].end, H, a0, a1);
      DYNCAL_UNROLL
      for (int k = 0; k < N; ++k) {
        v_[i][k] = a0[k];
        v_[i + 1][k] = a1[k];
      }
    }
    if (i < P) {  // odd P: the last row alone
      DYNCAL_UNROLL
      for (int k = 0; k < N; ++k) v_[i][k] = Scalar(0);
      for (int c = 0; c < P; ++c) {
        const Scalar pic = (*this)(i, c);
        DYNCAL_UNROLL
        for (int k = structure_.first[c]; k <= structure_.last[c]; ++k) v_[i][k] += pic * H[c * N + k];
      }
    }
  }

  /// P <- s (P - W W^T) over the upper triangle, three rows at a time (W_i of three rows in
  /// registers, W_j loaded once per column for all three).
  template <bool Scaled>
  void downdate(Scalar s) noexcept {
    int i = 0;
    for (; i + 2 < P; i += 3) {
      Scalar w0[N], w1[N], w2[N];
      DYNCAL_UNROLL
      for (int k = 0; k < N; ++k) {
        w0[k] = v_[i][k];
        w1[k] = v_[i + 1][k];
        w2[k] = v_[i + 2][k];
      }
      Scalar* r0 = p_ + index(i, i);
      Scalar* r1 = p_ + index(i + 1, i + 1);
      Scalar* r2 = p_ + index(i + 2, i + 2);
      // The 3 x 3 corner: P(i, i..i+2), P(i+1, i+1..i+2), P(i+2, i+2).
      Scalar x00 = r0[0], x01 = r0[1], x02 = r0[2], x11 = r1[0], x12 = r1[1], x22 = r2[0];
      DYNCAL_UNROLL
      for (int k = 0; k < N; ++k) {
        x00 -= w0[k] * w0[k];
        x01 -= w0[k] * w1[k];
        x02 -= w0[k] * w2[k];
        x11 -= w1[k] * w1[k];
        x12 -= w1[k] * w2[k];
        x22 -= w2[k] * w2[k];
      }
      r0[0] = Scaled ? x00 * s : x00;
      r0[1] = Scaled ? x01 * s : x01;
      r0[2] = Scaled ? x02 * s : x02;
      r1[0] = Scaled ? x11 * s : x11;
      r1[1] = Scaled ? x12 * s : x12;
      r2[0] = Scaled ? x22 * s : x22;
      r0 += 3;
      r1 += 2;
      r2 += 1;
      const Scalar* wj = v_[i + 3];
      for (int j = i + 3; j < P; ++j, wj += N) {
        Scalar x0 = *r0, x1 = *r1, x2 = *r2;
        DYNCAL_UNROLL
        for (int k = 0; k < N; ++k) {
          const Scalar w = wj[k];
          x0 -= w0[k] * w;
          x1 -= w1[k] * w;
          x2 -= w2[k] * w;
        }
        *r0++ = Scaled ? x0 * s : x0;
        *r1++ = Scaled ? x1 * s : x1;
        *r2++ = Scaled ? x2 * s : x2;
      }
    }
    for (; i < P; ++i) {  // the last rows when P is not a multiple of 3
      for (int j = i; j < P; ++j) {
        Scalar x = p_[index(i, j)];
        DYNCAL_UNROLL
        for (int k = 0; k < N; ++k) x -= v_[i][k] * v_[j][k];
        p_[index(i, j)] = Scaled ? x * s : x;
      }
    }
  }

  Scalar p_[kPacked] = {};
  Scalar v_[P][N] = {};  ///< V = P H^T, then W = V L^-T
  Scalar dphi_[P] = {};
  Scalar inv_d_[N] = {};
  RegressorStructure<P> structure_ = RegressorStructure<P>::dense(N);
  Run runs_[P] = {};
  int num_runs_ = 0;
  /// row_[i] = index(i, i) - i: P(i, j) = p_[row_[i] + j] for j >= i.
  static constexpr struct RowOffsets {
    int v[P];
    constexpr RowOffsets() : v() {
      for (int i = 0; i < P; ++i) v[i] = index(i, i) - i;
    }
    constexpr int operator[](int i) const { return v[i]; }
  } row_{};
  std::uint16_t outside_[P * N] = {};  ///< positions in H (column-major) outside the structure
  int num_outside_ = 0;
};

}  // namespace dyncal
