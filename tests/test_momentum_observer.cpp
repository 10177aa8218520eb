// lib/'s generalised-momentum observer (dyncal/momentum_observer.hpp) and contact threshold
// (dyncal/contact_threshold.hpp):
// - its model split M(q) qdd + n(q, qd) equals the drive's feed-forward of the same table
//   (IdentificationModel's regressor times the table plus the effect terms: an independent path
//   through the generated base regressor, not the mass matrix and inverse dynamics) on the TX40
//   and the er20, with friction, rotor inertia, offsets, a coupled motor and Stribeck friction;
// - on a prescribed motion with an external torque step on one joint its residual is the
//   first-order response K / (s + K) of that step and stays near 0 on the others and before it;
// - float follows double; bad input and configurations return their status and change nothing;
// - the threshold's crossing rate (discrete Rice) matches the count on simulated Gaussian processes;
// - the centred slope (dyncal/centred_slope.hpp) against a least-squares line fitted by Eigen, its
//   delay, its standstill flags and its statuses;
// - the friction uncertainty's weight (dyncal/friction_uncertainty.hpp): 1 at rest, in the band and
//   at a reversal, then the observer's own decay (1 - K dt)^k.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <iostream>
#include <random>
#include <vector>

#include "dyncal/centred_slope.hpp"
#include "dyncal/contact_threshold.hpp"
#include "dyncal/direct_residual.hpp"
#include "dyncal/friction_uncertainty.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/generated/tx40/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/table_check.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace momentum_observer_suite {

using dyncal::UpdateStatus;

constexpr unsigned kTerms = dyncal::kFrictionEq7 | dyncal::term::rotor_inertia | dyncal::term::offset;

/// A table of Robot's nominal inertials with Coulomb 3 + j Nm, viscous 2 Nm s/rad, rotor inertia
/// 0.05 kg m^2 where separate, offset -1 + 0.5 j Nm, and (with_effects) a coupled motor on joints
/// 5, 6 (ratio -0.8) and Stribeck friction on joint 2.
template <class Robot>
dyncal::ParameterTable nominal_table(const double* nominal_standard, bool with_effects) {
  using Model = dyncal::IdentificationModel<Robot, kTerms>;
  Eigen::Matrix<double, Robot::kNumStandard, 1> phi_std;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi_std[i] = nominal_standard[i];
  Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
  Robot::standard_to_base(phi_std, phi_b);
  typename Model::template ParamVector<double> phi;
  phi.template head<Robot::kNumBase>() = phi_b;
  for (int i = Robot::kNumBase; i < Model::kNumParams; ++i) {
    const dyncal::ParamInfo info = Model::info(i);
    const double j = info.joint;
    phi[i] = info.term == dyncal::term::coulomb         ? 3 + j
             : info.term == dyncal::term::viscous       ? 2
             : info.term == dyncal::term::rotor_inertia ? 0.05
                                                        : -1 + 0.5 * j;
  }
  dyncal::ParameterTable t;
  dyncal::make_table<Model>(phi, t);
  if (with_effects) {
    dyncal::EffectTerm coupling;
    coupling.kind = dyncal::EffectKind::coupling;
    coupling.joint = 4;
    coupling.joint2 = 5;
    coupling.sign = -1;
    coupling.shape = 0.8f;
    coupling.c[0] = 1.5f, coupling.c[1] = 0.7f, coupling.c[2] = 0.02f;
    dyncal::EffectTerm stribeck;
    stribeck.kind = dyncal::EffectKind::stribeck;
    stribeck.joint = 1;
    stribeck.shape = 0.1f;
    stribeck.c[0] = 4.0f;
    t.effects[0] = coupling;
    t.effects[1] = stribeck;
    t.effect_count = 2;
  }
  return t;
}

/// The drive's feed-forward of a table (drive_plant_of.hpp): K(q, qd, qdd) phi plus the effects.
template <class Robot>
Eigen::Matrix<double, 6, 1> feed_forward(const dyncal::ParameterTable& t, const Eigen::Matrix<double, 6, 1>& q,
                                         const Eigen::Matrix<double, 6, 1>& qd,
                                         const Eigen::Matrix<double, 6, 1>& qdd) {
  using Model = dyncal::IdentificationModel<Robot, kTerms>;
  typename Model::template Regressor<double> K;
  Model::regressor(q, qd, qdd, Eigen::Matrix<double, 6, 1>::Zero().eval(), K);
  typename Model::template ParamVector<double> phi;
  for (int i = 0; i < Model::kNumParams; ++i) phi[i] = t.values[i];
  Eigen::Matrix<double, 6, 1> tau = K * phi;
  const Eigen::Matrix<double, 6, 1> tau_rb =
      K.template leftCols<Robot::kNumBase>() * phi.template head<Robot::kNumBase>();
  dyncal::add_effect_torques(t.effects, t.effect_count, q, qd, qdd, tau_rb, tau);
  return tau;
}

