#pragma once
// Inner loops of PackedCovariance's measurement update (six measurements, float) written for an
// ARMv7E-M core with a single-precision FPU (Cortex-M4F, M7). GCC never emits multi-register
// VLDM/VSTM for data, and on these cores each VLDM/VSTM is one instruction however many registers
// it moves: loading three rows of W, four elements of P or a column of H at once, and keeping the
// accumulators in fixed registers, cuts the instructions per multiply-add (docs/performance.md).
// PackedCovariance uses them only when kArmFloatKernels is true; elsewhere its portable loops.

namespace dyncal {

#if defined(__thumb2__) && defined(__ARM_FP) && (__ARM_FP & 4) && defined(__ARM_FEATURE_FMA)
#define DYNCAL_ARM_FLOAT_KERNELS 1
inline constexpr bool kArmFloatKernels = true;
#else
#define DYNCAL_ARM_FLOAT_KERNELS 0
inline constexpr bool kArmFloatKernels = false;
#endif

/// P <- s (P - W W^T) over the whole upper triangle: p = packed P (rows 0..rows-1 from their
/// diagonals, one after another), w = W (rows x 6 floats). Row by row, three columns at a time
/// (one VLDM of three W rows = 18 floats; VLDM / VSTM of three P elements), the row loop in
/// assembler too (count = rows - i kept as 3 groups + rest). Scaled selects the factor s.
/// Only available when kArmFloatKernels.
template <bool Scaled>
inline void downdate_float6(float* p, const float* w, int rows, float s) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  int groups = rows / 3;
  int rest = rows - 3 * groups;
  const float* wj;
  int n;
  __asm__ volatile(
      ".macro dyn_dd_group\n\t"
      "vldmia %[wj]!, {s6-s23}\n\t"
      "vldmia %[p], {s24-s26}\n\t"
      "vfms.f32 s24, s0, s6\n\t"
      "vfms.f32 s25, s0, s12\n\t"
      "vfms.f32 s26, s0, s18\n\t"
      "vfms.f32 s24, s1, s7\n\t"
      "vfms.f32 s25, s1, s13\n\t"
      "vfms.f32 s26, s1, s19\n\t"
      "vfms.f32 s24, s2, s8\n\t"
      "vfms.f32 s25, s2, s14\n\t"
      "vfms.f32 s26, s2, s20\n\t"
      "vfms.f32 s24, s3, s9\n\t"
      "vfms.f32 s25, s3, s15\n\t"
      "vfms.f32 s26, s3, s21\n\t"
      "vfms.f32 s24, s4, s10\n\t"
      "vfms.f32 s25, s4, s16\n\t"
      "vfms.f32 s26, s4, s22\n\t"
      "vfms.f32 s24, s5, s11\n\t"
      "vfms.f32 s25, s5, s17\n\t"
      "vfms.f32 s26, s5, s23\n\t"
      ".if %c[scaled]\n\t"
      "vmul.f32 s24, s24, s27\n\t"
      "vmul.f32 s25, s25, s27\n\t"
      "vmul.f32 s26, s26, s27\n\t"
      ".endif\n\t"
      "vstmia %[p]!, {s24-s26}\n\t"
      ".endm\n\t"
      "vmov.f32 s27, %[s]\n"
      "0:\n\t"  // row i: w_i in s0..s5, columns i..rows-1 = 3 groups + rest
      "vldmia %[wi], {s0-s5}\n\t"
      "mov %[wj], %[wi]\n\t"
      "lsrs %[n], %[g], #1\n\t"
      "beq 5f\n"
      "1:\n\t"
      "dyn_dd_group\n\t"
      "dyn_dd_group\n\t"
      "subs %[n], %[n], #1\n\t"
      "bne 1b\n"
      "5:\n\t"
      "tst %[g], #1\n\t"
      "beq 2f\n\t"
      "dyn_dd_group\n"
      "2:\n\t"
      "cmp %[rest], #1\n\t"
      "blt 4f\n\t"
      "bgt 3f\n\t"
      "vldmia %[wj], {s6-s11}\n\t"
      "vldr s24, [%[p]]\n\t"
      "vfms.f32 s24, s0, s6\n\t"
      "vfms.f32 s24, s1, s7\n\t"
      "vfms.f32 s24, s2, s8\n\t"
      "vfms.f32 s24, s3, s9\n\t"
      "vfms.f32 s24, s4, s10\n\t"
      "vfms.f32 s24, s5, s11\n\t"
      ".if %c[scaled]\n\t"
      "vmul.f32 s24, s24, s27\n\t"
      ".endif\n\t"
      "vstmia %[p]!, {s24}\n\t"
      "b 4f\n"
      "3:\n\t"
      "vldmia %[wj], {s6-s17}\n\t"
      "vldmia %[p], {s24-s25}\n\t"
      "vfms.f32 s24, s0, s6\n\t"
      "vfms.f32 s25, s0, s12\n\t"
      "vfms.f32 s24, s1, s7\n\t"
      "vfms.f32 s25, s1, s13\n\t"
      "vfms.f32 s24, s2, s8\n\t"
      "vfms.f32 s25, s2, s14\n\t"
      "vfms.f32 s24, s3, s9\n\t"
      "vfms.f32 s25, s3, s15\n\t"
      "vfms.f32 s24, s4, s10\n\t"
      "vfms.f32 s25, s4, s16\n\t"
      "vfms.f32 s24, s5, s11\n\t"
      "vfms.f32 s25, s5, s17\n\t"
      ".if %c[scaled]\n\t"
      "vmul.f32 s24, s24, s27\n\t"
      "vmul.f32 s25, s25, s27\n\t"
      ".endif\n\t"
      "vstmia %[p]!, {s24-s25}\n"
      "4:\n\t"  // next row: one column fewer
      "add %[wi], %[wi], #24\n\t"
      "subs %[rest], %[rest], #1\n\t"
      "bpl 6f\n\t"
      "movs %[rest], #2\n\t"
      "subs %[g], %[g], #1\n"
      "6:\n\t"
      "subs %[rows], %[rows], #1\n\t"
      "bne 0b\n\t"
      ".purgem dyn_dd_group\n"
      : [p] "+r"(p), [wi] "+r"(w), [wj] "=&r"(wj), [n] "=&r"(n), [g] "+r"(groups), [rest] "+r"(rest), [rows] "+r"(rows)
      : [s] "t"(s), [scaled] "i"(Scaled ? 1 : 0)
      : "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16",
        "s17", "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27", "cc", "memory");
#else
  (void)p, (void)w, (void)rows, (void)s;
#endif
}

