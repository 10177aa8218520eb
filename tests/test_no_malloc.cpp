// The lib/ updaters and generated regressors allocate nothing: Eigen's runtime no-malloc check is
// on (this target compiles with assertions), and malloc/calloc/realloc and operator new are
// counted while the updaters run. The program's files, one updater family each (compiled in
// parallel): this one (the counter and the er20's estimators), no_malloc/er20_drive_code.cpp (the
// generated code and what a drive runs per sample and per flash), no_malloc/generic_joints.cpp (1, 3
// and 7 joints).
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <new>

#include "dyncal/causal_differentiator.hpp"
#include "dyncal/extended_kalman_filter.hpp"
#include "dyncal/friction_tracker.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "no_malloc/allocation_counter.hpp"
#include "no_malloc/er20_model.hpp"

namespace dyncal::test {
std::atomic<long> allocations{0};
std::atomic<bool> counting{false};
}  // namespace dyncal::test

using dyncal::test::allocations;
using dyncal::test::counting;

extern "C" {
void* __real_malloc(size_t);
void* __real_calloc(size_t, size_t);
void* __real_realloc(void*, size_t);
void* __wrap_malloc(size_t n) {
  if (counting) ++allocations;
  return __real_malloc(n);
}
void* __wrap_calloc(size_t a, size_t b) {
  if (counting) ++allocations;
  return __real_calloc(a, b);
}
void* __wrap_realloc(void* p, size_t n) {
  if (counting) ++allocations;
  return __real_realloc(p, n);
}
}

void* operator new(size_t n) {
  if (counting) ++allocations;
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

using namespace dyncal::test::no_malloc;  // the er20 model (er20_model.hpp)

template <typename Scalar>
struct Workspace {
  dyncal::StreamingLeastSquares<Scalar, P> ls;
  dyncal::KalmanFilter<Scalar, P, 6> kf;
  dyncal::RlsForgetting<Scalar, P, 6> rls;
  dyncal::KalmanFilter<Scalar, P, 6, dyncal::UdCovariance<Scalar, P>> kf_ud;
  dyncal::ExtendedKalmanFilter<Scalar, Er20, dyncal::NonlinearFrictionModel::eq4> ekf;
  dyncal::FrictionTracker<Scalar, 6, dyncal::NonlinearFrictionAmplitudes<dyncal::NonlinearFrictionModel::eq4>> tracker;
  dyncal::CausalDifferentiator<Scalar, 6> diff;
  Eigen::Matrix<Scalar, 6, P> K;
  Eigen::Matrix<Scalar, P, 1> phi, diag;
};

/// The estimators on the er20's identification model (KF, UD-KF, RLS, streaming LS, EKF, friction
/// tracker) and the causal differentiator, 300 samples of noise-free data.
template <typename Scalar>
void run_estimators(Workspace<Scalar>& w) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  using PV = Eigen::Matrix<Scalar, P, 1>;
  const PV truth = dyncal::test::er20_truth<kTerms>().template cast<Scalar>();
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
  JointVec qd_, q_, qdd_;
  for (int i = 0; i < 300; ++i) {
    dyncal::test::fourier_state(0.01 * i, q_, qd_, qdd_);
    const V q = q_.cast<Scalar>(), qd = qd_.cast<Scalar>(), qdd = qdd_.cast<Scalar>();
    const V zero = V::Zero();
    Model::regressor(q, qd, qdd, zero, w.K);
    const V tau = w.K * truth;
    ASSERT_EQ(w.ls.update(w.K, tau), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf.update(w.K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.rls.update(w.K, tau), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.kf_ud.update(w.K, tau, V::Ones()), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.ekf.update(q, qd, qdd, tau, V::Constant(Scalar(100))), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.tracker.update(qd, zero, tau, V::Ones()), dyncal::UpdateStatus::ok);
    V fq, fqd, fqdd, ftau;
    const auto ds = w.diff.update(q, tau, fq, fqd, fqdd, ftau);
    ASSERT_TRUE(ds == dyncal::UpdateStatus::ok || ds == dyncal::UpdateStatus::not_ready);
  }
  ASSERT_EQ(w.ls.solve(w.phi), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.ls.inverse_gram_diagonal(w.diag), dyncal::UpdateStatus::ok);
  w.kf.covariance().diagonal(w.diag);
}

TEST(NoMalloc, Er20EstimatorsAllocateNothing) {
  EXPECT_EQ(dyncal::test::allocations_in_double_and_float<Workspace>([](auto& w) { run_estimators(w); }), 0);
}

TEST(NoMalloc, TheCheckItselfWorks) {
  // A dynamic-size Eigen object must trip the counter: the tests can fail.
  allocations = 0;
  counting = true;
  Eigen::VectorXd v(1000);
  v.setZero();
  counting = false;
  EXPECT_GT(allocations.load(), 0);
}

}  // namespace
