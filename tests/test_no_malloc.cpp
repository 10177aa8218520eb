// The lib/ updaters and generated regressors allocate nothing: Eigen's runtime no-malloc check is
// on (this target compiles with assertions), and malloc/calloc/realloc and operator new are
// counted while the updaters run.
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <random>

#include "dyncal/causal_differentiator.hpp"
#include "dyncal/centred_slope.hpp"
#include "dyncal/contact_threshold.hpp"
#include "dyncal/direct_residual.hpp"
#include "dyncal/extended_kalman_filter.hpp"
#include "dyncal/friction_tracker.hpp"
#include "dyncal/friction_uncertainty.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/payload_estimator.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal/table_check.hpp"
#include "support/synthetic.hpp"

namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};
}  // namespace

extern "C" {
void* __real_malloc(size_t);
void* __real_calloc(size_t, size_t);
void* __real_realloc(void*, size_t);
void* __wrap_malloc(size_t n) {
  if (g_counting) ++g_allocations;
  return __real_malloc(n);
}
void* __wrap_calloc(size_t a, size_t b) {
  if (g_counting) ++g_allocations;
  return __real_calloc(a, b);
}
void* __wrap_realloc(void* p, size_t n) {
  if (g_counting) ++g_allocations;
  return __real_realloc(p, n);
}
}

