#pragma once
// The firmware replay, shared by the Cortex-M images and the host: a block of recorded er20 drive
// samples (q, tau at 100 Hz) goes through the causal differentiator, the generated regressor and
// one updater — the Kalman filter (Eq. 19) or RLS with forgetting (Eq. 23) on the base parameters
// + Eq. 7 friction, the EKF (Eq. 21) on the base parameters + Eq. 4 (Stribeck) friction, or the
// friction tracker of a calibrated drive (FrictionTracker: Eq. 4 amplitudes with forgetting on top
// of a fixed rigid-body calibration), or the payload estimator (PayloadEstimator: the last link's 10
// parameters with the arm's model fixed) — exactly as a drive would run them online. Templated on the scalar: float on
// the M4F, double on the M7 and on the host (the reference). Static storage only; no heap.
#include <cstdint>

#include "dyncal/causal_differentiator.hpp"
#include "dyncal/extended_kalman_filter.hpp"
#include "dyncal/friction_tracker.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/payload_estimator.hpp"
#include "dyncal/rls_forgetting.hpp"

namespace dyncal::replay {

using Robot = dyncal::generated::er20::Robot;
using LinearModel = IdentificationModel<Robot, kFrictionEq7>;

enum class Updater { kf, rls, ekf, friction, payload };

constexpr const char* name(Updater u) {
  switch (u) {
    case Updater::kf:
      return "KF";
    case Updater::rls:
      return "RLS";
    case Updater::ekf:
      return "EKF";
    case Updater::payload:
      return "payload estimator";
    default:
      return "friction tracker";
  }
}

/// Settings of the replay (the same on every target).
struct Settings {
  static constexpr double kCutoffHz = 10.0;  ///< causal low-pass on q and tau
  static constexpr double kPrior = 1e4;      ///< initial variance of every parameter
  static constexpr double kMu = 0.999;       ///< RLS forgetting factor
  static constexpr double kGate = 8.0;       ///< innovation gate [standard deviations]
  /// The friction tracker's calibration (what a drive would have flashed): the robot file's
  /// standard parameters, which the simulated drive runs, and its Stribeck velocity qds [rad/s].
  static constexpr double kCalibratedQds = 0.1;
};

template <typename Scalar, Updater U>
struct Estimator;

/// What the KF and RLS replays share: the linear model's regressor and prediction.
template <typename Scalar, class Filter>
struct LinearEstimator {
  static constexpr int kNumParams = LinearModel::kNumParams;
  Filter filter;
  typename LinearModel::template Regressor<Scalar> K;
  /// tau = K(q, qd, qdd) phi for a parameter vector phi (kNumParams).
  template <class V>
  void predict(const Scalar* phi, const V& q, const V& qd, const V& qdd, V& tau) {
    LinearModel::regressor(q, qd, qdd, V::Zero().eval(), K);
    tau.noalias() = K * Eigen::Map<const Eigen::Matrix<Scalar, kNumParams, 1>>(phi);
  }
  const Eigen::Matrix<Scalar, kNumParams, 1>& estimate() const { return filter.estimate(); }
};

template <typename Scalar>
struct Estimator<Scalar, Updater::kf> : LinearEstimator<Scalar, KalmanFilter<Scalar, LinearModel::kNumParams, 6>> {
  UpdateStatus reset() {
    const UpdateStatus s = this->filter.reset(LinearModel::ParamVector<Scalar>::Zero(),
                                              LinearModel::ParamVector<Scalar>::Constant(Scalar(Settings::kPrior)),
                                              LinearModel::structure());
    return s != UpdateStatus::ok ? s : this->filter.set_gate(Scalar(Settings::kGate));
  }
  template <class V>
  UpdateStatus update(const V& q, const V& qd, const V& qdd, const V& tau, const V& r) {
    LinearModel::regressor(q, qd, qdd, V::Zero().eval(), this->K);
    return this->filter.update(this->K, tau, r);
  }
};

template <typename Scalar>
struct Estimator<Scalar, Updater::rls> : LinearEstimator<Scalar, RlsForgetting<Scalar, LinearModel::kNumParams, 6>> {
  UpdateStatus reset() {
    return this->filter.reset(LinearModel::ParamVector<Scalar>::Zero(),
                              LinearModel::ParamVector<Scalar>::Constant(Scalar(Settings::kPrior)),
                              Scalar(Settings::kMu), Scalar(0), LinearModel::structure());
  }
  template <class V>
  UpdateStatus update(const V& q, const V& qd, const V& qdd, const V& tau, const V& r) {
    LinearModel::regressor(q, qd, qdd, V::Zero().eval(), this->K);
    V w;
    for (int j = 0; j < 6; ++j) w[j] = Scalar(1) / std::sqrt(r[j]);  // weights 1 / sigma_j
    return this->filter.update(this->K, tau, w);
  }
};

template <typename Scalar>
struct Estimator<Scalar, Updater::ekf> {
  using Filter = ExtendedKalmanFilter<Scalar, Robot, NonlinearFrictionModel::eq4>;
  static constexpr int kNumParams = Filter::kNumParams;
  Filter filter;
  UpdateStatus reset() {
    typename Filter::ParamVector phi0 = Filter::ParamVector::Zero(),
                                 p0 = Filter::ParamVector::Constant(Scalar(Settings::kPrior));
    for (int j = 0; j < 6; ++j) {  // Stribeck velocity: prior 0.2 +- 0.1 rad/s
      phi0[Filter::column(2, j)] = Scalar(0.2);
      p0[Filter::column(2, j)] = Scalar(0.01);
    }
    const UpdateStatus s = filter.reset(phi0, p0, Scalar(Settings::kMu));
    return s != UpdateStatus::ok ? s : filter.set_gate(Scalar(Settings::kGate));
  }
  template <class V>
  UpdateStatus update(const V& q, const V& qd, const V& qdd, const V& tau, const V& r) {
    return filter.update(q, qd, qdd, tau, r);
  }
  Eigen::Matrix<Scalar, 6, Robot::kNumBase> Yb;
  /// tau = Y_b phi_b + f(theta, qd) for a parameter vector phi (kNumParams).
  template <class V>
  void predict(const Scalar* phi, const V& q, const V& qd, const V& qdd, V& tau) {
    Robot::base_regressor(q, qd, qdd, Yb);
    tau.noalias() = Yb * Eigen::Map<const Eigen::Matrix<Scalar, Robot::kNumBase, 1>>(phi);
    for (int j = 0; j < 6; ++j)
      tau[j] += Filter::Friction::torque(phi + Filter::column(0, j), qd[j], static_cast<Scalar*>(nullptr));
  }
  const Eigen::Matrix<Scalar, kNumParams, 1>& estimate() const { return filter.estimate(); }
};

/// A calibrated drive tracking its friction: the rigid-body torque Y_b phi_b at the calibration's
/// base parameters (fixed), the Eq. 4 amplitudes Fc, Fs, beta of every joint tracked by
/// FrictionTracker with forgetting mu (qds fixed at the calibration's). Parameters: the tracker's,
/// joint-major (Fc, Fs, qds, beta).
template <typename Scalar>
struct Estimator<Scalar, Updater::friction> {
  using Tracker = FrictionTracker<Scalar, 6, NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq4>>;
  static constexpr int kNumParams = Tracker::ParamVector::RowsAtCompileTime;
  Tracker tracker;
  Eigen::Matrix<Scalar, Robot::kNumBase, 1> phi_b;
  Eigen::Matrix<Scalar, 6, Robot::kNumBase> Yb;
  UpdateStatus reset() {
    Eigen::Matrix<Scalar, Robot::kNumStandard, 1> phi;
    for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = Scalar(generated::er20::kNominalStandard[i]);
    Robot::standard_to_base(phi, phi_b);
    typename Tracker::ParamVector theta0 = Tracker::ParamVector::Zero();
    for (int j = 0; j < 6; ++j) theta0[4 * j + 2] = Scalar(Settings::kCalibratedQds);
    return tracker.reset(theta0, Scalar(Settings::kPrior), Scalar(Settings::kMu));
  }
  template <class V>
  UpdateStatus update(const V& q, const V& qd, const V& qdd, const V& tau, const V& r) {
    Robot::base_regressor(q, qd, qdd, Yb);
    V w;
    for (int j = 0; j < 6; ++j) w[j] = Scalar(1) / std::sqrt(r[j]);  // weights 1 / sigma_j
    return tracker.update(qd, V::Zero().eval(), (tau - Yb * phi_b).eval(), w);
  }
  /// tau = Y_b phi_b + f(theta, qd) for tracker parameters theta (kNumParams).
  template <class V>
  void predict(const Scalar* theta, const V& q, const V& qd, const V& qdd, V& tau) {
    Robot::base_regressor(q, qd, qdd, Yb);
    tau.noalias() = Yb * phi_b;
    for (int j = 0; j < 6; ++j)
      tau[j] +=
          NonlinearFriction<NonlinearFrictionModel::eq4>::torque(theta + 4 * j, qd[j], static_cast<Scalar*>(nullptr));
  }
  const typename Tracker::ParamVector& estimate() const { return tracker.parameters(); }
};

/// The payload on the last link with the arm's model fixed (PayloadEstimator, docs/payload.md): the
/// arm is the KF replay's estimate (the linear model, set_arm before reset: what a calibrated drive
/// has in its table), the input the torque it does not explain. The er20 recording carries no load:
/// the estimate is the arm model's error seen through the last link's columns; what the replay
/// measures is the update's cost and float against double. Parameters: dphi of payload_estimator.hpp.
template <typename Scalar>
struct Estimator<Scalar, Updater::payload> {
  using Payload = PayloadEstimator<Robot, Scalar>;
  static constexpr int kNumParams = Payload::kParams;
  Payload payload;
  typename LinearModel::template ParamVector<Scalar> phi_arm;
  typename LinearModel::template Regressor<Scalar> K;
  typename Payload::Regressor Y;
  /// The arm's parameters (LinearModel::kNumParams, the KF replay's reference estimate).
  void set_arm(const double* phi) {
    for (int i = 0; i < LinearModel::kNumParams; ++i) phi_arm[i] = Scalar(phi[i]);
  }
  UpdateStatus reset() { return payload.reset(Payload::ParamVector::Constant(Scalar(Settings::kPrior))); }
  /// One regressor evaluation: the arm's torque K phi_arm and, from its base columns, the payload's.
  template <class V>
  UpdateStatus update(const V& q, const V& qd, const V& qdd, const V& tau, const V& r) {
    if (!all_finite(q) || !all_finite(qd) || !all_finite(qdd)) return UpdateStatus::rejected_non_finite;
    LinearModel::regressor(q, qd, qdd, V::Zero().eval(), K);
    const V residual = tau - K * phi_arm;
    return payload.update_base(K.template leftCols<Robot::kNumBase>(), residual, r);
  }
  /// tau = K phi_arm + Y_b K_N dphi for payload parameters dphi (kNumParams).
  template <class V>
  void predict(const Scalar* dphi, const V& q, const V& qd, const V& qdd, V& tau) {
    LinearModel::regressor(q, qd, qdd, V::Zero().eval(), K);
    payload.regressor_from_base(K.template leftCols<Robot::kNumBase>(), Y);
    tau.noalias() = K * phi_arm + Y * Eigen::Map<const typename Payload::ParamVector>(dphi);
  }
  const typename Payload::ParamVector& estimate() const { return payload.estimate(); }
};

/// Counts of one replay.
struct Counts {
  int accepted = 0, rejected = 0, not_ready = 0;
};

/// Runs the estimator over samples[count][12] (q[6] rad, tau[6] Nm, at period h). `tick` is
/// called around each update with 0 (before the regressor) and 1 (after the update) for cost
/// measurement; pass a no-op on the host.
template <typename Scalar, Updater U, class Tick>
Counts run(Estimator<Scalar, U>& est, CausalDifferentiator<Scalar, 6>& diff, const float (*samples)[12], int count,
           double h, const double* sigma, Tick&& tick) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  Counts c;
  diff.reset(Scalar(h), Scalar(Settings::kCutoffHz));
  V r;
  for (int j = 0; j < 6; ++j) r[j] = Scalar(sigma[j] * sigma[j]);
  for (int k = 0; k < count; ++k) {
    V q_in, tau_in, q, qd, qdd, tau;
    for (int j = 0; j < 6; ++j) {
      q_in[j] = Scalar(samples[k][j]);
      tau_in[j] = Scalar(samples[k][6 + j]);
    }
    if (diff.update(q_in, tau_in, q, qd, qdd, tau) != UpdateStatus::ok) {
      ++c.not_ready;
      continue;
    }
    tick(0);
    const UpdateStatus s = est.update(q, qd, qdd, tau, r);
    tick(1);
    if (s == UpdateStatus::ok) {
      ++c.accepted;
    } else {
      ++c.rejected;
    }
  }
  return c;
}