template <class Robot>
void expect_model_is_feed_forward(const double* nominal_standard) {
  const dyncal::ParameterTable t = nominal_table<Robot>(nominal_standard, true);
  dyncal::MomentumObserver<Robot> observer;
  ASSERT_EQ(observer.configure(t, Eigen::Matrix<double, 6, 1>::Constant(100), 1e-3), UpdateStatus::ok);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    Eigen::Matrix<double, 6, 1> q, qd, qdd;
    for (int j = 0; j < 6; ++j) q[j] = 2 * u(rng), qd[j] = 2 * u(rng), qdd[j] = 5 * u(rng);
    Eigen::Matrix<double, 6, 6> M;
    Eigen::Matrix<double, 6, 1> n;
    observer.model(q, qd, M, n);
    const Eigen::Matrix<double, 6, 1> ff = feed_forward<Robot>(t, q, qd, qdd);
    worst = std::max(worst, (M * qdd + n - ff).norm() / ff.norm());
    EXPECT_LT((M - M.transpose()).norm(), 1e-12 * M.norm());
    EXPECT_GT(M.ldlt().vectorD().minCoeff(), 0.0);
  }
  // The two paths round the generated constants (kinematic products, grouping coefficients) apart.
  EXPECT_LT(worst, 1e-9) << Robot::kName;
}

TEST(MomentumObserver, ModelIsTheDrivesFeedForward) {
  expect_model_is_feed_forward<dyncal::generated::tx40::Robot>(dyncal::generated::tx40::kNominalStandard);
  expect_model_is_feed_forward<dyncal::generated::er20::Robot>(dyncal::generated::er20::kNominalStandard);
}

using Er20 = dyncal::generated::er20::Robot;
using V6 = Eigen::Matrix<double, 6, 1>;

/// A prescribed smooth motion (sums of sines, within the er20's range) and the torque a drive
/// applies for it when an external torque tau_ext acts: tau = M qdd + n - tau_ext.
struct Motion {
  static void state(double t, V6& q, V6& qd, V6& qdd) {
    for (int j = 0; j < 6; ++j) {
      const double w1 = 1.3 + 0.4 * j, w2 = 2.9 - 0.3 * j, a1 = 0.5, a2 = 0.2;
      q[j] = a1 * std::sin(w1 * t) + a2 * std::sin(w2 * t + j);
      qd[j] = a1 * w1 * std::cos(w1 * t) + a2 * w2 * std::cos(w2 * t + j);
      qdd[j] = -a1 * w1 * w1 * std::sin(w1 * t) - a2 * w2 * w2 * std::sin(w2 * t + j);
    }
  }
};

TEST(MomentumObserver, ResidualIsTheLowPassedExternalTorque) {
  const dyncal::ParameterTable t = nominal_table<Er20>(dyncal::generated::er20::kNominalStandard, true);
  dyncal::MomentumObserver<Er20> observer;
  const double dt = 1e-3, K = 200, step = 50;  // 50 Nm on joint 3 from sample k0
  const int k0 = 1000;
  ASSERT_EQ(observer.configure(t, V6::Constant(K), dt), UpdateStatus::ok);
  double before = 0, others = 0, tracking = 0;
  for (int k = 0; k <= 2000; ++k) {
    const double time = k * dt;
    V6 q, qd, qdd, n;
    Motion::state(time, q, qd, qdd);
    Eigen::Matrix<double, 6, 6> M;
    observer.model(q, qd, M, n);
    V6 ext = V6::Zero();
    if (k >= k0) ext[2] = step;
    ASSERT_EQ(observer.update(q, qd, M * qdd + n - ext), UpdateStatus::ok);
    const V6& r = observer.residual();
    if (k < k0) {
      before = std::max(before, r.cwiseAbs().maxCoeff());
      continue;
    }
    // The discrete first-order response to a step that starts between two samples (trapezoid: half
    // of it in the first step): r_k = step (1 - (1 - K dt)^k (1 - K dt / 2)) after k + 1 samples.
    const int m = k - k0;
    const double expected = step * (1 - std::pow(1 - K * dt, m) * (1 - K * dt / 2));
    tracking = std::max(tracking, std::abs(r[2] - expected));
    for (int j = 0; j < 6; ++j)
      if (j != 2) others = std::max(others, std::abs(r[j]));
  }
  // Discretisation error of the motion (second order in dt) only; the step itself is exact.
  EXPECT_LT(before, 0.02);
  EXPECT_LT(others, 0.02);
  EXPECT_LT(tracking, 0.02);
  EXPECT_NEAR(observer.residual()[2], step, 0.02);
}