/// W = V L^-T for count >= 1 rows of V (6 floats each, in place) by forward substitution:
/// w_k = (v_k - sum_(t<k) L(k, t) w_t) / L(k, k), with c packed by rows (21 floats):
/// c[k(k+1)/2 + t] = L(k, t) for t < k and c[k(k+1)/2 + k] = 1 / L(k, k). Row i's diagonal
/// p_ii - |w_i|^2 must stay positive: pd = &P(0, 0) in packed storage, the next diagonal
/// `stride` (= P) floats on, one less each row. Returns false at the first row where it does not
/// (or is NaN); rows before it are already W. Only available when kArmFloatKernels.
inline bool w_rows_float6(float* v, const float* c, const float* pd, int stride, int count) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  int ok = 1;
  __asm__ volatile(
      "vldmia %[c], {s0-s20}\n"
      "1:\n\t"
      "vldmia %[v], {s21-s26}\n\t"
      "vmul.f32 s21, s21, s0\n\t"  // w0
      "vfms.f32 s22, s1, s21\n\t"  // w1
      "vmul.f32 s22, s22, s2\n\t"
      "vfms.f32 s23, s3, s21\n\t"  // w2
      "vfms.f32 s23, s4, s22\n\t"
      "vmul.f32 s23, s23, s5\n\t"
      "vfms.f32 s24, s6, s21\n\t"  // w3
      "vfms.f32 s24, s7, s22\n\t"
      "vfms.f32 s24, s8, s23\n\t"
      "vmul.f32 s24, s24, s9\n\t"
      "vfms.f32 s25, s10, s21\n\t"  // w4
      "vfms.f32 s25, s11, s22\n\t"
      "vfms.f32 s25, s12, s23\n\t"
      "vfms.f32 s25, s13, s24\n\t"
      "vmul.f32 s25, s25, s14\n\t"
      "vfms.f32 s26, s15, s21\n\t"  // w5
      "vfms.f32 s26, s16, s22\n\t"
      "vfms.f32 s26, s17, s23\n\t"
      "vfms.f32 s26, s18, s24\n\t"
      "vfms.f32 s26, s19, s25\n\t"
      "vmul.f32 s26, s26, s20\n\t"
      "vstmia %[v]!, {s21-s26}\n\t"
      "vldr s27, [%[pd]]\n\t"
      "vfms.f32 s27, s21, s21\n\t"
      "vfms.f32 s27, s22, s22\n\t"
      "vfms.f32 s27, s23, s23\n\t"
      "vfms.f32 s27, s24, s24\n\t"
      "vfms.f32 s27, s25, s25\n\t"
      "vfms.f32 s27, s26, s26\n\t"
      "vcmp.f32 s27, #0\n\t"
      "vmrs APSR_nzcv, fpscr\n\t"
      "ble 2f\n\t"  // not > 0, or unordered (NaN)
      "add %[pd], %[pd], %[st], lsl #2\n\t"
      "sub %[st], %[st], #1\n\t"
      "subs %[n], %[n], #1\n\t"
      "bne 1b\n\t"
      "b 3f\n"
      "2:\n\t"
      "mov %[ok], #0\n"
      "3:\n"
      : [v] "+r"(v), [pd] "+r"(pd), [st] "+r"(stride), [n] "+r"(count), [ok] "+r"(ok)
      : [c] "r"(c)
      : "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16",
        "s17", "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27", "cc", "memory");
  return ok != 0;
