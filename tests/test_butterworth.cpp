// The zero-phase Butterworth low-pass (identification/methods/butterworth.hpp) against the filter's
// analytic response, and its columns filtered together against each alone.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <random>

#include "dyncal_host/identification/methods/butterworth.hpp"

namespace {

using dyncal::host::ButterworthLowPass;

// filtfilt's gain at f: the square of the digital Butterworth magnitude (bilinear transform,
// pre-warped at the cut-off): 1 / (1 + (tan(pi f / fs) / tan(pi fc / fs))^(2 order)).
double zero_phase_gain(double f, double fc, double fs, int order) {
  return 1.0 / (1.0 + std::pow(std::tan(M_PI * f / fs) / std::tan(M_PI * fc / fs), 2 * order));
}

TEST(Butterworth, SinesComeOutWithTheAnalyticGainAndNoLag) {
  const double fs = 1000, fc = 20;
  const Eigen::Index n = 20000;
  for (int order : {2, 4, 6}) {
    const ButterworthLowPass filter(order, fc, fs);
    for (double f : {2.0, 10.0, 20.0, 30.0, 45.0}) {
      Eigen::MatrixXd x(n, 2);
      for (Eigen::Index i = 0; i < n; ++i)
        x(i, 0) = std::sin(2 * M_PI * f * i / fs), x(i, 1) = std::cos(2 * M_PI * f * i / fs);
      const Eigen::MatrixXd in = x;
      filter.filtfilt(x);
      // Away from the ends: y = g x exactly in phase, so the least-squares gain of y on x is g and
      // the quadrature part (y on the other column) is 0.
      const auto mid = [&](const Eigen::MatrixXd& m, int c) { return m.col(c).segment(n / 4, n / 2); };
      const double g = mid(x, 0).dot(mid(in, 0)) / mid(in, 0).squaredNorm();
      const double quadrature = mid(x, 0).dot(mid(in, 1)) / mid(in, 1).squaredNorm();
      const double expected = zero_phase_gain(f, fc, fs, order);
      EXPECT_NEAR(g, expected, 1e-3 * std::max(expected, 1e-2)) << "order " << order << ", " << f << " Hz";
      EXPECT_NEAR(quadrature, 0.0, 1e-4) << "order " << order << ", " << f << " Hz";
    }
  }
}

TEST(Butterworth, ColumnsTogetherEqualEachAloneBitForBit) {
  // Seven columns: one group of four, one of two and one alone; ends of every kind of signal.
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  Eigen::MatrixXd x(1500, 7);
  for (Eigen::Index i = 0; i < x.rows(); ++i)
    for (Eigen::Index c = 0; c < x.cols(); ++c) x(i, c) = (c % 2 ? 3.0 : -1.0) + noise(rng) + (i > 700 ? c : 0);
  for (int order : {2, 4, 40}) {  // 40: more sections than one pass holds
    const ButterworthLowPass filter(order, 35, 1000);
    Eigen::MatrixXd together = x;
    filter.filtfilt(together);
    for (Eigen::Index c = 0; c < x.cols(); ++c) {
      Eigen::VectorXd alone = x.col(c);
      filter.filtfilt(alone);
      for (Eigen::Index i = 0; i < x.rows(); ++i)
        ASSERT_EQ(together(i, c), alone[i]) << "order " << order << ", column " << c << ", sample " << i;
    }
  }
}

}  // namespace