// The direct residual (direct_residual.hpp) with exact accelerations: the drive's feed-forward of
// the table (an independent path to the model) minus an external step on joint 3 gives the
// first-order filter's response r_k = step (1 - (1 - K dt)^(k + 1)), the other joints 0.
TEST(DirectResidual, IsTheLowPassedExternalTorqueGivenTheAcceleration) {
  const dyncal::ParameterTable t = nominal_table<Er20>(dyncal::generated::er20::kNominalStandard, true);
  dyncal::DirectResidual<Er20> direct;
  const double dt = 1e-3, K = 200, step = 50;
  const int k0 = 1000;
  V6 q, qd, qdd;
  Motion::state(0, q, qd, qdd);
  EXPECT_EQ(direct.update(q, qd, qd, qdd, V6::Zero()), UpdateStatus::invalid_argument);    // before configure
  EXPECT_EQ(direct.configure(t, V6::Constant(1001), dt), UpdateStatus::invalid_argument);  // K dt > 1
  ASSERT_EQ(direct.configure(t, V6::Constant(K), dt), UpdateStatus::ok);
  double before = 0, others = 0, tracking = 0;
  for (int k = 0; k <= 2000; ++k) {
    Motion::state(k * dt, q, qd, qdd);
    V6 ext = V6::Zero();
    if (k >= k0) ext[2] = step;
    const V6 tau = feed_forward<Er20>(t, q, qd, qdd) - ext;
    if (k == k0) {  // a non-finite sample is refused and changes nothing
      V6 bad = qdd;
      bad[1] = std::nan("");
      const V6 r = direct.residual();
      EXPECT_EQ(direct.update(q, qd, qd, bad, tau), UpdateStatus::rejected_non_finite);
      EXPECT_EQ(direct.residual(), r);
    }
    ASSERT_EQ(direct.update(q, qd, qd, qdd, tau), UpdateStatus::ok);
    const V6& r = direct.residual();
    if (k < k0) {
      before = std::max(before, r.cwiseAbs().maxCoeff());
      continue;
    }
    const double expected = step * (1 - std::pow(1 - K * dt, k - k0 + 1));
    tracking = std::max(tracking, std::abs(r[2] - expected));
    for (int j = 0; j < 6; ++j)
      if (j != 2) others = std::max(others, std::abs(r[j]));
  }
  // The model and the feed-forward round the generated constants apart (1e-9 relative).
  EXPECT_LT(before, 1e-6);
  EXPECT_LT(others, 1e-6);
  EXPECT_LT(tracking, 1e-6);
}

TEST(MomentumObserver, FloatFollowsDouble) {
  const dyncal::ParameterTable t = nominal_table<Er20>(dyncal::generated::er20::kNominalStandard, false);
  dyncal::MomentumObserver<Er20, double> d;
  dyncal::MomentumObserver<Er20, float> f;
  ASSERT_EQ(d.configure(t, V6::Constant(100), 1e-3), UpdateStatus::ok);
  ASSERT_EQ(f.configure(t, Eigen::Matrix<float, 6, 1>::Constant(100), 1e-3f), UpdateStatus::ok);
  double worst = 0;
  for (int k = 0; k < 3000; ++k) {
    V6 q, qd, qdd, n;
    Motion::state(k * 1e-3, q, qd, qdd);
    Eigen::Matrix<double, 6, 6> M;
    d.model(q, qd, M, n);
    V6 tau = M * qdd + n;
    tau[0] -= k > 1500 ? 100.0 : 0.0;
    ASSERT_EQ(d.update(q, qd, tau), UpdateStatus::ok);
    ASSERT_EQ(f.update(q.cast<float>(), qd.cast<float>(), tau.cast<float>()), UpdateStatus::ok);
    worst = std::max(worst, (d.residual() - f.residual().cast<double>()).cwiseAbs().maxCoeff());
  }
  EXPECT_NEAR(d.residual()[0], 100.0, 0.05);
  // float's 24 bits on momenta of about 100 N m s: the residual within a few 0.1 Nm.
  EXPECT_LT(worst, 0.5);
}