#else
  (void)v, (void)c, (void)pd, (void)stride, (void)count;
  return false;
#endif
}

/// out[i] = w_i . z for count >= 1 rows of W (6 floats each); returns the sum of out (non-finite
/// if any out[i] is). Only available when kArmFloatKernels.
inline float dot_rows_float6(const float* w, const float* z, float* out, int count) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  float sum = 0.0f;
  int pairs = count / 2;
  const int odd = count & 1;
  __asm__ volatile(
      "vldmia %[z], {s0-s5}\n\t"
      "cmp %[n], #0\n\t"
      "beq 2f\n"
      "1:\n\t"
      "vldmia %[w]!, {s6-s17}\n\t"
      "vmul.f32 s18, s6, s0\n\t"
      "vmul.f32 s19, s12, s0\n\t"
      "vfma.f32 s18, s7, s1\n\t"
      "vfma.f32 s19, s13, s1\n\t"
      "vfma.f32 s18, s8, s2\n\t"
      "vfma.f32 s19, s14, s2\n\t"
      "vfma.f32 s18, s9, s3\n\t"
      "vfma.f32 s19, s15, s3\n\t"
      "vfma.f32 s18, s10, s4\n\t"
      "vfma.f32 s19, s16, s4\n\t"
      "vfma.f32 s18, s11, s5\n\t"
      "vfma.f32 s19, s17, s5\n\t"
      "vstmia %[out]!, {s18-s19}\n\t"
      "vadd.f32 %[sum], %[sum], s18\n\t"
      "vadd.f32 %[sum], %[sum], s19\n\t"
      "subs %[n], %[n], #1\n\t"
      "bne 1b\n"
      "2:\n\t"
      "cmp %[odd], #0\n\t"
      "beq 3f\n\t"
      "vldmia %[w], {s6-s11}\n\t"
      "vmul.f32 s18, s6, s0\n\t"
      "vfma.f32 s18, s7, s1\n\t"
      "vfma.f32 s18, s8, s2\n\t"
      "vfma.f32 s18, s9, s3\n\t"
      "vfma.f32 s18, s10, s4\n\t"
      "vfma.f32 s18, s11, s5\n\t"
      "vstr s18, [%[out]]\n\t"
      "vadd.f32 %[sum], %[sum], s18\n"
      "3:\n"
      : [w] "+r"(w), [out] "+r"(out), [n] "+r"(pairs), [sum] "+t"(sum)
      : [z] "r"(z), [odd] "r"(odd)
      : "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16",
        "s17", "s18", "s19", "cc", "memory");
  return sum;
