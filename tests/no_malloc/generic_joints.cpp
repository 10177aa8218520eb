// test_no_malloc: lib/'s estimators for 1, 3 and 7 joints allocate nothing.
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <type_traits>

#include "dyncal/causal_differentiator.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "no_malloc/allocation_counter.hpp"

namespace {

using dyncal::test::allocations;
using dyncal::test::counting;

// lib/'s estimators are generic in the number of measured joints N: the robots dyncal takes have 1
// to 7. For N = 1 (double), 3 and 7 (float and double; the portable path, the ARM float kernels
// specialise N = 6 only) the updaters allocate nothing and, on noise-free data of a seeded random
// regressor (P = 12), recover the parameters: streaming LS to 1e-3 in float and 1e-8 in double
// (relative), the recursive ones to that or their prior's bias. Float with N = 1 is not built:
// g++ 12 -O3 rejects PackedCovariance<float, 12, 1>::compute_v ("iteration 2147483635 invokes
// undefined behavior", -Werror=aggressive-loop-optimizations; see the closing note of issue 20).
// The streaming LS, KF and RLS at a run-time size (P = Eigen::Dynamic, capacity 16), as the host
// runs them for any robot, allocate nothing either and equal the fixed-size ones bit for bit: double
// with N = 1, whose regressor is a row-major row (test_estimators.cpp compares N = 6 with the
// model's structure).
template <typename Scalar, int N>
struct RunTimeSize {
  static constexpr bool kBuilt = std::is_same_v<Scalar, double> && N == 1;
  static constexpr int kCapacity = 16;
  using Covariance = dyncal::PackedCovariance<Scalar, Eigen::Dynamic, N, kCapacity>;
  using Kf = dyncal::KalmanFilter<Scalar, Eigen::Dynamic, N, Covariance>;
  using Rls = dyncal::RlsForgetting<Scalar, Eigen::Dynamic, N, Covariance>;
  using Ls = dyncal::StreamingLeastSquares<Scalar, Eigen::Dynamic, kCapacity>;
  Kf kf;
  Rls rls;
  Ls ls;
  typename Ls::Vector phi;
  typename Kf::ParamVector zero, p0;
  typename Kf::Regressor k;
};
struct NotBuilt {};

template <typename Scalar, int N>
struct GenericWorkspace {
  static constexpr int kP = 12;
  using PV = Eigen::Matrix<Scalar, kP, 1>;
  using V = Eigen::Matrix<Scalar, N, 1>;
  dyncal::StreamingLeastSquares<Scalar, kP> ls;
  dyncal::KalmanFilter<Scalar, kP, N> kf;
  dyncal::KalmanFilter<Scalar, kP, N, dyncal::UdCovariance<Scalar, kP>> kf_ud;
  dyncal::RlsForgetting<Scalar, kP, N> rls;
  std::conditional_t<RunTimeSize<Scalar, N>::kBuilt, RunTimeSize<Scalar, N>, NotBuilt> run_time;
  dyncal::CausalDifferentiator<Scalar, N> diff;
  Eigen::Matrix<Scalar, N, kP> K[64];
  PV truth, phi;
};

template <typename Scalar, int N>
void run_generic(GenericWorkspace<Scalar, N>& w, double tolerance) {
  using W = GenericWorkspace<Scalar, N>;
  using PV = typename W::PV;
  using V = typename W::V;
  std::mt19937 rng(N);  // the regressor rows and the truth, made before counting starts
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& K : w.K)
    for (int r = 0; r < N; ++r)
      for (int c = 0; c < W::kP; ++c) K(r, c) = Scalar(u(rng));
  for (int c = 0; c < W::kP; ++c) w.truth[c] = Scalar(1.0 + u(rng));
  counting = true;
  ASSERT_EQ(w.kf.reset(PV::Zero(), PV::Constant(Scalar(1e4))), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.kf_ud.reset(PV::Zero(), PV::Constant(Scalar(1e4))), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.rls.reset(PV::Zero(), PV::Constant(Scalar(1e4)), Scalar(0.999)), dyncal::UpdateStatus::ok);
  if constexpr (RunTimeSize<Scalar, N>::kBuilt) {
    w.run_time.zero = PV::Zero();
    w.run_time.p0 = PV::Constant(Scalar(1e4));
    ASSERT_EQ(w.run_time.kf.reset(w.run_time.zero, w.run_time.p0), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.run_time.rls.reset(w.run_time.zero, w.run_time.p0, Scalar(0.999)), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.run_time.ls.reset(W::kP), dyncal::UpdateStatus::ok);
  }
  ASSERT_EQ(w.diff.reset(Scalar(0.01), Scalar(20)), dyncal::UpdateStatus::ok);
  for (int i = 0; i < 300; ++i) {
    const auto& K = w.K[i % 64];
    const V tau = K * w.truth;
    ASSERT_EQ(w.ls.update(K, tau), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf.update(K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf_ud.update(K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.rls.update(K, tau), dyncal::UpdateStatus::ok);
    if constexpr (RunTimeSize<Scalar, N>::kBuilt) {
      w.run_time.k = K;
      ASSERT_EQ(w.run_time.kf.update(w.run_time.k, tau, V::Ones()), dyncal::UpdateStatus::ok);
      ASSERT_EQ(w.run_time.rls.update(w.run_time.k, tau), dyncal::UpdateStatus::ok);
      ASSERT_EQ(w.run_time.ls.update(w.run_time.k, tau), dyncal::UpdateStatus::ok);
    }
    V fq, fqd, fqdd, ftau;
    const auto ds = w.diff.update(tau, tau, fq, fqd, fqdd, ftau);
    ASSERT_TRUE(ds == dyncal::UpdateStatus::ok || ds == dyncal::UpdateStatus::not_ready);
  }
  ASSERT_EQ(w.ls.solve(w.phi), dyncal::UpdateStatus::ok);
  if constexpr (RunTimeSize<Scalar, N>::kBuilt) {
    ASSERT_EQ(w.run_time.ls.solve(w.run_time.phi), dyncal::UpdateStatus::ok);
  }
  counting = false;
  const double scale = static_cast<double>(w.truth.norm());
  EXPECT_LT(static_cast<double>((w.phi - w.truth).norm()) / scale, tolerance) << "LS, N = " << N;
  // The recursive estimators start from a prior (0, covariance 1e4): on noise-free data it leaves a
  // bias of about 1 / (1e4 lambda_min(K^T K)), ~1e-6 relative here.
  const double recursive = std::max(tolerance, 1e-5);
  EXPECT_LT(static_cast<double>((w.kf.estimate() - w.truth).norm()) / scale, recursive) << "KF, N = " << N;
  EXPECT_LT(static_cast<double>((w.kf_ud.estimate() - w.truth).norm()) / scale, recursive) << "UD-KF, N = " << N;
  EXPECT_LT(static_cast<double>((w.rls.estimate() - w.truth).norm()) / scale, recursive) << "RLS, N = " << N;
  if constexpr (RunTimeSize<Scalar, N>::kBuilt) {
    ASSERT_EQ(w.run_time.kf.estimate().size(), W::kP);
    for (int c = 0; c < W::kP; ++c) {
      EXPECT_EQ(w.run_time.kf.estimate()[c], w.kf.estimate()[c]) << "run-time KF, N = " << N;
      EXPECT_EQ(w.run_time.rls.estimate()[c], w.rls.estimate()[c]) << "run-time RLS, N = " << N;
      EXPECT_EQ(w.run_time.phi[c], w.phi[c]) << "run-time LS, N = " << N;
    }
  }
}

TEST(NoMalloc, UpdatersForOneThreeAndSevenJointsAllocateNothingAndRecoverTheTruth) {
  auto w1 = std::make_unique<GenericWorkspace<double, 1>>();
  auto w3f = std::make_unique<GenericWorkspace<float, 3>>();
  auto w3d = std::make_unique<GenericWorkspace<double, 3>>();
  auto w7f = std::make_unique<GenericWorkspace<float, 7>>();
  auto w7d = std::make_unique<GenericWorkspace<double, 7>>();
  Eigen::internal::set_is_malloc_allowed(false);
  allocations = 0;
  run_generic(*w1, 1e-8);
  run_generic(*w3f, 1e-3);
  run_generic(*w3d, 1e-8);
  run_generic(*w7f, 1e-3);
  run_generic(*w7d, 1e-8);
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(allocations.load(), 0);
}

}  // namespace