TEST(MomentumObserver, BadInputAndConfigurationChangeNothing) {
  const dyncal::ParameterTable good = nominal_table<Er20>(dyncal::generated::er20::kNominalStandard, true);
  dyncal::MomentumObserver<Er20> observer;
  const V6 q = V6::Constant(0.1), qd = V6::Constant(0.2), tau = V6::Constant(1);
  EXPECT_EQ(observer.update(q, qd, tau), UpdateStatus::invalid_argument);  // not configured
  dyncal::ParameterTable t = good;
  t.robot_id ^= 1u;
  EXPECT_EQ(observer.configure(t, V6::Constant(100), 1e-3), UpdateStatus::invalid_argument);
  t = good;
  t.count -= 1;
  EXPECT_EQ(observer.configure(t, V6::Constant(100), 1e-3), UpdateStatus::invalid_argument);
  t = good;
  t.model_id |= dyncal::term::load;
  EXPECT_EQ(observer.configure(t, V6::Constant(100), 1e-3), UpdateStatus::invalid_argument);
  t = good;
  t.values[3] = NAN;
  EXPECT_EQ(observer.configure(t, V6::Constant(100), 1e-3), UpdateStatus::rejected_non_finite);
  t = good;
  t.effects[0].joint2 = t.effects[0].joint;
  EXPECT_EQ(observer.configure(t, V6::Constant(100), 1e-3), UpdateStatus::invalid_argument);
  EXPECT_EQ(observer.configure(good, V6::Constant(1001), 1e-3), UpdateStatus::invalid_argument);  // K dt > 1
  EXPECT_EQ(observer.configure(good, V6::Constant(-1), 1e-3), UpdateStatus::invalid_argument);
  ASSERT_EQ(observer.configure(good, V6::Constant(100), 1e-3), UpdateStatus::ok);
  ASSERT_EQ(observer.update(q, qd, tau), UpdateStatus::ok);
  ASSERT_EQ(observer.update(q, qd, tau + V6::Constant(5)), UpdateStatus::ok);
  const V6 r = observer.residual();
  V6 bad = tau;
  bad[4] = NAN;
  EXPECT_EQ(observer.update(q, qd, bad), UpdateStatus::rejected_non_finite);
  EXPECT_EQ(observer.residual(), r);
  // The same next sample with and without the refused one in between: the same residual.
  dyncal::MomentumObserver<Er20> twin;
  ASSERT_EQ(twin.configure(good, V6::Constant(100), 1e-3), UpdateStatus::ok);
  ASSERT_EQ(twin.update(q, qd, tau), UpdateStatus::ok);
  ASSERT_EQ(twin.update(q, qd, tau + V6::Constant(5)), UpdateStatus::ok);
  ASSERT_EQ(twin.update(q, qd, tau), UpdateStatus::ok);
  ASSERT_EQ(observer.update(q, qd, tau), UpdateStatus::ok);
  EXPECT_EQ(observer.residual(), twin.residual());
  // The friction velocity overload with qd itself is the plain update.
  ASSERT_EQ(twin.update(q, qd, qd, tau), UpdateStatus::ok);
  ASSERT_EQ(observer.update(q, qd, tau), UpdateStatus::ok);
  EXPECT_EQ(observer.residual(), twin.residual());
}