#else
  (void)w, (void)z, (void)out, (void)count;
  return 0.0f;
#endif
}

#define DYNCAL_S0_S31                                                                                                 \
  "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16", "s17", \
      "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27", "s28", "s29", "s30", "s31"

// Assembler text shared by the V kernels: a[r][k] (acc[6 r + k], s(6 r + k)) += p_r (s24 + r) * H(k, c)
// for the rows k = R0..R1 of H's column c at [h]; H(k, c) goes through s28..s31 (four at a time).
// Assembler text shared by the S kernels: S (lower, packed by rows, S(k, t) in s(k(k+1)/2 + t),
// s0..s20) += H(k, c) V(c, 0..k) with V's row c in s21..s26.
#define DYNCAL_S_MACROS                                \
  ".altmacro\n\t"                                      \
  ".macro dyn_sf a, b, hh\n\t"                         \
  "vfma.f32 s\\a, s\\b, s\\hh\n\t"                     \
  ".endm\n\t"                                          \
  ".macro dyn_s_row k, hh\n\t"                         \
  ".irp t, 0,1,2,3,4,5\n\t"                            \
  ".if \\t <= \\k\n\t"                                 \
  "dyn_sf %%(\\k*(\\k+1)/2+\\t), %%(21+\\t), \\hh\n\t" \
  ".endif\n\t"                                         \
  ".endr\n\t"                                          \
  ".endm\n\t"                                          \
  ".macro dyn_ldv base, last\n\t"                      \
  ".if \\last == 21\n\t"                               \
  "vldmia \\base, {s21}\n\t"                           \
  ".else\n\t"                                          \
  "vldmia \\base, {s21-s\\last}\n\t"                   \
  ".endif\n\t"                                         \
  ".endm\n\t"                                          \
  ".macro dyn_ldh base, last\n\t"                      \
  ".if \\last == 27\n\t"                               \
  "vldmia \\base, {s27}\n\t"                           \
  ".else\n\t"                                          \
  "vldmia \\base, {s27-s\\last}\n\t"                   \
  ".endif\n\t"                                         \
  ".endm\n\t"
#define DYNCAL_S_PURGE ".purgem dyn_ldh\n\t.purgem dyn_ldv\n\t.purgem dyn_s_row\n\t.purgem dyn_sf\n\t.noaltmacro\n"