/// Relative RMS difference between the torques predicted by the estimate of `est` and by the
/// reference parameters `ref` (kNumParams, a host double run) over the same filtered samples, and
/// the relative RMS residual of the estimate: sqrt(sum |tau_est - tau_ref|^2 / sum |tau_ref|^2).
template <typename Scalar, Updater U>
void compare(Estimator<Scalar, U>& est, const Scalar* ref, CausalDifferentiator<Scalar, 6>& diff,
             const float (*samples)[12], int count, double h, double& rel_difference, double& rel_residual) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  diff.reset(Scalar(h), Scalar(Settings::kCutoffHz));
  double sd = 0, sr = 0, st = 0;
  for (int k = 0; k < count; ++k) {
    V q_in, tau_in, q, qd, qdd, tau;
    for (int j = 0; j < 6; ++j) {
      q_in[j] = Scalar(samples[k][j]);
      tau_in[j] = Scalar(samples[k][6 + j]);
    }
    if (diff.update(q_in, tau_in, q, qd, qdd, tau) != UpdateStatus::ok) continue;
    V a, b;
    est.predict(est.estimate().data(), q, qd, qdd, a);
    est.predict(ref, q, qd, qdd, b);
    for (int j = 0; j < 6; ++j) {
      sd += double(a[j] - b[j]) * double(a[j] - b[j]);
      sr += double(a[j] - tau[j]) * double(a[j] - tau[j]);
      st += double(b[j]) * double(b[j]);
    }
  }
  rel_difference = st > 0 ? std::sqrt(sd / st) : 0.0;
  rel_residual = st > 0 ? std::sqrt(sr / st) : 0.0;
}

}  // namespace dyncal::replay
