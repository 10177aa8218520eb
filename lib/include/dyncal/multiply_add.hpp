#pragma once
// a * b + c with a rounding that does not depend on the compiler's choices.

#include <cmath>
#include <type_traits>

namespace dyncal {

/// a * b + c rounded once (std::fma) where the target has a fused multiply-add for Scalar
/// (FP_FAST_FMA, FP_FAST_FMAF), else rounded twice. Either way the result is fixed by the target:
/// the compiler may contract a plain `a * b + c` into a fused one or not, differently in two
/// instantiations of the same loop (a fixed and a run-time size), and those would then differ in the
/// last bits.
template <typename Scalar>
inline Scalar multiply_add(Scalar a, Scalar b, Scalar c) noexcept {
#if defined(FP_FAST_FMA)
  if constexpr (std::is_same_v<Scalar, double>) return std::fma(a, b, c);
#endif
#if defined(FP_FAST_FMAF)
  if constexpr (std::is_same_v<Scalar, float>) return std::fma(a, b, c);
#endif
  return a * b + c;
}

}  // namespace dyncal