/// S += H(R0..R1, c) V(c, .) restricted to S's lower triangle (S(k, t), t <= k, packed by rows in
/// s, 21 floats) for n >= 1 columns c of one run: v = V's row c0 (6 floats per row), h = H's
/// column c0 (6 floats per column).
template <int R0, int R1>
inline void s_run_float6(float* s, const float* v, const float* h, int n) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  if (R1 - R0 < 5) h += R0;
  __asm__ volatile(DYNCAL_S_MACROS
                   "vldmia %[s], {s0-s20}\n"
                   "1:\n\t"
                   "dyn_ldv %[v], %%(21+%c[r1])\n\t"
                   "add %[v], %[v], #24\n\t"
                   ".if (%c[r1] - %c[r0]) < 5\n\t"
                   "dyn_ldh %[h], %%(27+%c[r1]-%c[r0])\n\t"
                   ".irp kk, 0,1,2,3,4,5\n\t"
                   ".if (\\kk >= %c[r0]) && (\\kk <= %c[r1])\n\t"
                   "dyn_s_row \\kk, %%(27+\\kk-%c[r0])\n\t"
                   ".endif\n\t"
                   ".endr\n\t"
                   "add %[h], %[h], #24\n\t"
                   ".else\n\t"
                   "vldmia %[h]!, {s27-s31}\n\t"
                   ".irp kk, 0,1,2,3,4\n\t"
                   "dyn_s_row \\kk, %%(27+\\kk)\n\t"
                   ".endr\n\t"
                   "vldmia %[h]!, {s27}\n\t"
                   "dyn_s_row 5, 27\n\t"
                   ".endif\n\t"
                   "subs %[n], %[n], #1\n\t"
                   "bne 1b\n\t"
                   "vstmia %[s], {s0-s20}\n\t" DYNCAL_S_PURGE
                   : [v] "+r"(v), [h] "+r"(h), [n] "+r"(n)
                   : [s] "r"(s), [r0] "i"(R0), [r1] "i"(R1)
                   : DYNCAL_S0_S31, "cc", "memory");
#else
  (void)s, (void)v, (void)h, (void)n;
#endif
}

/// As s_run_float6 for a term block: m >= 1 columns per joint j = 0..5, joint j's on row j only;
/// v and h at the block's first column.
inline void s_terms_float6(float* s, const float* v, const float* h, int m) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  int count;
  __asm__ volatile(DYNCAL_S_MACROS
                   "vldmia %[s], {s0-s20}\n\t"
                   ".irp j, 0,1,2,3,4,5\n\t"
                   "mov %[cnt], %[m]\n"
                   "1:\n\t"
                   "dyn_ldv %[v], %%(21+\\j)\n\t"
                   "add %[v], %[v], #24\n\t"
                   "vldr s27, [%[h], #4*\\j]\n\t"
                   "add %[h], %[h], #24\n\t"
                   "dyn_s_row \\j, 27\n\t"
                   "subs %[cnt], %[cnt], #1\n\t"
                   "bne 1b\n\t"
                   ".endr\n\t"
                   "vstmia %[s], {s0-s20}\n\t" DYNCAL_S_PURGE
                   : [v] "+r"(v), [h] "+r"(h), [cnt] "=&r"(count)
                   : [s] "r"(s), [m] "r"(m)
                   : DYNCAL_S0_S31, "cc", "memory");
#else
  (void)s, (void)v, (void)h, (void)m;
#endif
}

#define DYNCAL_V_MACROS                          \
  ".altmacro\n\t"                                \
  ".macro dyn_vf a, p, hh\n\t"                   \
  "vfma.f32 s\\a, s\\p, s\\hh\n\t"               \
  ".endm\n\t"                                    \
  ".macro dyn_row k, hh\n\t"                     \
  "dyn_vf %%(\\k), 24, \\hh\n\t"                 \
  "dyn_vf %%(6+\\k), 25, \\hh\n\t"               \
  "dyn_vf %%(12+\\k), 26, \\hh\n\t"              \
  "dyn_vf %%(18+\\k), 27, \\hh\n\t"              \
  ".endm\n\t"                                    \
  ".macro dyn_column\n\t"                        \
  ".if (%c[r1] - %c[r0]) < 4\n\t"                \
  "vldmia %[h], {s28-s31}\n\t"                   \
  ".irp kk, 0,1,2,3,4,5\n\t"                     \
  ".if (\\kk >= %c[r0]) && (\\kk <= %c[r1])\n\t" \
  "dyn_row \\kk, %%(28+\\kk-%c[w0])\n\t"         \
  ".endif\n\t"                                   \
  ".endr\n\t"                                    \
  ".else\n\t"                                    \
  "vldmia %[h], {s28-s31}\n\t"                   \
  ".irp kk, 0,1,2,3\n\t"                         \
  ".if (\\kk >= %c[r0])\n\t"                     \
  "dyn_row \\kk, %%(28+\\kk)\n\t"                \
  ".endif\n\t"                                   \
  ".endr\n\t"                                    \
  "vldr s28, [%[h], #16]\n\t"                    \
  "vldr s29, [%[h], #20]\n\t"                    \
  "dyn_row 4, 28\n\t"                            \
  ".if %c[r1] == 5\n\t"                          \
  "dyn_row 5, 29\n\t"                            \
  ".endif\n\t"                                   \
  ".endif\n\t"                                   \
  "add %[h], %[h], #24\n\t"                      \
  ".endm\n\t"
