#pragma once
// The survey's calculation methods (Sec. 3) run on one RunData: pseudo-inverse (Eq. 16),
// Kalman filter (Eq. 19), exponential forgetting (Eq. 23), extended Kalman filter (Eq. 21) and its
// forgetting form (Eq. 24). The recursive ones are the allocation-free lib/ updaters, fed one
// sample at a time in order, as on a drive.

#include <Eigen/Core>
#include <array>
#include <memory>

#include "dyncal/extended_kalman_filter.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal_host/survey/methods/estimate.hpp"
#include "dyncal_host/survey/methods/run_data.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host {

struct MethodSettings {
  CadPrior prior;                                             ///< CAD prior on the standard parameters
  std::array<double, 6> sigma{10, 10, 10, 1.78, 1.78, 1.78};  ///< assumed torque noise (Table 7) [Nm]
  double mu = 0.999;                                          ///< forgetting factor (Eq. 23, 24)
  double p0 = 1e6;                                            ///< initial covariance of unknown parameters
};

/// An Eq. 7 estimate from the parameter vector of IdentificationModel<er20, Eq. 7> (48: the 36 base
/// parameters, then Fc, beta of each joint): base + joint-major (Fc, beta). Throws InputError on
/// another size.
Estimate eq7_estimate(const Eigen::VectorXd& phi, const char* method);

/// Fills standard, standard_prior and tau_hat of `e` from its base and friction parameters.
void complete_estimate(Estimate& e, const RunData& data, const MethodSettings& settings);

/// Linear model (Eq. 7, 8 or 9; lib/ IdentificationModel, Eq. 9's load torque RunData::tau_load),
/// least squares over every sample (QR of the stacked base regressor). Throws InputError on another
/// model.
Estimate pseudo_inverse(const RunData& data, const MethodSettings& settings, FrictionModel model = FrictionModel::eq7);
/// Linear model, lib/ KalmanFilter (R = sigma^2, prior 0 with covariance p0).
Estimate kalman_filter(const RunData& data, const MethodSettings& settings, FrictionModel model = FrictionModel::eq7);
/// Linear model, lib/ RlsForgetting (weights 1/sigma, forgetting factor mu).
Estimate exponential_forgetting(const RunData& data, const MethodSettings& settings,
                                FrictionModel model = FrictionModel::eq7);
using SurveyEkf = ExtendedKalmanFilter<double, generated::er20::Robot, NonlinearFrictionModel::eq4>;
/// The study's EKF (mu = 1: Eq. 21, mu < 1: Eq. 24), reset to its start: base parameters 0 with
/// covariance p0, friction Fc = Fs = 10 Nm, qds = 0.3 +- 0.1 rad/s, beta = 0. Throws InputError.
std::unique_ptr<SurveyEkf> make_survey_ekf(const MethodSettings& settings, double mu);

/// Nonlinear model (Eq. 4, 5 or 6), lib/ ExtendedKalmanFilter; mu = 1: Eq. 21, mu < 1: Eq. 24.
/// Friction start (no knowledge of the set values): Fc, Fs (Eq. 4) and f1 (Eq. 5, 6) 10 Nm, other
/// amplitudes and beta 0, every velocity scale 0.3 rad/s +- a third (qds, f3 of Eq. 5 as velocities,
/// f5 of Eq. 5 and f3, f4 of Eq. 6 as their inverses). Throws InputError on another model.
Estimate extended_kalman_filter(const RunData& data, const MethodSettings& settings, double mu,
                                FrictionModel model = FrictionModel::eq4);

}  // namespace dyncal::host
