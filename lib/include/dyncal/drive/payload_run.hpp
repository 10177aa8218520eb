#pragma once
// The drive's payload run (docs/payload.md "On the drive"): the last link's 10 standard parameters
// of a load, identified while a run plays with the active table fixed — lib/'s payload estimator
// (payload_estimator.hpp: the Kalman filter of the survey's Eq. 19 on Y_b K_N, Gautier's base map of
// link N) on every recorded sample's residual tau_measured - tau_model, tau_model the table's torque
// at the measured position with the trajectory's velocity and acceleration (the PD loop lets a load
// pull the arm off its trajectory; the arm's gravity there differs from the feed-forward's). At the
// run's end the verdict: the mass determined (95 % half-width 1.96 std at most a tenth of itself)
// and positive, and every other parameter kept when its half-width is within its scale
// (payload_scales), not determined (NaN) otherwise; the std are the filter's times the residuals' RMS
// over their assumed std (at least 1). The loaded table is the active one with its base parameters
// moved by K_N dphi (the determined parameters; the others held at 0). One implementation for every
// drive: the drive application and the Linux simulated drive run it. Heap-free, exception-free.

#include <Eigen/Core>
#include <cmath>
#include <limits>

#include "dyncal/parameter_table.hpp"
#include "dyncal/payload_estimator.hpp"

namespace dyncal::drive {

/// The payload run's estimate: dphi [XX XY XZ YY YZ ZZ (kg m^2) MX MY MZ (kg m) M (kg)], last link's
/// frame, about its origin.
struct PayloadVerdict {
  bool mass_determined = false;  ///< the mass determined and positive: the table takes the load
  double value[10] = {};         ///< NaN where the run does not determine the parameter
  double std[10] = {};           ///< NaN likewise
  long updates = 0;              ///< samples the filter took

  /// No estimate yet (a payload run that has not ended): every value and std NaN.
  static PayloadVerdict unknown() noexcept {
    PayloadVerdict v;
    for (int i = 0; i < 10; ++i) v.value[i] = v.std[i] = std::numeric_limits<double>::quiet_NaN();
    return v;
  }
};

template <class Robot, typename Scalar>
class PayloadRun {
 public:
  static constexpr int N = Robot::kNumJoints;
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  /// 95 % two-sided normal quantile; the mass must be determined to a tenth of itself.
  static constexpr double kZ = 1.959963984540054, kDeterminedFraction = 0.1;

  /// `link_nominal`: the last link's own 10 standard parameters (the robot file's, for the scales).
  explicit PayloadRun(const double* link_nominal) noexcept {
    for (int i = 0; i < 10; ++i) link_nominal_[i] = static_cast<Scalar>(link_nominal[i]);
  }

  /// Starts from no load with a diffuse prior (1e6 in the parameters' units: least squares).
  void begin() noexcept {
    estimator_.reset(Eigen::Matrix<Scalar, 10, 1>::Constant(Scalar(1e6)));
    innovation_sq_.setZero();
    updates_ = 0;
  }

  /// One recorded sample: the measured q [rad], the trajectory's qd [rad/s] and qdd [rad/s^2], the
  /// residual tau_measured - tau_model [Nm] and the torque measurement's variance r [Nm^2] (> 0). A
  /// sample the filter refuses is skipped.
  void update(const Vec& q, const Vec& qd, const Vec& qdd, const Vec& residual, const Vec& r) noexcept {
    if (estimator_.update(q, qd, qdd, residual, r) != UpdateStatus::ok) return;
    typename Estimator::Regressor Y;
    estimator_.regressor(q, qd, qdd, Y);
    const Vec after = residual - Y * estimator_.estimate();  // a posteriori: the fit's residual
    innovation_sq_ += after.cwiseAbs2().cwiseQuotient(r);
    ++updates_;
  }

  /// The estimate now, with its verdicts.
  PayloadVerdict verdict() const noexcept {
    PayloadVerdict v;
    v.updates = updates_;
    Eigen::Matrix<Scalar, 10, 1> var, scale;
    estimator_.variance(var);
    // The residuals' mean square over r (the worst joint): 1 when r is their variance; above 1 they
    // hold more than the sensor's noise (the arm model's error), and the std grows with them.
    const double inflation =
        updates_ > 0 ? std::fmax(1.0, static_cast<double>(innovation_sq_.maxCoeff()) / static_cast<double>(updates_))
                     : 1.0;
    const Eigen::Matrix<Scalar, 10, 1>& x = estimator_.estimate();
    payload_scales(x, link_nominal_, scale);
    const double mass = static_cast<double>(x[9]);
    const double mass_std = std::sqrt(std::fmax(0.0, static_cast<double>(var[9])) * inflation);
    v.mass_determined = updates_ > 0 && mass > 0 && kZ * mass_std <= kDeterminedFraction * mass;
    for (int i = 0; i < 10; ++i) {
      const double sd = std::sqrt(std::fmax(0.0, static_cast<double>(var[i])) * inflation);
      const bool kept = v.mass_determined && std::isfinite(sd) && kZ * sd <= static_cast<double>(scale[i]);
      v.value[i] = kept ? static_cast<double>(x[i]) : std::numeric_limits<double>::quiet_NaN();
      v.std[i] = kept ? sd : std::numeric_limits<double>::quiet_NaN();
    }
    return v;
  }

  /// `active` (a table whose first Robot::kNumBase values are the base parameters) with the load
  /// of `v` on the last link: its base parameters moved by K_N dphi, the parameters the run did not
  /// determine held at 0; every other value kept.
  static ParameterTable loaded(const ParameterTable& active, const PayloadVerdict& v) noexcept {
    Eigen::Matrix<double, Robot::kNumStandard, 1> phi = Eigen::Matrix<double, Robot::kNumStandard, 1>::Zero();
    for (int i = 0; i < 10; ++i) phi[Robot::kNumStandard - 10 + i] = std::isfinite(v.value[i]) ? v.value[i] : 0.0;
    Eigen::Matrix<double, Robot::kNumBase, 1> delta;
    Robot::standard_to_base(phi, delta);
    ParameterTable t = active;
    for (int i = 0; i < Robot::kNumBase; ++i) t.values[i] = static_cast<float>(t.values[i] + delta[i]);
    return t;
  }

 private:
  using Estimator = PayloadEstimator<Robot, Scalar>;
  Estimator estimator_;
  Scalar link_nominal_[10] = {};
  Vec innovation_sq_ = Vec::Zero();
  long updates_ = 0;
};

}  // namespace dyncal::drive
