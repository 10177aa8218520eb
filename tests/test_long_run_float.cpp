// Robustness of the firmware arithmetic: 10^6 float32 Kalman updates on noisy er20 data (the lib/
// code the Cortex-M4F image runs: packed symmetric P, block update over the regressor's structure)
// keep P symmetric (by storage) and positive definite — every update returns ok, and at the end the
// float P has a Cholesky factorisation (checked in double) — and end within the documented
// tolerance of the same run in double.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <memory>
#include <random>

#include "dyncal/kalman_filter.hpp"
#include "support/synthetic.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace long_run_float_suite {

using Er20 = dyncal::generated::er20::Robot;
constexpr unsigned kTerms = dyncal::kFrictionEq7;
using Model = dyncal::IdentificationModel<Er20, kTerms>;
constexpr int P = Model::kNumParams;

TEST(LongRunFloat, MillionUpdatesStayPositiveDefiniteAndNearDouble) {
  const Eigen::Matrix<double, P, 1> truth = dyncal::test::er20_truth<kTerms>();
  auto kf_f = std::make_unique<dyncal::KalmanFilter<float, P, 6>>();
  auto kf_d = std::make_unique<dyncal::KalmanFilter<double, P, 6>>();
  ASSERT_EQ(
      kf_f->reset(Eigen::Matrix<float, P, 1>::Zero(), Eigen::Matrix<float, P, 1>::Constant(1e4f), Model::structure()),
      dyncal::UpdateStatus::ok);
  ASSERT_EQ(
      kf_d->reset(Eigen::Matrix<double, P, 1>::Zero(), Eigen::Matrix<double, P, 1>::Constant(1e4), Model::structure()),
      dyncal::UpdateStatus::ok);
  // Survey Table 7 torque noise; R = its variance.
  const Eigen::Matrix<double, 6, 1> sigma = (Eigen::Matrix<double, 6, 1>() << 10, 10, 10, 1.78, 1.78, 1.78).finished();
  const Eigen::Matrix<double, 6, 1> r = sigma.cwiseAbs2();
  std::mt19937 rng(17);
  std::normal_distribution<double> noise(0.0, 1.0);
  Model::Regressor<double> K;
  const Eigen::Matrix<double, 6, 1> zero = Eigen::Matrix<double, 6, 1>::Zero();
  const long updates = 1000000;
  for (long k = 0; k < updates; ++k) {
    Eigen::Matrix<double, 6, 1> q, qd, qdd;
    dyncal::test::fourier_state(0.01 * static_cast<double>(k % 100000), q, qd, qdd);  // 1000 s, repeated
    Model::regressor(q, qd, qdd, zero, K);
    Eigen::Matrix<double, 6, 1> tau = K * truth;
    for (int j = 0; j < 6; ++j) tau[j] += sigma[j] * noise(rng);
    ASSERT_EQ(kf_d->update(K, tau, r), dyncal::UpdateStatus::ok) << k;
    ASSERT_EQ(kf_f->update(K.cast<float>(), tau.cast<float>(), r.cast<float>()), dyncal::UpdateStatus::ok) << k;
  }
  Eigen::Matrix<float, P, P> p_f;
  kf_f->covariance().to_dense(p_f);
  ASSERT_TRUE(p_f.allFinite());
  const Eigen::Matrix<double, P, P> p_fd = p_f.cast<double>();
  Eigen::LLT<Eigen::Matrix<double, P, P>> llt(p_fd);
  EXPECT_EQ(llt.info(), Eigen::Success) << "P lost positive definiteness";
  const double min_eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, P, P>>(p_fd).eigenvalues().minCoeff();
  // Tolerance: the float and double estimates predict the torque of a fresh period alike, to 1e-3 of
  // its RMS (parameters themselves differ along poorly excited directions, which predict nothing).
  double se = 0, st = 0;
  const Eigen::Matrix<double, P, 1> phi_f = kf_f->estimate().cast<double>();
  for (int k = 0; k < 1000; ++k) {
    Eigen::Matrix<double, 6, 1> q, qd, qdd;
    dyncal::test::fourier_state(0.0137 * k + 0.005, q, qd, qdd);
    Model::regressor(q, qd, qdd, zero, K);
    se += (K * (phi_f - kf_d->estimate())).squaredNorm();
    st += (K * kf_d->estimate()).squaredNorm();
  }
  const double rel = std::sqrt(se / st);
  std::cout << "float vs double after " << updates << " updates: relative prediction difference " << rel
            << ", smallest eigenvalue of the float P " << min_eig << "\n";
  EXPECT_LT(rel, 1e-3);
}

}  // namespace long_run_float_suite
}  // namespace
