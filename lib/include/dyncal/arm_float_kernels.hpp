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

/// p[j] <- s (p[j] - w_i . w_(i+j)) for j = 0..count - 1 (count >= 1): p is row i of packed P from
/// its diagonal, w rows i.. of W (6 floats each, contiguous; the first is w_i). Scaled selects
/// the factor s. Only available when kArmFloatKernels.
template <bool Scaled>
inline void downdate_row_float6(float* p, const float* w, int count, float s) noexcept {
#if DYNCAL_ARM_FLOAT_KERNELS
  int groups = count / 3;
  const int rest = count - 3 * groups;
  const float* wj = w;
  __asm__ volatile(
      "vmov.f32 s27, %[s]\n\t"
      "vldmia %[wi], {s0-s5}\n\t"
      "cmp %[n], #0\n\t"
      "beq 2f\n"
      "1:\n\t"
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
      "subs %[n], %[n], #1\n\t"
      "bne 1b\n"
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
      "vstr s24, [%[p]]\n\t"
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
      "vstmia %[p], {s24-s25}\n"
      "4:\n"
      : [p] "+r"(p), [wj] "+r"(wj), [n] "+r"(groups)
      : [wi] "r"(w), [rest] "r"(rest), [s] "t"(s), [scaled] "i"(Scaled ? 1 : 0)
      : "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16",
        "s17", "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27", "cc", "memory");
#else
  (void)p, (void)w, (void)count, (void)s;
#endif
}

#define DYNCAL_S0_S31                                                                                                 \
  "s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7", "s8", "s9", "s10", "s11", "s12", "s13", "s14", "s15", "s16", "s17", \
      "s18", "s19", "s20", "s21", "s22", "s23", "s24", "s25", "s26", "s27", "s28", "s29", "s30", "s31"

// Assembler text shared by the V kernels: a[r][k] (acc[6 r + k], s(6 r + k)) += p_r (s24 + r) * H(k, c)
// for the rows k = R0..R1 of H's column c at [h]; H(k, c) goes through s28..s31 (four at a time).
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

#undef DYNCAL_V_MACROS
#undef DYNCAL_V_PURGE
#undef DYNCAL_S0_S31

}  // namespace dyncal
