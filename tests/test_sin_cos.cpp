// dyncal::sin_cos against libm (long double as the reference) over joint-angle ranges and beyond.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "dyncal/sin_cos.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace sin_cos_suite {

// Largest error in units of the scalar's epsilon, measured against long double sin/cos; the error
// is taken relative to max(|reference|, 2^-10) so that values near a zero are held to an absolute bound.
template <typename Scalar>
double max_error_eps(Scalar lo, Scalar hi, int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  double worst = 0.0;
  for (int i = 0; i < n; ++i) {
    const Scalar x = static_cast<Scalar>(u(rng));
    const auto sc = dyncal::sin_cos(x);
    const long double xs = x;
    const long double ref[2] = {std::sin(xs), std::cos(xs)};
    const Scalar got[2] = {sc.sin, sc.cos};
    for (int k = 0; k < 2; ++k) {
      const long double scale = std::max(std::fabs(ref[k]), 1.0L / 1024);
      const long double err = std::fabs(got[k] - ref[k]) / scale / std::numeric_limits<Scalar>::epsilon();
      worst = std::max(worst, static_cast<double>(err));
    }
  }
  return worst;
}

TEST(SinCos, DoubleWithinTwoUlpOverJointRanges) {
  EXPECT_LE(max_error_eps<double>(-7.0, 7.0, 200000, 1), 2.0);
  EXPECT_LE(max_error_eps<double>(-1e5, 1e5, 200000, 2), 2.0);
}

TEST(SinCos, FloatWithinTwoUlpOverJointRanges) {
  EXPECT_LE(max_error_eps<float>(-7.0f, 7.0f, 200000, 3), 2.0);
  EXPECT_LE(max_error_eps<float>(-1e3f, 1e3f, 200000, 4), 2.0);
}

TEST(SinCos, QuadrantBoundariesAndSigns) {
  for (int k = -8; k <= 8; ++k) {
    const double x = k * 1.57079632679489661923;
    const auto sc = dyncal::sin_cos(x);
    EXPECT_NEAR(sc.sin, std::sin(x), 1e-15) << "k=" << k;
    EXPECT_NEAR(sc.cos, std::cos(x), 1e-15) << "k=" << k;
  }
  EXPECT_EQ(dyncal::sin_cos(0.0).sin, 0.0);
  EXPECT_EQ(dyncal::sin_cos(0.0).cos, 1.0);
}

TEST(SinCos, OutOfRangeAndNonFiniteFallBackToLibm) {
  const double big = 3.0e7;
  EXPECT_EQ(dyncal::sin_cos(big).sin, std::sin(big));
  EXPECT_EQ(dyncal::sin_cos(big).cos, std::cos(big));
  const auto nan = dyncal::sin_cos(std::numeric_limits<double>::quiet_NaN());
  EXPECT_TRUE(std::isnan(nan.sin) && std::isnan(nan.cos));
  const auto inf = dyncal::sin_cos(std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(inf.sin) && std::isnan(inf.cos));
}

}  // namespace sin_cos_suite
}  // namespace