#define DYNCAL_V_PURGE ".purgem dyn_column\n\t.purgem dyn_row\n\t.purgem dyn_vf\n\t.noaltmacro\n"

/// First row of the four-row window of H's column that holds rows R0..R1 (R1 - R0 < 4), or 0.
template <int R0, int R1>
constexpr int v_window() noexcept {
  return R1 - R0 < 4 ? (R0 < 2 ? R0 : 2) : 0;
}

/// V rows i..i+3 (acc, 24 floats, row-major) += P(c, i..i+3) H(R0..R1, c) for n >= 1 columns c
/// left of the block: q = &P(c0, i) in packed storage (four neighbours), stride = P - 1 - c0
/// (the distance to the next packed row), h = H's column c0 (six floats).
template <int R0, int R1>
inline void v_left_float6(float* acc, const float* q, int stride, const float* h, int n) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  h += v_window<R0, R1>();
  __asm__ volatile(DYNCAL_V_MACROS
                   "vldmia %[acc], {s0-s23}\n"
                   "1:\n\t"
                   "vldmia %[q], {s24-s27}\n\t"
                   "add %[q], %[q], %[st], lsl #2\n\t"
                   "sub %[st], %[st], #1\n\t"
                   "dyn_column\n\t"
                   "subs %[n], %[n], #1\n\t"
                   "bne 1b\n\t"
                   "vstmia %[acc], {s0-s23}\n\t" DYNCAL_V_PURGE
                   : [q] "+r"(q), [st] "+r"(stride), [h] "+r"(h), [n] "+r"(n)
                   : [acc] "r"(acc), [r0] "i"(R0), [r1] "i"(R1), [w0] "i"(v_window<R0, R1>())
                   : DYNCAL_S0_S31, "cc", "memory");
#else
  (void)acc, (void)q, (void)stride, (void)h, (void)n;
#endif
}

/// As v_left_float6 with the four P values of each column contiguous, column after column (q).
template <int R0, int R1>
inline void v_dense_float6(float* acc, const float* q, const float* h, int n) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  h += v_window<R0, R1>();
  __asm__ volatile(DYNCAL_V_MACROS
                   "vldmia %[acc], {s0-s23}\n"
                   "1:\n\t"
                   "vldmia %[q]!, {s24-s27}\n\t"
                   "dyn_column\n\t"
                   "subs %[n], %[n], #1\n\t"
                   "bne 1b\n\t"
                   "vstmia %[acc], {s0-s23}\n\t" DYNCAL_V_PURGE
                   : [q] "+r"(q), [h] "+r"(h), [n] "+r"(n)
                   : [acc] "r"(acc), [r0] "i"(R0), [r1] "i"(R1), [w0] "i"(v_window<R0, R1>())
                   : DYNCAL_S0_S31, "cc", "memory");
#else
  (void)acc, (void)q, (void)h, (void)n;
#endif
}

