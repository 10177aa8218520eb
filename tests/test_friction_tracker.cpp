// lib/ FrictionTracker: the amplitude columns against the models' torques, exact recovery against
// batch least squares, following a changed parameter with forgetting, and its error statuses.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <memory>

#include "dyncal/friction_tracker.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace friction_tracker_suite {

using dyncal::FrictionTracker;
using dyncal::LinearFrictionAmplitudes;
using dyncal::NonlinearFriction;
using dyncal::NonlinearFrictionAmplitudes;
using dyncal::NonlinearFrictionModel;
using dyncal::UpdateStatus;
using Vec3 = Eigen::Matrix<double, 3, 1>;

/// Velocity and load torque of joint j at sample s: sweeps through zero at different rates.
double velocity(int j, int s) {
  return (0.4 + 0.3 * j) * std::sin(0.011 * (j + 1) * s + j) + 0.05 * std::cos(0.07 * s);
}
double load(int j, int s) {
  return 30.0 * std::cos(0.005 * s + j);
}

template <NonlinearFrictionModel M>
void expect_columns_reproduce_torque(const double* theta) {
  using A = NonlinearFrictionAmplitudes<M>;
  for (double qd : {-1.3, -0.2, -0.01, 0.0, 0.03, 0.4, 2.0}) {
    double c[A::kNumAmplitudes];
    A::columns(theta, qd, 0.0, c);
    double t = 0;
    for (int i = 0; i < A::kNumAmplitudes; ++i) t += c[i] * theta[A::amplitude(i)];
    EXPECT_NEAR(t, NonlinearFriction<M>::torque(theta, qd, static_cast<double*>(nullptr)), 1e-12) << qd;
  }
}

TEST(FrictionTracker, AmplitudeColumnsTimesAmplitudesAreTheModelsTorque) {
  const double eq4[] = {20.0, 28.0, 0.12, 9.0};
  const double eq5[] = {20.0, -8.0, 0.1, 2.0, 4.0, 9.0};
  const double eq6[] = {20.0, 8.0, 10.0, 30.0, 9.0};
  expect_columns_reproduce_torque<NonlinearFrictionModel::eq4>(eq4);
  expect_columns_reproduce_torque<NonlinearFrictionModel::eq5>(eq5);
  expect_columns_reproduce_torque<NonlinearFrictionModel::eq6>(eq6);
  static_assert(NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq4>::kNumAmplitudes == 3, "Fc, Fs, beta");
  static_assert(NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq4>::amplitude(2) == 3, "beta");
  static_assert(NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq5>::kNumAmplitudes == 4, "f1, f2, f4, beta");
  static_assert(NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq6>::kNumAmplitudes == 3, "f1, f2, beta");
  static_assert(LinearFrictionAmplitudes<dyncal::kFrictionEq9>::kNumAmplitudes == 3, "Fc, Fv, Fl");
}

// Without forgetting (mu = 1) the tracker is recursive least squares: from a wrong start with a
// large initial variance it ends at the batch least-squares amplitudes of each joint (Eq. 9: Fc,
// Fv, Fl; noisy torque, so the optimum is not the true value).
TEST(FrictionTracker, WithoutForgettingEqualsBatchLeastSquaresPerJoint) {
  using Tracker = FrictionTracker<double, 3, LinearFrictionAmplitudes<dyncal::kFrictionEq9>>;
  auto tracker = std::make_unique<Tracker>();
  ASSERT_EQ(tracker->reset(Tracker::ParamVector::Constant(1.0), 1e8, 1.0), UpdateStatus::ok);
  const double truth[3][3] = {{20, 9, 0.05}, {12, 4, 0.02}, {6, 2, 0.1}};
  constexpr int S = 3000;
  Eigen::MatrixXd A[3];
  Eigen::VectorXd b[3];
  for (int j = 0; j < 3; ++j) {
    A[j].resize(S, 3);
    b[j].resize(S);
  }
  for (int s = 0; s < S; ++s) {
    Vec3 qd, tl, tau;
    for (int j = 0; j < 3; ++j) {
      qd[j] = velocity(j, s);
      tl[j] = load(j, s);
      const double sg = qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0);
      A[j].row(s) << sg, qd[j], std::abs(tl[j]) * sg;
      tau[j] = A[j].row(s).dot(Eigen::Vector3d(truth[j][0], truth[j][1], truth[j][2])) + 0.5 * std::sin(1.7 * s * s);
      b[j][s] = tau[j];
    }
    ASSERT_EQ(tracker->update(qd, tl, tau, Vec3::Ones()), UpdateStatus::ok);
  }
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d ls = A[j].colPivHouseholderQr().solve(b[j]);
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(tracker->parameters()[3 * j + i], ls[i], 1e-6 * std::abs(ls[i])) << j;
    EXPECT_NEAR(tracker->torque(j, 0.3, 10.0), ls[0] + 0.3 * ls[1] + 10.0 * ls[2], 1e-9);
  }
}