/// Up-crossings of |x - mean| over c per hour, x sampled every dt, against the rate c was
/// set for (contact_threshold from x's own mean, std and difference std).
void expect_rate_matches(const std::vector<double>& x, double dt, const char* what) {
  const double n = static_cast<double>(x.size());
  double sum = 0, sq = 0, dsq = 0;
  for (size_t k = 0; k < x.size(); ++k) {
    sum += x[k], sq += x[k] * x[k];
    if (k > 0) dsq += (x[k] - x[k - 1]) * (x[k] - x[k - 1]);
  }
  const double mean = sum / n, s = std::sqrt(sq / n - mean * mean), s_d = std::sqrt(dsq / (n - 1));
  for (double per_hour : {200.0, 2000.0}) {
    const double c = dyncal::contact_threshold(s, s_d, dt, 1, per_hour / 3600);
    long crossings = 0;
    for (size_t k = 1; k < x.size(); ++k) crossings += (std::abs(x[k - 1] - mean) <= c && std::abs(x[k] - mean) > c);
    const double expected = per_hour * n * dt / 3600;
    EXPECT_GT(crossings, 0.8 * expected) << what << ", " << per_hour << " per hour";
    EXPECT_LT(crossings, 1.25 * expected) << what << ", " << per_hour << " per hour";
  }
}

TEST(ContactThreshold, CrossingRateMatchesTheCountOnGaussianProcesses) {
  // 4e6 samples at 1 kHz (1.1 h) of two processes: a first-order low-pass of white noise (what the
  // observer makes of white torque noise) and a second-order one with a mean (smoother, correlated
  // beyond one lag: the crossing rate still depends on the lag-1 correlation alone).
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double dt = 1e-3;
  const size_t n = 4000000;
  std::vector<double> first(n), second(n);
  double v = 0, w1 = 0, w2 = 0;
  for (size_t k = 0; k < n; ++k) {
    first[k] = v = 0.8 * v + 0.2 * noise(rng);
    w1 = 0.9 * w1 + 0.1 * noise(rng);
    w2 = 0.9 * w2 + 0.1 * w1;
    second[k] = 3.0 + w2;
  }
  expect_rate_matches(first, dt, "first order");
  expect_rate_matches(second, dt, "second order");
  EXPECT_TRUE(std::isnan(dyncal::contact_threshold(0.0, 1.0, dt, 1, 1.0)));
  EXPECT_TRUE(std::isnan(dyncal::contact_threshold(1.0, 1.0, dt, 1, 0.0)));
}

TEST(CentredSlope, IsTheLeastSquaresLineAndParabolaThroughTheWindowDSamplesLate) {
  using Slope = dyncal::CentredSlope<double, 3, 8>;
  using V = Slope::Vec;
  Slope s;
  const double dt = 1e-3;
  const int D = 5, joints = 2;
  ASSERT_EQ(s.reset(D, dt, joints), dyncal::UpdateStatus::ok);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<V> q;
  const double quantum = 1e-3;
  for (int k = 0; k < 200; ++k) {
    V x = V::Zero();
    x[0] = std::sin(0.02 * k) + 1e-4 * n(rng);
    x[1] = quantum * std::round(std::max(0.0, 0.05 * (k - 100)) * std::max(0.0, 0.05 * (k - 100)) / quantum);
    x[2] = 7.0;  // past `joints`: ignored
    q.push_back(x);
    V qc, qdc, qddc, tauc;
    Slope::Flags still;
    const auto st = s.update(x, V::Constant(k), qc, qdc, qddc, tauc, still);
    if (k < 2 * D) {
      EXPECT_EQ(st, dyncal::UpdateStatus::not_ready);
      continue;
    }
    ASSERT_EQ(st, dyncal::UpdateStatus::ok);
    const int m = k - D;
    // The least-squares line through the window's samples, by Eigen.
    Eigen::MatrixXd A(2 * D + 1, 2);
    Eigen::MatrixXd b(2 * D + 1, joints);
    bool stalled[joints] = {false, false};
    for (int i = -D; i <= D; ++i) {
      A.row(i + D) << 1.0, i * dt;
      for (int j = 0; j < joints; ++j) {
        b(i + D, j) = q[static_cast<size_t>(m + i)][j];
        if (i > -D && q[static_cast<size_t>(m + i)][j] == q[static_cast<size_t>(m + i - 1)][j]) stalled[j] = true;
      }
    }
    const Eigen::MatrixXd line = A.colPivHouseholderQr().solve(b);
    Eigen::MatrixXd A2(2 * D + 1, 3);  // and the parabola: qdd is twice its t^2 coefficient
    A2 << A, A.col(1).cwiseProduct(A.col(1));
    const Eigen::MatrixXd parabola = A2.colPivHouseholderQr().solve(b);
    for (int j = 0; j < joints; ++j) {
      EXPECT_NEAR(qdc[j], line(1, j), 1e-9 * (1 + std::abs(line(1, j))));
      EXPECT_NEAR(qddc[j], 2 * parabola(2, j), 1e-6 * (1 + std::abs(parabola(2, j))));
      EXPECT_EQ(qc[j], q[static_cast<size_t>(m)][j]);
      EXPECT_EQ(still[j] != 0, stalled[j]) << "sample " << m << " joint " << j;
    }
    EXPECT_NEAR(tauc[0], m, 1e-12 * m);  // a ramp's weighted mean over a symmetric window: its centre
    EXPECT_EQ(qc[2], 0.0);
    EXPECT_EQ(qdc[2], 0.0);
  }
}