void* operator new(size_t n) {
  if (g_counting) ++g_allocations;
  if (void* p = __real_malloc(n)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, size_t) noexcept {
  std::free(p);
}

namespace {

using dyncal::test::Er20;
constexpr unsigned kTerms = dyncal::kFrictionEq8 | dyncal::term::rotor_inertia | dyncal::term::offset;
using Model = dyncal::IdentificationModel<Er20, kTerms>;
constexpr int P = Model::kNumParams;
using JointVec = Eigen::Matrix<double, 6, 1>;
using ParamVec = Eigen::Matrix<double, P, 1>;

template <typename Scalar>
struct Workspace {
  dyncal::StreamingLeastSquares<Scalar, P> ls;
  dyncal::KalmanFilter<Scalar, P, 6> kf;
  dyncal::RlsForgetting<Scalar, P, 6> rls;
  dyncal::KalmanFilter<Scalar, P, 6, dyncal::UdCovariance<Scalar, P>> kf_ud;
  dyncal::ExtendedKalmanFilter<Scalar, Er20, dyncal::NonlinearFrictionModel::eq4> ekf;
  dyncal::FrictionTracker<Scalar, 6, dyncal::NonlinearFrictionAmplitudes<dyncal::NonlinearFrictionModel::eq4>> tracker;
  Eigen::Matrix<Scalar, 6, P> K;
  Eigen::Matrix<Scalar, 6, Er20::kNumStandard> Y;
  Eigen::Matrix<Scalar, Er20::kNumStandard, 1> phi_std;
  Eigen::Matrix<Scalar, 6, 6> M;
  Eigen::Matrix<Scalar, P, 1> phi, diag;
  dyncal::CausalDifferentiator<Scalar, 6> diff;
  dyncal::PayloadEstimator<Er20, Scalar> payload;
  dyncal::MomentumObserver<Er20, Scalar> observer;
  dyncal::DirectResidual<Er20, Scalar> direct;
  dyncal::CentredSlope<Scalar, 6> slope;
  dyncal::FrictionUncertainty<Scalar, 6> uncertainty;
  dyncal::ParameterTable table;
  std::uint8_t table_bytes[dyncal::kTableMaxBytes];
};

template <typename Scalar>
void run_updaters(Workspace<Scalar>& w) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  using PV = Eigen::Matrix<Scalar, P, 1>;
  const PV truth = dyncal::test::er20_truth<kTerms>().template cast<Scalar>();
  for (int i = 0; i < Er20::kNumStandard; ++i) w.phi_std[i] = Scalar(dyncal::generated::er20::kNominalStandard[i]);
  ASSERT_EQ(w.kf.reset(PV::Zero(), PV::Constant(Scalar(1e4))), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.kf.set_gate(Scalar(100)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.kf_ud.reset(PV::Zero(), PV::Constant(Scalar(1e4))), dyncal::UpdateStatus::ok);
  using Ekf = dyncal::ExtendedKalmanFilter<Scalar, Er20, dyncal::NonlinearFrictionModel::eq4>;
  ASSERT_EQ(w.ekf.reset(Ekf::ParamVector::Constant(Scalar(1)), Ekf::ParamVector::Constant(Scalar(1e2)), Scalar(0.999)),
            dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.rls.reset(PV::Zero(), PV::Constant(Scalar(1e4)), Scalar(0.999)), dyncal::UpdateStatus::ok);
  using Tracker = decltype(w.tracker);
  ASSERT_EQ(w.tracker.reset(Tracker::ParamVector::Constant(Scalar(0.2)), Scalar(1e4), Scalar(0.99)),
            dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.diff.reset(Scalar(0.01), Scalar(20)), dyncal::UpdateStatus::ok);
  using Payload = dyncal::PayloadEstimator<Er20, Scalar>;
  ASSERT_EQ(w.payload.reset(Payload::ParamVector::Constant(Scalar(1e2))), dyncal::UpdateStatus::ok);
  JointVec qd_, q_, qdd_;
  for (int i = 0; i < 300; ++i) {
    dyncal::test::fourier_state(0.01 * i, q_, qd_, qdd_);
    const V q = q_.cast<Scalar>(), qd = qd_.cast<Scalar>(), qdd = qdd_.cast<Scalar>();
    const V zero = V::Zero();
    Model::regressor(q, qd, qdd, zero, w.K);
    Er20::standard_regressor(q, qd, qdd, w.Y);
    Er20::mass_matrix(q, w.phi_std, w.M);
    V tau;
    Er20::inverse_dynamics(q, qd, qdd, w.phi_std, tau);
    tau.noalias() = w.K * truth;
    ASSERT_EQ(w.ls.update(w.K, tau), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf.update(w.K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.rls.update(w.K, tau), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf_ud.update(w.K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.ekf.update(q, qd, qdd, tau, V::Constant(Scalar(100))), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.tracker.update(qd, zero, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.payload.update(q, qd, qdd, Scalar(0.01) * tau, V::Ones()), dyncal::UpdateStatus::ok);
    V fq, fqd, fqdd, ftau;
    const auto ds = w.diff.update(q, tau, fq, fqd, fqdd, ftau);
    ASSERT_TRUE(ds == dyncal::UpdateStatus::ok || ds == dyncal::UpdateStatus::not_ready);
  }
  // Parameter table: build, encode, decode, check (what a drive does on a flash).
  dyncal::make_table<Model>(truth, w.table);
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(w.table, w.table_bytes, dyncal::kTableMaxBytes, &size), dyncal::TableStatus::ok);
  ASSERT_EQ(dyncal::decode_table(w.table_bytes, size, w.table), dyncal::TableStatus::ok);
  ASSERT_EQ(dyncal::check_table<Model>(w.table), dyncal::TableStatus::ok);
  // The momentum observer on that table and a contact threshold (what a drive does per sample and
  // once per commit).
  ASSERT_EQ(w.observer.configure(w.table, V::Constant(Scalar(100)), Scalar(0.01)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.direct.configure(w.table, V::Constant(Scalar(100)), Scalar(0.01)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.slope.reset(1, Scalar(0.01), 6), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.uncertainty.reset(Scalar(100), Scalar(0.01), 6), dyncal::UpdateStatus::ok);
  for (int i = 0; i < 50; ++i) {
    dyncal::test::fourier_state(0.01 * i, q_, qd_, qdd_);
    V sq, sqd, sqdd, stau;
    Eigen::Matrix<int, 6, 1> still = Eigen::Matrix<int, 6, 1>::Zero();
    const auto ss = w.slope.update(q_.cast<Scalar>(), V::Constant(Scalar(i)), sq, sqd, sqdd, stau, still);
    ASSERT_TRUE(ss == dyncal::UpdateStatus::ok || ss == dyncal::UpdateStatus::not_ready);
    V weight;
    ASSERT_EQ(w.uncertainty.update(qd_.cast<Scalar>(), still, weight), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.observer.update(q_.cast<Scalar>(), qd_.cast<Scalar>(), V::Constant(Scalar(i))),
              dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.direct.update(q_.cast<Scalar>(), qd_.cast<Scalar>(), qd_.cast<Scalar>(), qdd_.cast<Scalar>(),
                              V::Constant(Scalar(i))),
              dyncal::UpdateStatus::ok);
  }
  ASSERT_TRUE(std::isfinite(dyncal::contact_threshold(Scalar(1), Scalar(0.5), Scalar(0.001), 6, Scalar(1e-5))));
  ASSERT_EQ(w.ls.solve(w.phi), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.ls.inverse_gram_diagonal(w.diag), dyncal::UpdateStatus::ok);
  w.kf.covariance().diagonal(w.diag);
}

TEST(NoMalloc, UpdatersAndGeneratedCodeAllocateNothing) {
  auto wd = std::make_unique<Workspace<double>>();
  auto wf = std::make_unique<Workspace<float>>();
  Eigen::internal::set_is_malloc_allowed(false);
  g_allocations = 0;
  g_counting = true;
  run_updaters(*wd);
  run_updaters(*wf);
  g_counting = false;
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(g_allocations.load(), 0);
}

// lib/'s estimators are generic in the number of measured joints N: the robots dyncal takes have 1
// to 7. For N = 1 (double), 3 and 7 (float and double; the portable path, the ARM float kernels
// specialise N = 6 only) the updaters allocate nothing and, on noise-free data of a seeded random
// regressor (P = 12), recover the parameters: streaming LS to 1e-3 in float and 1e-8 in double
// (relative), the recursive ones to that or their prior's bias. Float with N = 1 is not built:
// g++ 12 -O3 rejects PackedCovariance<float, 12, 1>::compute_v ("iteration 2147483635 invokes
// undefined behavior", -Werror=aggressive-loop-optimizations; see the closing note of issue 20).
template <typename Scalar, int N>
struct GenericWorkspace {
  static constexpr int kP = 12;
  using PV = Eigen::Matrix<Scalar, kP, 1>;
  using V = Eigen::Matrix<Scalar, N, 1>;
  dyncal::StreamingLeastSquares<Scalar, kP> ls;
  dyncal::KalmanFilter<Scalar, kP, N> kf;
  dyncal::KalmanFilter<Scalar, kP, N, dyncal::UdCovariance<Scalar, kP>> kf_ud;
  dyncal::RlsForgetting<Scalar, kP, N> rls;
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
  g_counting = true;
  ASSERT_EQ(w.kf.reset(PV::Zero(), PV::Constant(Scalar(1e4))), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.kf_ud.reset(PV::Zero(), PV::Constant(Scalar(1e4))), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.rls.reset(PV::Zero(), PV::Constant(Scalar(1e4)), Scalar(0.999)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.diff.reset(Scalar(0.01), Scalar(20)), dyncal::UpdateStatus::ok);
  for (int i = 0; i < 300; ++i) {
    const auto& K = w.K[i % 64];
    const V tau = K * w.truth;
    ASSERT_EQ(w.ls.update(K, tau), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf.update(K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf_ud.update(K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.rls.update(K, tau), dyncal::UpdateStatus::ok);
    V fq, fqd, fqdd, ftau;
    const auto ds = w.diff.update(tau, tau, fq, fqd, fqdd, ftau);
    ASSERT_TRUE(ds == dyncal::UpdateStatus::ok || ds == dyncal::UpdateStatus::not_ready);
  }
  ASSERT_EQ(w.ls.solve(w.phi), dyncal::UpdateStatus::ok);
  g_counting = false;
  const double scale = static_cast<double>(w.truth.norm());
  EXPECT_LT(static_cast<double>((w.phi - w.truth).norm()) / scale, tolerance) << "LS, N = " << N;
  // The recursive estimators start from a prior (0, covariance 1e4): on noise-free data it leaves a
  // bias of about 1 / (1e4 lambda_min(K^T K)), ~1e-6 relative here.
  const double recursive = std::max(tolerance, 1e-5);
  EXPECT_LT(static_cast<double>((w.kf.estimate() - w.truth).norm()) / scale, recursive) << "KF, N = " << N;
  EXPECT_LT(static_cast<double>((w.kf_ud.estimate() - w.truth).norm()) / scale, recursive) << "UD-KF, N = " << N;
  EXPECT_LT(static_cast<double>((w.rls.estimate() - w.truth).norm()) / scale, recursive) << "RLS, N = " << N;
}

TEST(NoMalloc, UpdatersForOneThreeAndSevenJointsAllocateNothingAndRecoverTheTruth) {
  auto w1 = std::make_unique<GenericWorkspace<double, 1>>();
  auto w3f = std::make_unique<GenericWorkspace<float, 3>>();
  auto w3d = std::make_unique<GenericWorkspace<double, 3>>();
  auto w7f = std::make_unique<GenericWorkspace<float, 7>>();
  auto w7d = std::make_unique<GenericWorkspace<double, 7>>();
  Eigen::internal::set_is_malloc_allowed(false);
  g_allocations = 0;
  run_generic(*w1, 1e-8);
  run_generic(*w3f, 1e-3);
  run_generic(*w3d, 1e-8);
  run_generic(*w7f, 1e-3);
  run_generic(*w7d, 1e-8);
  Eigen::internal::set_is_malloc_allowed(true);
  EXPECT_EQ(g_allocations.load(), 0);
}

TEST(NoMalloc, TheCheckItselfWorks) {
  // A dynamic-size Eigen object must trip the counter: the test above can fail.
  g_allocations = 0;
  g_counting = true;
  Eigen::VectorXd v(1000);
  v.setZero();
  g_counting = false;
  EXPECT_GT(g_allocations.load(), 0);
}

}  // namespace