// Eq. 4 at the calibrated qds: the amplitudes follow a step of beta with forgetting, not without;
// qds is never touched.
TEST(FrictionTracker, ForgettingFollowsAStepOfBetaOnStribeckFriction) {
  using A = NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq4>;
  using Tracker = FrictionTracker<double, 1, A>;
  using V1 = Eigen::Matrix<double, 1, 1>;
  const double theta[] = {20.0, 28.0, 0.12, 9.0};
  for (double mu : {1.0, 0.99}) {
    auto tracker = std::make_unique<Tracker>();
    ASSERT_EQ(tracker->reset(Eigen::Map<const Tracker::ParamVector>(theta), 1e4, mu), UpdateStatus::ok);
    double plant[4] = {20.0, 28.0, 0.12, 9.0};
    constexpr int S = 4000;
    for (int s = 0; s < S; ++s) {
      if (s == S / 2) plant[3] = 13.5;  // beta + 50 %
      const double qd = velocity(0, s);
      const V1 tau = V1::Constant(
          NonlinearFriction<NonlinearFrictionModel::eq4>::torque(plant, qd, static_cast<double*>(nullptr)));
      ASSERT_EQ(tracker->update(V1::Constant(qd), V1::Zero(), tau, V1::Ones()), UpdateStatus::ok);
    }
    EXPECT_EQ(tracker->parameters()[2], 0.12);
    if (mu < 1) {
      EXPECT_NEAR(tracker->parameters()[3], 13.5, 1e-3);
      EXPECT_NEAR(tracker->parameters()[0], 20.0, 1e-3);
    } else {
      EXPECT_LT(tracker->parameters()[3], 13.0);  // averages over both halves
    }
  }
}

TEST(FrictionTracker, BadInputIsRejectedAndChangesNothing) {
  using Tracker = FrictionTracker<float, 3, LinearFrictionAmplitudes<dyncal::kFrictionEq7>>;
  using V = Tracker::JointVector;
  auto tracker = std::make_unique<Tracker>();
  EXPECT_EQ(tracker->reset(Tracker::ParamVector::Ones(), 0.0f, 0.99f), UpdateStatus::invalid_argument);
  EXPECT_EQ(tracker->reset(Tracker::ParamVector::Ones(), 1e3f, 1.5f), UpdateStatus::invalid_argument);
  EXPECT_EQ(tracker->reset(Tracker::ParamVector::Constant(NAN), 1e3f, 0.99f), UpdateStatus::rejected_non_finite);
  ASSERT_EQ(tracker->reset(Tracker::ParamVector::Ones(), 1e3f, 0.99f), UpdateStatus::ok);
  const V qd(0.5f, -0.2f, 0.1f), tau(3.0f, -2.0f, 1.0f);
  ASSERT_EQ(tracker->update(qd, V::Zero(), tau, V::Ones()), UpdateStatus::ok);
  const Tracker before = *tracker;
  V bad = tau;
  bad[2] = NAN;
  EXPECT_EQ(tracker->update(qd, V::Zero(), bad, V::Ones()), UpdateStatus::rejected_non_finite);
  EXPECT_EQ(tracker->update(qd, V::Zero(), tau, V(1.0f, 0.0f, 1.0f)), UpdateStatus::invalid_argument);
  EXPECT_EQ(tracker->parameters(), before.parameters());
  // The state is untouched: the next good sample gives what it gives on the saved copy.
  Tracker copy = before;
  ASSERT_EQ(tracker->update(qd, V::Zero(), tau, V::Ones()), UpdateStatus::ok);
  ASSERT_EQ(copy.update(qd, V::Zero(), tau, V::Ones()), UpdateStatus::ok);
  EXPECT_EQ(tracker->parameters(), copy.parameters());
}

}  // namespace friction_tracker_suite
}  // namespace
