// lib/'s recursive payload estimator (dyncal/payload_estimator.hpp) on the generated TX40 model: its
// regressor Y_b K_N is the standard regressor's last link columns (an independent generated
// function), its diffuse-prior estimate is batch least squares' on those columns, the truth is
// recovered within its standard deviations on noisy samples, in double and in float (its UD
// covariance: the packed form lost positive definiteness in float on these samples), and bad input
// leaves it as it was.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <random>

#include "dyncal/generated/tx40/robot.hpp"
#include "dyncal/payload_estimator.hpp"
#include "support/random_physical.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace payload_estimator_suite {

using Tx40 = dyncal::generated::tx40::Robot;
using V6 = Eigen::Matrix<double, 6, 1>;
using V10 = Eigen::Matrix<double, 10, 1>;

struct Samples {
  std::vector<V6> q, qd, qdd, residual;
  V10 truth;
  double sigma = 0.05;  // torque noise [Nm]
};

/// Random states (q within +-2 rad, qd +-2 rad/s, qdd +-5 rad/s^2) and the torque of a 2.5 kg load
/// (inverse dynamics of its standard parameters alone) plus Gaussian noise.
Samples make_samples(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  dyncal::test::Body load = dyncal::test::random_body(rng);
  load.m = 2.5;
  load.c *= 0.25;
  load.Ic *= 0.05;
  Samples s;
  s.truth = dyncal::test::standard_parameters(load);
  Eigen::Matrix<double, Tx40::kNumStandard, 1> phi = Eigen::Matrix<double, Tx40::kNumStandard, 1>::Zero();
  phi.tail(10) = s.truth;
  for (int k = 0; k < n; ++k) {
    V6 q, qd, qdd, tau;
    for (int j = 0; j < 6; ++j) q[j] = 2 * u(rng), qd[j] = 2 * u(rng), qdd[j] = 5 * u(rng);
    Tx40::inverse_dynamics(q, qd, qdd, phi, tau);
    for (int j = 0; j < 6; ++j) tau[j] += s.sigma * noise(rng);
    s.q.push_back(q), s.qd.push_back(qd), s.qdd.push_back(qdd), s.residual.push_back(tau);
  }
  return s;
}

TEST(PayloadEstimator, RegressorIsTheStandardRegressorsLastLink) {
  dyncal::PayloadEstimator<Tx40> est;
  const Samples s = make_samples(50, 1);
  for (size_t k = 0; k < s.q.size(); ++k) {
    Eigen::Matrix<double, 6, 10> Y;
    est.regressor(s.q[k], s.qd[k], s.qdd[k], Y);
    Eigen::Matrix<double, 6, Tx40::kNumStandard> Ys;
    Tx40::standard_regressor(s.q[k], s.qd[k], s.qdd[k], Ys);
    EXPECT_LE((Y - Ys.rightCols(10)).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, Ys.cwiseAbs().maxCoeff()));
  }
}

TEST(PayloadEstimator, DiffusePriorGivesBatchLeastSquaresAndTheTruth) {
  const Samples s = make_samples(2000, 2);
  dyncal::PayloadEstimator<Tx40> est;
  ASSERT_EQ(est.reset(V10::Constant(1e6)), dyncal::UpdateStatus::ok);
  Eigen::MatrixXd A(6 * s.q.size(), 10);
  Eigen::VectorXd b(6 * s.q.size());
  for (size_t k = 0; k < s.q.size(); ++k) {
    ASSERT_EQ(est.update(s.q[k], s.qd[k], s.qdd[k], s.residual[k], V6::Constant(s.sigma * s.sigma)),
              dyncal::UpdateStatus::ok);
    Eigen::Matrix<double, 6, Tx40::kNumStandard> Ys;
    Tx40::standard_regressor(s.q[k], s.qd[k], s.qdd[k], Ys);
    A.middleRows(6 * static_cast<Eigen::Index>(k), 6) = Ys.rightCols(10);
    b.segment(6 * static_cast<Eigen::Index>(k), 6) = s.residual[k];
  }
  const V10 batch = A.colPivHouseholderQr().solve(b);
  const V10 cov_diag = (A.transpose() * A).inverse().diagonal() * s.sigma * s.sigma;
  V10 var;
  est.variance(var);
  for (int i = 0; i < 10; ++i) {
    SCOPED_TRACE(Tx40::standard_param_name(Tx40::kNumStandard - 10 + i));
    const double sd = std::sqrt(cov_diag[i]);
    std::printf("%-6s truth %+.6f batch %+.6f kf %+.6f std %.2g\n",
                Tx40::standard_param_name(Tx40::kNumStandard - 10 + i), s.truth[i], batch[i], est.estimate()[i], sd);
    EXPECT_NEAR(est.estimate()[i], batch[i], 1e-3 * sd);  // the prior's 1e6 variance: a bias of ~1e-6 sd^2
    EXPECT_NEAR(std::sqrt(var[i]), sd, 1e-3 * sd);
    EXPECT_NEAR(est.estimate()[i], s.truth[i], 4 * sd);
  }
}

TEST(PayloadEstimator, FloatFollowsDouble) {
  const Samples s = make_samples(2000, 3);
  dyncal::PayloadEstimator<Tx40, float> f;
  dyncal::PayloadEstimator<Tx40> d;
  ASSERT_EQ(f.reset(Eigen::Matrix<float, 10, 1>::Constant(1e4f)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(d.reset(V10::Constant(1e4)), dyncal::UpdateStatus::ok);
  for (size_t k = 0; k < s.q.size(); ++k) {
    const V6 r = V6::Constant(s.sigma * s.sigma);
    ASSERT_EQ(f.update(s.q[k].cast<float>(), s.qd[k].cast<float>(), s.qdd[k].cast<float>(), s.residual[k].cast<float>(),
                       r.cast<float>()),
              dyncal::UpdateStatus::ok);
    ASSERT_EQ(d.update(s.q[k], s.qd[k], s.qdd[k], s.residual[k], r), dyncal::UpdateStatus::ok);
  }
  V10 var;
  d.variance(var);
  for (int i = 0; i < 10; ++i)
    EXPECT_NEAR(static_cast<double>(f.estimate()[i]), d.estimate()[i], 0.1 * std::sqrt(var[i])) << i;
  std::printf("mass: float %.6f double %.6f truth %.6f\n", f.estimate()[9], d.estimate()[9], s.truth[9]);
}

TEST(PayloadEstimator, BadInputLeavesTheEstimateUnchanged) {
  const Samples s = make_samples(20, 4);
  dyncal::PayloadEstimator<Tx40> est;
  EXPECT_EQ(est.reset(V10::Constant(-1.0)), dyncal::UpdateStatus::not_positive_definite);
  ASSERT_EQ(est.reset(V10::Constant(1e4)), dyncal::UpdateStatus::ok);
  for (size_t k = 0; k < s.q.size(); ++k)
    ASSERT_EQ(est.update(s.q[k], s.qd[k], s.qdd[k], s.residual[k], V6::Ones()), dyncal::UpdateStatus::ok);
  const V10 before = est.estimate();
  V6 nan_residual = s.residual[0];
  nan_residual[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(est.update(s.q[0], s.qd[0], s.qdd[0], nan_residual, V6::Ones()), dyncal::UpdateStatus::rejected_non_finite);
  EXPECT_EQ(est.update(s.q[0], s.qd[0], s.qdd[0], s.residual[0], V6::Zero()),
            dyncal::UpdateStatus::not_positive_definite);
  EXPECT_EQ(est.estimate(), before);
}

}  // namespace payload_estimator_suite
}  // namespace