/// As v_left_float6 for n >= 1 columns right of the block: q0..q3 = &P(i + r, c0), contiguous rows.
template <int R0, int R1>
inline void v_right_float6(float* acc, const float* q0, const float* q1, const float* q2, const float* q3,
                           const float* h, int n) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  h += v_window<R0, R1>();
  __asm__ volatile(DYNCAL_V_MACROS
                   "vldmia %[acc], {s0-s23}\n"
                   "1:\n\t"
                   "vldmia %[q0]!, {s24}\n\t"
                   "vldmia %[q1]!, {s25}\n\t"
                   "vldmia %[q2]!, {s26}\n\t"
                   "vldmia %[q3]!, {s27}\n\t"
                   "dyn_column\n\t"
                   "subs %[n], %[n], #1\n\t"
                   "bne 1b\n\t"
                   "vstmia %[acc], {s0-s23}\n\t" DYNCAL_V_PURGE
                   : [q0] "+r"(q0), [q1] "+r"(q1), [q2] "+r"(q2), [q3] "+r"(q3), [h] "+r"(h), [n] "+r"(n)
                   : [acc] "r"(acc), [r0] "i"(R0), [r1] "i"(R1), [w0] "i"(v_window<R0, R1>())
                   : DYNCAL_S0_S31, "cc", "memory");
#else
  (void)acc, (void)q0, (void)q1, (void)q2, (void)q3, (void)h, (void)n;
#endif
}

/// The term block (M = 1 or 2 columns per joint, joint j's on row j only) added to V's rows
/// i..i+3 (acc, 24 floats): acc[r][j] += sum_t P(i + r, b + j M + t) h[j M + t]. q = &P(i, b) in
/// packed storage, stride = P - 1 - i (the distance to &P(i + 1, b), one less each row), h the
/// block's 6 M nonzero entries of H.
template <int M>
inline void v_terms_float6(float* acc, const float* q, int stride, const float* h) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  static_assert(M == 1 || M == 2, "one or two term columns per joint");
  __asm__ volatile(
      ".altmacro\n\t"
      ".macro dyn_tf a, p, hh\n\t"
      "vfma.f32 s\\a, s\\p, s\\hh\n\t"
      ".endm\n\t"
      ".if %c[m] == 1\n\t"
      "vldmia %[h], {s0-s5}\n\t"
      ".else\n\t"
      "vldmia %[h], {s0-s11}\n\t"
      ".endif\n\t"
      ".rept 4\n\t"
      "vldmia %[acc], {s12-s17}\n\t"
      ".if %c[m] == 1\n\t"
      "vldmia %[q], {s18-s23}\n\t"
      ".else\n\t"
      "vldmia %[q], {s18-s29}\n\t"
      ".endif\n\t"
      ".irp j, 0,1,2,3,4,5\n\t"
      ".irp t, 0,1\n\t"
      ".if \\t < %c[m]\n\t"
      "dyn_tf %%(12+\\j), %%(18+\\j*%c[m]+\\t), %%(\\j*%c[m]+\\t)\n\t"
      ".endif\n\t"
      ".endr\n\t"
      ".endr\n\t"
      "vstmia %[acc]!, {s12-s17}\n\t"
      "add %[q], %[q], %[st], lsl #2\n\t"
      "sub %[st], %[st], #1\n\t"
      ".endr\n\t"
      ".purgem dyn_tf\n\t"
      ".noaltmacro\n"
      : [acc] "+r"(acc), [q] "+r"(q), [st] "+r"(stride)
      : [h] "r"(h), [m] "i"(M)
      : "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16",
        "s17", "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27", "s28", "s29", "cc", "memory");
#else
  (void)acc, (void)q, (void)stride, (void)h;
#endif
}

#undef DYNCAL_V_MACROS
#undef DYNCAL_V_PURGE
#undef DYNCAL_S_MACROS
#undef DYNCAL_S_PURGE
#undef DYNCAL_S0_S31

}  // namespace dyncal
