// Sine and cosine of one angle together, for the generated kinematics (no libm call in range).
#pragma once

#include <cmath>

namespace dyncal {

template <typename Scalar>
struct SinCos {
  Scalar sin;
  Scalar cos;
};

namespace detail {

/// Polynomial order and reduction limits per scalar type (Taylor series on [-pi/4, pi/4]: the first
/// omitted term is below half an ulp, 8e-20 for double at x^19, 2e-9 for float at x^11).
template <typename Scalar>
struct SinCosTraits;

template <>
struct SinCosTraits<double> {
  static constexpr int kSinTerms = 8;  // x^3 .. x^17
  static constexpr int kCosTerms = 9;  // x^2 .. x^18
  static constexpr double kMaxReduced = 1e5;
  static constexpr double kRoundingShift = 6755399441055744.0;  // 1.5 * 2^52
  // pi/2 split in three parts of 33 bits and a rest, so k * part is exact for |k| < 2^20 (Cody-Waite).
  static constexpr double kPio2Hi = 1.57079632673412561417e+00;
  static constexpr double kPio2Mid = 6.07710050630396597660e-11;
  static constexpr double kPio2Lo = 2.02226624879595063154e-21;
};

template <>
struct SinCosTraits<float> {
  static constexpr int kSinTerms = 4;  // x^3 .. x^9
  static constexpr int kCosTerms = 5;  // x^2 .. x^10
  static constexpr float kMaxReduced = 1e3f;
  static constexpr float kRoundingShift = 12582912.0f;  // 1.5 * 2^23
  // 12-bit parts: k * part exact for |k| < 2^12.
  static constexpr float kPio2Hi = 1.5703125f;
  static constexpr float kPio2Mid = 4.837512969970703125e-04f;
  static constexpr float kPio2Lo = 7.54978995489188216e-08f;
};

// Nested (Horner) Taylor series, unrolled by recursion on the term index so that every coefficient
// is a compile-time constant.
template <typename Scalar, int kTerm, int kLast, int kFirstPower>
struct TaylorTail {
  // Returns 1 - r2/((p+1)(p+2)) * (1 - r2/((p+3)(p+4)) * (...)) with p = kFirstPower + 2 * kTerm.
  static Scalar eval(Scalar r2) noexcept {
    constexpr int p = kFirstPower + 2 * kTerm;
    constexpr Scalar inv = Scalar(1) / (Scalar(p + 1) * Scalar(p + 2));
    return Scalar(1) - r2 * inv * TaylorTail<Scalar, kTerm + 1, kLast, kFirstPower>::eval(r2);
  }
};

template <typename Scalar, int kLast, int kFirstPower>
struct TaylorTail<Scalar, kLast, kLast, kFirstPower> {
  static Scalar eval(Scalar) noexcept { return Scalar(1); }
};

}  // namespace detail

/// sin(x) and cos(x) for x [rad]. For |x| up to 1e5 (double) or 1e3 (float): Cody-Waite reduction
/// to [-pi/4, pi/4] and Taylor polynomials, within 2 ulp of the correctly rounded result (checked
/// against libm in tests/test_sin_cos.cpp); beyond that, and for NaN/inf, std::sin and std::cos.
/// One call costs a fraction of two libm calls, which dominate a regressor evaluation otherwise, and
/// keeps newlib's slow sinf/cosf out of the firmware's update loop.
template <typename Scalar>
inline SinCos<Scalar> sin_cos(Scalar x) noexcept {
  using T = detail::SinCosTraits<Scalar>;
  if (!(std::fabs(x) <= T::kMaxReduced)) return {std::sin(x), std::cos(x)};
  // k = round(x / (pi/2)) by adding and removing 1.5 * 2^mantissa (no libm call without SSE4.1/VFP
  // rounding instructions); volatile-free because the build never enables -ffast-math.
  const Scalar k = (x * Scalar(0.63661977236758134308) + T::kRoundingShift) - T::kRoundingShift;
  const Scalar r = ((x - k * T::kPio2Hi) - k * T::kPio2Mid) - k * T::kPio2Lo;
  const Scalar r2 = r * r;
  const Scalar s = r * detail::TaylorTail<Scalar, 0, T::kSinTerms, 1>::eval(r2);
  const Scalar c = detail::TaylorTail<Scalar, 0, T::kCosTerms, 0>::eval(r2);
  // Quadrant without branches (random joint angles would mispredict a switch): n = 0..3 maps
  // (sin, cos) to (s, c), (c, -s), (-s, -c), (-c, s).
  const int n = static_cast<int>(static_cast<long>(k) & 3);
  const bool swap = (n & 1) != 0;
  const Scalar a = swap ? c : s;
  const Scalar b = swap ? s : c;
  return {Scalar(1 - (n & 2)) * a, Scalar(1 - ((n + 1) & 2)) * b};
}

}  // namespace dyncal