// The torque comes weighted as the slope weights the acceleration: where the acceleration steps
// (from 0 to 2 rad/s^2 between two samples), the slope's change per period follows the weighted
// acceleration fed as torque, while the raw acceleration is up to a whole step ahead of it.
TEST(CentredSlope, WeightsTheTorqueAsTheSlopeWeightsTheAcceleration) {
  using Slope = dyncal::CentredSlope<double, 1, 16>;
  using V = Slope::Vec;
  const double dt = 1e-3, a = 2.0;
  for (const int D : {1, 5, 16}) {
    Slope s;
    ASSERT_EQ(s.reset(D, dt, 1), dyncal::UpdateStatus::ok);
    double previous = std::nan(""), previous_tau = 0, raw_lag = 0, weighted_lag = 0;
    for (int k = 0; k < 200; ++k) {
      const double t = k * dt, t0 = 100.5 * dt;  // the step, between samples 100 and 101
      const double q = 0.3 * t + (t > t0 ? 0.5 * a * (t - t0) * (t - t0) : 0.0);
      const double acceleration = t > t0 ? a : 0.0;
      V qc, qd, tau;
      Slope::Flags still;
      if (s.update(V::Constant(q), V::Constant(acceleration), qc, qd, tau, still) != dyncal::UpdateStatus::ok) continue;
      const int m = k - D;
      if (!std::isnan(previous)) {
        const double change = (qd[0] - previous) / dt;  // at m - 1/2
        const double raw = m * dt > t0 ? a : 0.0;
        raw_lag = std::max(raw_lag, std::abs(change - raw));
        weighted_lag = std::max(weighted_lag, std::abs(change - 0.5 * (tau[0] + previous_tau)));
      }
      previous = qd[0];
      previous_tau = tau[0];
    }
    EXPECT_GT(raw_lag, 0.4 * a) << "D " << D;
    EXPECT_LT(weighted_lag, 0.1 * a) << "D " << D;
  }
}

// A torque held over each period (a drive's command, TorqueHold::zero_order): the motion between
// samples k and k + 1 is tau_k's (q, qd exact for a piecewise constant acceleration), and with the
// weights shifted half a sample the slope's change between samples equals the trapezoid of the
// weighted torque to rounding, through an acceleration step; the sampled weights leave a part of the
// step (K dt / 2 of it for the observer: a half-sample shift).
TEST(CentredSlope, AHeldTorqueShiftsItsWeightsHalfASample) {
  using Slope = dyncal::CentredSlope<double, 1, 16>;
  using V = Slope::Vec;
  const double dt = 1e-3, a = 2.0;
  for (const int D : {1, 5, 16}) {
    double lag[2] = {0, 0};
    for (const auto hold : {dyncal::TorqueHold::sampled, dyncal::TorqueHold::zero_order}) {
      Slope s;
      ASSERT_EQ(s.reset(D, dt, 1, hold), dyncal::UpdateStatus::ok);
      double q = 0.1, v = 0.3, previous = std::nan(""), previous_tau = 0;
      for (int k = 0; k < 200; ++k) {
        const double held = k >= 100 ? a : 0.0;  // applied from sample k to k + 1
        V qc, qd, tau;
        Slope::Flags still;
        const dyncal::UpdateStatus st = s.update(V::Constant(q), V::Constant(held), qc, qd, tau, still);
        q += dt * v + 0.5 * dt * dt * held;
        v += dt * held;
        if (st != dyncal::UpdateStatus::ok) continue;
        if (!std::isnan(previous)) {
          const double change = (qd[0] - previous) / dt;
          double& worst = lag[hold == dyncal::TorqueHold::zero_order ? 1 : 0];
          worst = std::max(worst, std::abs(change - 0.5 * (tau[0] + previous_tau)));
        }
        previous = qd[0];
        previous_tau = tau[0];
      }
    }
    EXPECT_LT(lag[1], 1e-9 * a) << "D " << D;
    EXPECT_GT(lag[0], 0.02 * a) << "D " << D;
    std::cout << "D " << D << ": a held step's lag " << lag[0] / a << " of the step with the sampled weights, "
              << lag[1] / a << " with the held ones\n";
  }
}

