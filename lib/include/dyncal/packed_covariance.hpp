#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "arm_float_kernels.hpp"
#include "estimator_size.hpp"
#include "regressor_structure.hpp"
#include "status.hpp"

// The short loops over the N measurements must be unrolled for the accumulators to live in
// registers (GCC does not unroll at -O2 by itself). Under AddressSanitizer the hints are dropped: they
// only make the instrumented build faster to run, and forced inlining and unrolling with every access
// instrumented cost 4-5x the compile time (an identification unit: 110 s against 23 s). The loops
// mean the same either way.
#if defined(__SANITIZE_ADDRESS__)
#define DYNCAL_NO_UNROLL_HINTS 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define DYNCAL_NO_UNROLL_HINTS 1
#endif
#endif
#if defined(DYNCAL_NO_UNROLL_HINTS)
#define DYNCAL_ALWAYS_INLINE_LAMBDA
#define DYNCAL_ALWAYS_INLINE inline
#define DYNCAL_UNROLL
#elif defined(__clang__)
#define DYNCAL_ALWAYS_INLINE inline __attribute__((always_inline))
#define DYNCAL_UNROLL _Pragma("unroll")
#define DYNCAL_ALWAYS_INLINE_LAMBDA __attribute__((always_inline))
#elif defined(__GNUC__)
#define DYNCAL_ALWAYS_INLINE inline __attribute__((always_inline))
#define DYNCAL_UNROLL _Pragma("GCC unroll 16")
#define DYNCAL_ALWAYS_INLINE_LAMBDA __attribute__((always_inline))
#else
#define DYNCAL_ALWAYS_INLINE_LAMBDA
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
/// skipped) and N * P(P+1)/2 for the downdate; no heap, no exceptions. V is built four rows of P
/// at a time (two in double) over runs of columns with the same rows of H, and a trailing block of
/// per-joint term columns (friction) in one unrolled pass. In float with N = 6 on an ARMv7E-M core
/// the inner loops are the assembler kernels of arm_float_kernels.hpp.
///
/// Safeguards (every failure leaves phi and P exactly as they were): non-finite input, an entry
/// of H outside its declared structure, r <= 0, S not positive definite, a diagonal entry of the
/// updated P not positive (checked before P is written), and optional innovation gating.
///
/// Size: P parameters fixed at compile time (the firmware), or P = Eigen::Dynamic with at most MaxP
/// set by reset() from p0's size (the host's one instantiation per N for every robot and term
/// set). The run-time size stores P in the packed layout of MaxP (row i at index(i, i)), without
/// heap: the vectors are Eigen's fixed-capacity dynamic matrices. The same loops run either way.
template <typename Scalar, int P, int N, int MaxP = P>
class PackedCovariance {
 public:
  static constexpr bool kDynamic = P == Eigen::Dynamic;
  /// Compile-time bound on the number of parameters (storage size).
  static constexpr int kCapacity = kDynamic ? MaxP : P;
  static_assert(kCapacity >= 1 && (kDynamic || MaxP == P), "P >= 1, or P = Eigen::Dynamic with MaxP >= 1");
  static_assert(kCapacity <= 255, "run bounds are stored in 8 bits");
  static constexpr int kPacked = kCapacity * (kCapacity + 1) / 2;
  using ParamVector = ParamVectorOf<Scalar, P, kCapacity>;
  using MeasVector = Eigen::Matrix<Scalar, N, 1>;
  using Regressor = RegressorOf<Scalar, N, P, kCapacity>;
  using Structure = RegressorStructure<kCapacity>;
  using DenseMatrix = std::conditional_t<kDynamic, Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic, 0, MaxP, MaxP>,
                                         Eigen::Matrix<Scalar, P, P>>;

  /// Number of parameters: P, or the size of the p0 given to reset() (0 before it).
  int size() const noexcept {
    if constexpr (kDynamic) {
      return n_;
    } else {
      return P;
    }
  }

  /// Position of P(i, j), i <= j, in the packed array.
  static constexpr int index(int i, int j) noexcept { return i * kCapacity - (i * (i - 1)) / 2 + (j - i); }

  /// P = diag(p0) (every p0_i > 0 and finite) and the structure of H (rows within 0..N-1).
  /// invalid_argument otherwise, and nothing changes.
  template <int Rows = N>
  UpdateStatus reset(const ParamVector& p0, const Structure& structure) noexcept {
    static_assert(Rows == N, "PackedCovariance is sized for N rows");
    // Every check before anything is written: a refused reset leaves the covariance as it was.
    int n = P;
    if constexpr (kDynamic) {
      if (p0.size() < 1 || p0.size() > MaxP) return UpdateStatus::invalid_argument;
      n = static_cast<int>(p0.size());
    }
    for (int i = 0; i < n; ++i) {
      if (!(p0[i] > Scalar(0)) || !std::isfinite(p0[i])) return UpdateStatus::invalid_argument;
      const int f = structure.first[i], l = structure.last[i];
      if (f <= l && (f < 0 || l >= N)) return UpdateStatus::invalid_argument;
    }
    if constexpr (kDynamic) n_ = n;
    int runs = 0;
    for (int c = 0; c < size(); ++c) {
      const int f = structure.first[c], l = structure.last[c];
      if (f > l) continue;  // an all-zero column
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
    // A trailing term block (friction and other per-joint terms): M columns per joint, joint j's on
    // row j only, joints in order. V takes it in one unrolled pass instead of N runs.
    term_columns_ = 0;
    num_base_runs_ = runs;
    for (int m = kMaxTermColumns; m >= 1; --m) {
      const int b = size() - m * N;
      if (b < 0) continue;
      bool block = true;
      for (int c = b; c < size() && block; ++c)
        block = structure.first[c] == (c - b) / m && structure.last[c] == (c - b) / m;
      if (!block) continue;
      int r = 0;
      while (r < runs && runs_[r].begin < b) ++r;
      if (r < runs && runs_[r].begin == b) {
        term_columns_ = m;
        num_base_runs_ = r;
      }
      break;
    }
    num_zero_columns_ = 0;
    for (int c = 0; c < size(); ++c) {
      if (structure.first[c] > structure.last[c]) zero_columns_[num_zero_columns_++] = static_cast<std::uint8_t>(c);
    }
    structure_ = structure;
    for (int k = 0; k < kPacked; ++k) p_[k] = Scalar(0);
    for (int i = 0; i < size(); ++i) p_[index(i, i)] = p0[i];
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
    Scalar e[N];
    const Bits outside = innovation(h, y, phi, e);
    if ((outside << 1) != 0) return outside_status(h);
    for (int k = 0; k < N; ++k) {
      if (!std::isfinite(e[k]) || !std::isfinite(r[k])) return UpdateStatus::rejected_non_finite;
      if (!(r[k] > Scalar(0))) return UpdateStatus::not_positive_definite;
    }
    compute_v(h);
    Scalar S[N][N];  // H V + diag(r), then its Cholesky factor
    if (!innovation_covariance(h, r, S)) return UpdateStatus::rejected_non_finite;
    if (gate > Scalar(0)) {
      for (int k = 0; k < N; ++k) {
        if (e[k] * e[k] > gate * gate * S[k][k]) return UpdateStatus::rejected_outlier;
      }
    }
    if (!cholesky_in_place(S)) return UpdateStatus::not_positive_definite;
    // z = L^-1 e.
    Scalar z[N];
    for (int k = 0; k < N; ++k) {
      Scalar x = e[k];
      for (int t = 0; t < k; ++t) x -= S[k][t] * z[t];
      z[k] = x * inv_d_[k];
    }
    // W = V L^-T row by row (in place), the parameter change W z, and the updated diagonal.
    if constexpr (kAsmW) {
      // L and 1 / diag(L) (21 values) stay in FPU registers for all rows; dphi_i = w_i . z after.
      float c[N * (N + 1) / 2];
      for (int k = 0; k < N; ++k) {
        for (int t = 0; t < k; ++t) c[k * (k + 1) / 2 + t] = S[k][t];
        c[k * (k + 1) / 2 + k] = inv_d_[k];
      }
      if (!w_rows_float6(&v_[0][0], c, p_, kCapacity, kCapacity)) return UpdateStatus::not_positive_definite;
      if (!std::isfinite(dot_rows_float6(&v_[0][0], z, dphi_, kCapacity))) return UpdateStatus::not_positive_definite;
    } else if (!w_rows(S, z)) {
      return UpdateStatus::not_positive_definite;
    }
    if (scale == Scalar(1)) {
      downdate<false>(Scalar(1));
    } else {
      downdate<true>(scale);
    }
    for (int i = 0; i < size(); ++i) phi[i] += dphi_[i];
    return UpdateStatus::ok;
  }

  /// P(i, j) for any i, j.
  Scalar operator()(int i, int j) const noexcept { return i <= j ? p_[index(i, j)] : p_[index(j, i)]; }

  /// Diagonal of P (parameter variances).
  void diagonal(ParamVector& out) const noexcept {
    if constexpr (kDynamic) out.resize(size());
    for (int i = 0; i < size(); ++i) out[i] = p_[index(i, i)];
  }
  Scalar trace() const noexcept {
    Scalar t(0);
    for (int i = 0; i < size(); ++i) t += p_[index(i, i)];
    return t;
  }
  /// The full P into `out` (host-side diagnostics and tests).
  void to_dense(DenseMatrix& out) const noexcept {
    if constexpr (kDynamic) out.resize(size(), size());
    for (int i = 0; i < size(); ++i) {
      for (int j = i; j < size(); ++j) out(i, j) = out(j, i) = p_[index(i, j)];
    }
  }

 private:
  /// The first entry of H outside the structure that is not zero: invalid_argument if finite,
  /// rejected_non_finite otherwise (ok if there is none).
  UpdateStatus outside_status(const Scalar* h) const noexcept {
    for (int c = 0; c < size(); ++c) {
      for (int k = 0; k < N; ++k) {
        const Scalar x = h[c * N + k];
        if ((k < structure_.first[c] || k > structure_.last[c]) && x != Scalar(0))
          return std::isfinite(x) ? UpdateStatus::invalid_argument : UpdateStatus::rejected_non_finite;
      }
    }
    return UpdateStatus::ok;
  }

  using Bits = std::conditional_t<sizeof(Scalar) == 8, std::uint64_t, std::uint32_t>;
  static_assert(sizeof(Bits) == sizeof(Scalar), "Scalar must be float or double");
  static Bits bits(Scalar x) noexcept {
    Bits b;
    std::memcpy(&b, &x, sizeof b);
    return b;
  }

  /// The innovation e = y - H phi over H's structure (a non-finite H, y or phi shows up in it), and
  /// the bit patterns of every entry outside the structure OR-ed together: any bit but the sign
  /// means a nonzero (or non-finite) entry where the structure promises zero.
  DYNCAL_ALWAYS_INLINE Bits innovation(const Scalar* h, const MeasVector& y, const ParamVector& phi,
                                       Scalar (&e)[N]) const noexcept {
    for (int k = 0; k < N; ++k) e[k] = y[k];
    Bits outside = 0;
    for (int n = 0; n < num_runs_; ++n) {
      const Run& u = runs_[n];
      with_rows(u.code, [&](auto r0, auto r1) DYNCAL_ALWAYS_INLINE_LAMBDA {
        constexpr int R0 = decltype(r0)::value, R1 = decltype(r1)::value;
        for (int c = u.begin; c < u.end; ++c) {
          const Scalar pc = phi[c];
          const Scalar* hc = h + c * N;
          DYNCAL_UNROLL
          for (int k = 0; k < N; ++k) {
            if (k >= R0 && k <= R1) {
              e[k] -= hc[k] * pc;
            } else {
              outside |= bits(hc[k]);
            }
          }
        }
      });
    }
    for (int n = 0; n < num_zero_columns_; ++n) {
      for (int k = 0; k < N; ++k) outside |= bits(h[zero_columns_[n] * N + k]);
    }
    return outside;
  }

  /// S = H V + diag(r), lower triangle (S_ks = sum over columns c with H(k, c) != 0; V from
  /// compute_v). False when an entry is not finite.
  DYNCAL_ALWAYS_INLINE bool innovation_covariance(const Scalar* h, const MeasVector& r, Scalar (&S)[N][N]) noexcept {
    if constexpr (kAsmW) {
      float packed[N * (N + 1) / 2] = {};
      for (int k = 0; k < N; ++k) packed[k * (k + 1) / 2 + k] = r[k];
      const int runs = term_columns_ > 0 ? num_base_runs_ : num_runs_;
      for (int n = 0; n < runs; ++n) {
        const Run& u = runs_[n];
        with_rows(u.code, [&](auto r0, auto r1) DYNCAL_ALWAYS_INLINE_LAMBDA {
          s_run_float6<decltype(r0)::value, decltype(r1)::value>(packed, v_[u.begin], h + u.begin * N, u.end - u.begin);
        });
      }
      if (term_columns_ > 0) {
        const int b = size() - term_columns_ * N;
        s_terms_float6(packed, v_[b], h + b * N, term_columns_);
      }
      for (int k = 0; k < N; ++k) {
        for (int t = 0; t <= k; ++t) S[k][t] = packed[k * (k + 1) / 2 + t];
      }
    } else {
      s_runs(h, r, S);
    }
    for (int k = 0; k < N; ++k) {
      for (int s = 0; s <= k; ++s) {
        if (!std::isfinite(S[k][s])) return false;
      }
    }
    return true;
  }

  /// Cholesky S = L L^T in place (lower), inv_d_ = 1 / L_kk. False when S is not positive definite.
  DYNCAL_ALWAYS_INLINE bool cholesky_in_place(Scalar (&S)[N][N]) noexcept {
    for (int k = 0; k < N; ++k) {
      for (int s = 0; s <= k; ++s) {
        Scalar x = S[k][s];
        for (int t = 0; t < s; ++t) x -= S[k][t] * S[s][t];
        if (s == k) {
          if (!(x > Scalar(0))) return false;
          const Scalar d = std::sqrt(x);
          S[k][k] = d;
          inv_d_[k] = Scalar(1) / d;
        } else {
          S[k][s] = x * inv_d_[s];
        }
      }
    }
    return true;
  }

  /// S = H V + diag(r) (lower triangle) over H's runs: S_kt = sum of H(k, c) V(c, t), t <= k.
  DYNCAL_ALWAYS_INLINE void s_runs(const Scalar* h, const MeasVector& r, Scalar (&S)[N][N]) const noexcept {
    for (int k = 0; k < N; ++k) {
      for (int t = 0; t <= k; ++t) S[k][t] = Scalar(0);
      S[k][k] = r[k];
    }
    for (int n = 0; n < num_runs_; ++n) {
      const Run& u = runs_[n];
      with_rows(u.code, [&](auto r0, auto r1) DYNCAL_ALWAYS_INLINE_LAMBDA {
        for (int c = u.begin; c < u.end; ++c) {
          DYNCAL_UNROLL
          for (int k = decltype(r0)::value; k <= decltype(r1)::value; ++k) {
            const Scalar hk = h[c * N + k];
            DYNCAL_UNROLL
            for (int t = 0; t <= k; ++t) S[k][t] += hk * v_[c][t];
          }
        }
      });
    }
  }

  /// W = V L^-T row by row (in place, L in S's lower triangle) and dphi = W z; false if some
  /// updated diagonal p_ii - |w_i|^2 is not positive or some dphi_i is not finite.
  bool w_rows(const Scalar (&S)[N][N], const Scalar (&z)[N]) noexcept {
    for (int i = 0; i < size(); ++i) {
      Scalar* w = v_[i];
      Scalar dphi = Scalar(0), ww = Scalar(0);
      DYNCAL_UNROLL
      for (int k = 0; k < N; ++k) {
        Scalar x = w[k];
        DYNCAL_UNROLL
        for (int t = 0; t < k; ++t) x -= S[k][t] * w[t];
        x *= inv_d_[k];
        w[k] = x;
        dphi += x * z[k];
        ww += x * x;
      }
      if (!(p_[index(i, i)] - ww > Scalar(0)) || !std::isfinite(dphi)) return false;
      dphi_[i] = dphi;
    }
    return true;
  }

  /// The ARMv7E-M float kernels for S, W, dphi and the downdate (six measurements).
  static constexpr bool kAsmW = kArmFloatKernels && std::is_same_v<Scalar, float> && N == 6 && !kDynamic;

  struct Run {
    std::uint8_t begin, end, code;
  };
  /// The ARMv7E-M float kernels for V's runs (four rows, six measurements).
  template <int B>
  static constexpr bool kAsmV = (kArmFloatKernels && std::is_same_v<Scalar, float> && N == 6 && B == 4 && !kDynamic);

  /// Rows of P per block in V = P H^T: the accumulators (kBlock x N) stay in FPU registers
  /// (32 single-precision on the M4F; 16 double on the M7).
  static constexpr int kBlock = sizeof(Scalar) <= 4 ? 4 : 2;

  /// a[r][k] += p[r] * h[k] for the B rows of a block and the rows R0..R1 of one column of H.
  template <int B, int R0, int R1>
  static DYNCAL_ALWAYS_INLINE void mac(const Scalar (&p)[B], const Scalar* h, Scalar (&a)[B][N]) noexcept {
    DYNCAL_UNROLL
    for (int k = R0; k <= R1; ++k) {
      const Scalar hk = h[k];
      DYNCAL_UNROLL
      for (int r = 0; r < B; ++r) a[r][k] += p[r] * hk;
    }
  }

  /// Columns [b, e) of one run (H rows R0..R1), all left of rows i..i+B-1, added to those rows
  /// of V: P(c, i..i+B-1) are neighbours in packed row c.
  template <int B, int R0, int R1>
  DYNCAL_ALWAYS_INLINE void run_left(int i, int b, int e, const Scalar* H, Scalar (&a)[B][N]) const noexcept {
    if constexpr (kAsmV<B>) {
      v_left_float6<R0, R1>(&a[0][0], p_ + row_[b] + i, kCapacity - 1 - b, H + b * N, e - b);
      return;
    }
    const Scalar* h = H + b * N;
    const Scalar* q = p_ + row_[b] + i;
    int stride = kCapacity - 1 - b;
    for (int n = e - b; n > 0; --n, h += N) {
      Scalar p[B];
      DYNCAL_UNROLL
      for (int r = 0; r < B; ++r) p[r] = q[r];
      mac<B, R0, R1>(p, h, a);
      q += stride--;
    }
  }

  /// As run_left for columns [b, e) right of the block: the B rows of P are contiguous there.
  template <int B, int R0, int R1>
  DYNCAL_ALWAYS_INLINE void run_right(int i, int b, int e, const Scalar* H, Scalar (&a)[B][N]) const noexcept {
    if constexpr (kAsmV<B>) {
      v_right_float6<R0, R1>(&a[0][0], p_ + row_[i] + b, p_ + row_[i + 1] + b, p_ + row_[i + 2] + b,
                             p_ + row_[i + 3] + b, H + b * N, e - b);
      return;
    }
    const Scalar* h = H + b * N;
    const Scalar* q[B];
    DYNCAL_UNROLL
    for (int r = 0; r < B; ++r) q[r] = p_ + row_[i + r] + b;
    for (int n = e - b; n > 0; --n, h += N) {
      Scalar p[B];
      DYNCAL_UNROLL
      for (int r = 0; r < B; ++r) p[r] = *q[r]++;
      mac<B, R0, R1>(p, h, a);
    }
  }

  /// Any columns [b, e): the parts left of, inside (the B x B diagonal corner) and right of the block.
  template <int B, int R0, int R1>
  DYNCAL_ALWAYS_INLINE void run_any(int i, int b, int e, const Scalar* H, const Scalar (&corner)[B][B],
                                    Scalar (&a)[B][N]) const noexcept {
    int c = b;
    if (c < i) {
      const int end = e < i ? e : i;
      run_left<B, R0, R1>(i, c, end, H, a);
      c = end;
    }
    const int corner_end = e < i + B ? e : i + B;
    if constexpr (kAsmV<B>) {
      if (c < corner_end) v_dense_float6<R0, R1>(&a[0][0], corner[c - i], H + c * N, corner_end - c);
      c = corner_end;
    }
    for (; c < corner_end; ++c) mac<B, R0, R1>(corner[c - i], H + c * N, a);
    if (c < e) run_right<B, R0, R1>(i, c, e, H, a);
  }

  template <int K>
  using Row = std::integral_constant<int, K>;

  /// Calls f(Row<R0>, Row<R1>) for a run's code: code < N means rows 0..code of H, code >= N the
  /// single row code - N. The rows are compile-time constants, so f's loops unroll.
  template <int Code = 0, class F>
  static DYNCAL_ALWAYS_INLINE void with_rows(int code, F&& f) noexcept {
    if constexpr (Code < 2 * N) {
      if (code == Code) {
        if constexpr (Code < N) {
          f(Row<0>{}, Row<Code>{});
        } else {
          f(Row<Code - N>{}, Row<Code - N>{});
        }
      } else {
        with_rows<Code + 1>(code, f);
      }
    }
  }

  /// The term block (right of rows i..i+B-1, M columns per joint) added to those rows of V.
  template <int B, int M>
  DYNCAL_ALWAYS_INLINE void terms(int i, const Scalar* H, Scalar (&a)[B][N]) const noexcept {
    const int b = size() - M * N;
    const Scalar* q[B];
    DYNCAL_UNROLL
    for (int r = 0; r < B; ++r) q[r] = p_ + row_[i + r] + b;
    DYNCAL_UNROLL
    for (int j = 0; j < N; ++j) {
      DYNCAL_UNROLL
      for (int t = 0; t < M; ++t) {
        const Scalar hj = H[(b + j * M + t) * N + j];
        DYNCAL_UNROLL
        for (int r = 0; r < B; ++r) a[r][j] += q[r][j * M + t] * hj;
      }
    }
  }

  /// Rows i..i+B-1 of V = P H^T, accumulated over the runs of H's structure (in registers; with
  /// the ARM kernels in V's rows, which each kernel loads and stores with one VLDM / VSTM).
  template <int B>
  DYNCAL_ALWAYS_INLINE void block_v(int i, const Scalar* H) noexcept {
    if constexpr (kAsmV<B>) {
      // The ARM kernels accumulate straight into V's rows (zeroed by compute_v; B rows of N are
      // contiguous in v_).
      accumulate_v<B>(i, H, *reinterpret_cast<Scalar(*)[B][N]>(&v_[i][0]));
    } else {
      // The portable loops in a local array the compiler keeps in registers.
      Scalar a[B][N];
      DYNCAL_UNROLL
      for (int r = 0; r < B; ++r) {
        DYNCAL_UNROLL
        for (int k = 0; k < N; ++k) a[r][k] = Scalar(0);
      }
      accumulate_v<B>(i, H, a);
      DYNCAL_UNROLL
      for (int r = 0; r < B; ++r) {
        DYNCAL_UNROLL
        for (int k = 0; k < N; ++k) v_[i + r][k] = a[r][k];
      }
    }
  }

  /// a += rows i..i+B-1 of P H^T, over the runs of H's structure and the term block.
  template <int B>
  DYNCAL_ALWAYS_INLINE void accumulate_v(int i, const Scalar* H, Scalar (&a)[B][N]) const noexcept {
    Scalar corner[B][B];  // corner[s][r] = P(i + r, i + s)
    for (int r = 0; r < B; ++r) {
      for (int s = r; s < B; ++s) corner[s][r] = corner[r][s] = p_[row_[i + r] + i + s];
    }
    const int term_begin = size() - term_columns_ * N;
    const bool fast_terms = term_columns_ > 0 && i + B <= term_begin;
    const int runs = fast_terms ? num_base_runs_ : num_runs_;
    // Runs are in column order: wholly left of the block, overlapping it, wholly right of it.
    int n = 0;
    for (; n < runs && runs_[n].end <= i; ++n) {
      const Run& u = runs_[n];
      with_rows(u.code, [&](auto r0, auto r1) DYNCAL_ALWAYS_INLINE_LAMBDA {
        run_left<B, decltype(r0)::value, decltype(r1)::value>(i, u.begin, u.end, H, a);
      });
    }
    for (; n < runs && runs_[n].begin < i + B; ++n) {
      const Run& u = runs_[n];
      with_rows(u.code, [&](auto r0, auto r1) DYNCAL_ALWAYS_INLINE_LAMBDA {
        run_any<B, decltype(r0)::value, decltype(r1)::value>(i, u.begin, u.end, H, corner, a);
      });
    }
    for (; n < runs; ++n) {
      const Run& u = runs_[n];
      with_rows(u.code, [&](auto r0, auto r1) DYNCAL_ALWAYS_INLINE_LAMBDA {
        run_right<B, decltype(r0)::value, decltype(r1)::value>(i, u.begin, u.end, H, a);
      });
    }
    if constexpr (kAsmV<B>) {
      if (fast_terms && term_columns_ <= 2) {
        if (term_columns_ == 1) {
          v_terms_float6<1>(&a[0][0], p_ + row_[i] + term_begin, kCapacity - 1 - i, h_terms_);
        } else {
          v_terms_float6<2>(&a[0][0], p_ + row_[i] + term_begin, kCapacity - 1 - i, h_terms_);
        }
        return;
      }
    }
    if (fast_terms) {
      switch (term_columns_) {
        case 1:
          terms<B, 1>(i, H, a);
          break;
        case 2:
          terms<B, 2>(i, H, a);
          break;
        case 3:
          terms<B, 3>(i, H, a);
          break;
        default:
          terms<B, 4>(i, H, a);
          break;
      }
    }
  }

  /// V = P H^T (rows of v_), kBlock rows of P at a time, skipping H's structural zeros.
  void compute_v(const Scalar* H) noexcept {
    if constexpr (kAsmV<kBlock>) {
      std::memset(v_, 0, sizeof v_);
      // The term block's nonzero entries, joint by joint: H(j, b + j M + t) at h_terms_[j M + t]
      // (v_terms_float6 takes one or two columns per joint; wider blocks use the portable pass).
      const int b = size() - term_columns_ * N;
      if (term_columns_ <= 2)
        for (int c = 0; c < term_columns_ * N; ++c) h_terms_[c] = H[(b + c) * N + c / term_columns_];
    }
    int i = 0;
    for (; i + kBlock <= size(); i += kBlock) block_v<kBlock>(i, H);
    for (; i < size(); ++i) block_v<1>(i, H);
  }

  /// P <- s (P - W W^T) over the upper triangle, three rows at a time (W_i of three rows in
  /// registers, W_j loaded once per column for all three).
  template <bool Scaled>
  void downdate(Scalar s) noexcept {
    if constexpr (kAsmW) {
      downdate_float6<Scaled>(p_, &v_[0][0], kCapacity, s);
      return;
    }
    int i = 0;
    for (; i + 2 < size(); i += 3) {
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
      for (int j = i + 3; j < size(); ++j, wj += N) {
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
    for (; i < size(); ++i) {  // the last rows when P is not a multiple of 3
      for (int j = i; j < size(); ++j) {
        Scalar x = p_[index(i, j)];
        DYNCAL_UNROLL
        for (int k = 0; k < N; ++k) x -= v_[i][k] * v_[j][k];
        p_[index(i, j)] = Scaled ? x * s : x;
      }
    }
  }

  static constexpr int kMaxTermColumns = 4;
  Scalar p_[kPacked] = {};
  Scalar v_[kCapacity][N] = {};  ///< V = P H^T, then W = V L^-T
  Scalar dphi_[kCapacity] = {};
  Scalar inv_d_[N] = {};
  RegressorStructure<kCapacity> structure_ = RegressorStructure<kCapacity>::dense(N);
  Run runs_[kCapacity] = {};
  int num_runs_ = 0;
  int num_base_runs_ = 0;  ///< runs before the term block
  int term_columns_ = 0;   ///< columns per joint in the trailing term block (0: none)
  /// row_[i] = index(i, i) - i: P(i, j) = p_[row_[i] + j] for j >= i.
  static constexpr struct RowOffsets {
    int v[kCapacity];
    constexpr RowOffsets() : v() {
      for (int i = 0; i < kCapacity; ++i) v[i] = index(i, i) - i;
    }
    constexpr int operator[](int i) const { return v[i]; }
  } row_{};
  std::uint8_t zero_columns_[kCapacity] = {};  ///< columns of H that the structure declares all zero
  int num_zero_columns_ = 0;
  int n_ = 0;  ///< size() when P is Eigen::Dynamic
  /// The term block's nonzero entries (ARM kernels only).
  Scalar h_terms_[kAsmV<kBlock> ? kMaxTermColumns * N : 1] = {};
};

}  // namespace dyncal