TEST(CentredSlope, BadInputAndConfigurationReturnTheirStatus) {
  using Slope = dyncal::CentredSlope<float, 2, 4>;
  using V = Slope::Vec;
  Slope s;
  EXPECT_EQ(s.reset(0, 1e-3f, 2), dyncal::UpdateStatus::invalid_argument);
  EXPECT_EQ(s.reset(5, 1e-3f, 2), dyncal::UpdateStatus::invalid_argument);  // above MaxHalfWidth
  EXPECT_EQ(s.reset(2, 0.0f, 2), dyncal::UpdateStatus::invalid_argument);
  EXPECT_EQ(s.reset(2, 1e-3f, 3), dyncal::UpdateStatus::invalid_argument);
  ASSERT_EQ(s.reset(1, 1e-3f, 2), dyncal::UpdateStatus::ok);
  V q, qd, tau;
  Slope::Flags still;
  EXPECT_EQ(s.update(V(0.f, 0.f), V::Zero(), q, qd, tau, still), dyncal::UpdateStatus::not_ready);
  EXPECT_EQ(s.update(V(std::nanf(""), 0.f), V::Zero(), q, qd, tau, still), dyncal::UpdateStatus::rejected_non_finite);
  EXPECT_EQ(s.update(V(1e-3f, 0.f), V::Zero(), q, qd, tau, still), dyncal::UpdateStatus::not_ready);
  ASSERT_EQ(s.update(V(2e-3f, 0.f), V::Zero(), q, qd, tau, still), dyncal::UpdateStatus::ok);  // the NaN left no trace
  EXPECT_NEAR(qd[0], 1.0f, 1e-4f);
  EXPECT_EQ(still[0], 0);
  EXPECT_EQ(still[1], 1);
}

TEST(FrictionUncertainty, OneAtRestAndReversalsThenTheObserversDecay) {
  using U = dyncal::FrictionUncertainty<double, 2>;
  U u;
  EXPECT_EQ(u.reset(200.0, 0.01, 1), dyncal::UpdateStatus::invalid_argument);  // K dt = 2
  EXPECT_EQ(u.reset(200.0, 1e-3, 3), dyncal::UpdateStatus::invalid_argument);
  ASSERT_EQ(u.reset(200.0, 1e-3, 1), dyncal::UpdateStatus::ok);
  U::Vec w;
  const U::Flags moving = U::Flags::Zero(), resting = U::Flags::Ones();
  // qd (joint 1) per sample, and the weight expected: the first sample's history is unknown.
  const double decay = 1.0 - 200.0 * 1e-3;
  struct Step {
    double qd;
    bool still;
    double weight;
  };
  const Step steps[] = {{0.5, false, 1.0},    {0.4, false, decay}, {0.3, false, decay * decay}, {-0.1, false, 1.0},
                        {-0.2, false, decay}, {0.0, false, 1.0},   {0.0, false, 1.0},           {0.2, false, 1.0},
                        {0.2, true, 1.0},     {0.3, false, decay}};
  for (const Step& s : steps) {
    ASSERT_EQ(u.update(U::Vec(s.qd, 9.0), s.still ? resting : moving, w), dyncal::UpdateStatus::ok);
    EXPECT_NEAR(w[0], s.weight, 1e-12) << "qd " << s.qd;
    EXPECT_EQ(w[1], 0.0);  // past `joints`
  }
  EXPECT_EQ(u.update(U::Vec(std::nan(""), 0.0), moving, w), dyncal::UpdateStatus::rejected_non_finite);
  ASSERT_EQ(u.update(U::Vec(0.3, 0.0), moving, w), dyncal::UpdateStatus::ok);  // the NaN left no trace
  EXPECT_NEAR(w[0], decay * decay, 1e-12);
  for (int k = 0; k < 400; ++k) u.update(U::Vec(0.3, 0.0), moving, w);
  EXPECT_EQ(w[0], 0.0);  // forgotten, no denormal
}

}  // namespace momentum_observer_suite
}  // namespace
