#include "dyncal_host/survey/tracking.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "dyncal/friction_tracker.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/friction_parameters.hpp"

namespace dyncal::host::survey {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Model7 = IdentificationModel<Robot, kFrictionEq7>;
constexpr int P7 = Model7::kNumParams;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using PV = Eigen::Matrix<double, P7, 1>;

constexpr double kChange = 0.5;  // beta0 -> (1 + kChange) beta0

double profile_factor(ChangeProfile p, Eigen::Index n, Eigen::Index S) {
  const double start = 0.5 * static_cast<double>(S);
  const double x = (static_cast<double>(n) - start) / (static_cast<double>(S) - start);
  if (x < 0) return 0;
  switch (p) {
    case ChangeProfile::step:
      return kChange;
    case ChangeProfile::ramp:
      return kChange * x;
    case ChangeProfile::second_order:
      return kChange * x * x;
  }
  return 0;
}

int viscous_column(int joint) {
  for (int i = Robot::kNumBase; i < P7; ++i) {
    const ParamInfo info = Model7::info(i);
    if (info.joint == joint && info.term == term::viscous) return i;
  }
  throw InputError("no viscous column for joint " + std::to_string(joint));
}

/// Lag, scatter and mean |error| of each result over the last quarter of the run (what is left
/// once a step's transient has decayed and a ramp's lag has settled).
void summarise(std::vector<TrackingResult>& out, ChangeProfile profile, double beta0) {
  for (TrackingResult& t : out) {
    const Eigen::Index S = static_cast<Eigen::Index>(t.beta.size()), start = 3 * S / 4;
    t.profile = profile;
    double sum = 0, sum_abs = 0, sum_sq = 0;
    for (Eigen::Index s = start; s < S; ++s) {
      const double e = t.beta_hat[static_cast<size_t>(s)] - t.beta[static_cast<size_t>(s)];
      sum += e;
      sum_abs += std::fabs(e);
      sum_sq += e * e;
    }
    const double n = static_cast<double>(S - start), change = kChange * beta0;
    const double mean = sum / n;
    t.relative_lag = std::fabs(mean) / change;
    t.relative_scatter = std::sqrt(std::max(0.0, sum_sq / n - mean * mean)) / change;
    t.relative_error = sum_abs / n / change;
  }
}

/// Runs the recorded states of `d` with joint `joint`'s beta changed by `profile` through
/// `update(s, q, qd, qdd, tau, beta_hat)` (s: the sample), which feeds the N filters and writes their beta estimates;
/// one result per filter, named `names`.
template <size_t N, class Update>
std::vector<TrackingResult> run_changed_beta(const SurveyData& d, ChangeProfile profile, int joint, double beta0,
                                             const std::array<const char*, N>& names, Update update) {
  const Eigen::Index S = d.q.rows();
  std::vector<TrackingResult> out(N);
  for (size_t k = 0; k < N; ++k) out[k].method = names[k];
  for (Eigen::Index s = 0; s < S; ++s) {
    const Vec6 q = d.q.row(s).transpose(), qd = d.qd.row(s).transpose(), qdd = d.qdd.row(s).transpose();
    const double beta = beta0 * (1 + profile_factor(profile, s, S));
    Vec6 tau = d.tau.row(s).transpose();
    tau[joint - 1] += (beta - beta0) * qd[joint - 1];
    std::array<double, N> beta_hat{};
    update(s, q, qd, qdd, tau, beta_hat);
    for (size_t k = 0; k < N; ++k) {
      out[k].beta.push_back(beta);
      out[k].beta_hat.push_back(beta_hat[k]);
    }
  }
  summarise(out, profile, beta0);
  return out;
}

/// track_friction_after_calibration with lib/ FrictionTracker<Friction> (the calibration's model).
template <class Friction>
TrackingResult track_amplitudes(const SurveyData& d, const Estimate& calibration, const MethodSettings& settings,
                                ChangeProfile profile, int joint, double mu, double beta0) {
  using Tracker = FrictionTracker<double, 6, Friction>;
  constexpr int k = Tracker::kNumParams;
  const std::vector<std::string> names = friction_parameter_names(calibration.model);
  const auto beta = std::find(names.begin(), names.end(), "beta");
  if (static_cast<int>(names.size()) != k || beta == names.end()) {
    throw InputError("tracking: unexpected friction parameters");
  }
  const int beta_index = k * (joint - 1) + static_cast<int>(beta - names.begin());
  auto tracker = std::make_unique<Tracker>();
  if (tracker->reset(Eigen::Map<const typename Tracker::ParamVector>(calibration.friction.data()), settings.p0, mu) !=
      UpdateStatus::ok) {
    throw InputError("tracking: tracker reset failed");
  }
  Vec6 w;
  for (int j = 0; j < 6; ++j) w[j] = 1.0 / settings.sigma[j];
  Eigen::Matrix<double, 6, Robot::kNumBase> Yb;
  std::vector<TrackingResult> out =
      run_changed_beta(d, profile, joint, beta0, std::array<const char*, 1>{""},
                       [&](Eigen::Index s, const Vec6& q, const Vec6& qd, const Vec6& qdd, const Vec6& tau,
                           std::array<double, 1>& beta_hat) {
                         Robot::base_regressor(q, qd, qdd, Yb);
                         const Vec6 tau_load = d.tau_load.row(s).transpose();
                         // A rejected sample leaves the estimate as it was: the tracking error then shows it.
                         (void)tracker->update(qd, tau_load, tau - Yb * calibration.base, w);
                         beta_hat[0] = tracker->parameters()[beta_index];
                       });
  return out.front();
}

/// Eq. 4 run: the extended Kalman filter (Eq. 21) and its forgetting form (Eq. 24).
std::vector<TrackingResult> track_nonlinear(const SurveyData& d, const MethodSettings& settings, ChangeProfile profile,
                                            int joint, double mu, double beta0) {
  const auto ekf = make_survey_ekf(settings, 1.0), fekf = make_survey_ekf(settings, mu);
  const int col = SurveyEkf::column(3, joint - 1);  // beta: the fourth Eq. 4 parameter
  Vec6 r;
  for (int j = 0; j < 6; ++j) r[j] = settings.sigma[j] * settings.sigma[j];
  return run_changed_beta(d, profile, joint, beta0,
                          std::array<const char*, 2>{"extended Kalman", "exponential forgetting (Eq. 4)"},
                          [&](Eigen::Index, const Vec6& q, const Vec6& qd, const Vec6& qdd, const Vec6& tau,
                              std::array<double, 2>& beta_hat) {
                            // A rejected sample leaves the estimate as it was: the tracking error then shows it.
                            (void)ekf->update(q, qd, qdd, tau, r);
                            (void)fekf->update(q, qd, qdd, tau, r);
                            beta_hat = {ekf->estimate()[col], fekf->estimate()[col]};
                          });
}

}  // namespace

const char* to_string(ChangeProfile p) {
  switch (p) {
    case ChangeProfile::step:
      return "step";
    case ChangeProfile::ramp:
      return "ramp";
    case ChangeProfile::second_order:
      return "second order";
  }
  return "?";
}

std::vector<TrackingResult> track_viscous_friction(const SurveyData& d, const MethodSettings& settings,
                                                   ChangeProfile profile, int joint, double mu) {
  if (joint < 1 || joint > 6) throw InputError("tracking: joint 1..6");
  const double beta0 = d.scenario.friction[joint - 1].beta;
  const bool nonlinear = d.scenario.friction[joint - 1].model == FrictionModel::eq4;
  if (nonlinear) return track_nonlinear(d, settings, profile, joint, mu, beta0);
  const int col = viscous_column(joint);
  auto kf = std::make_unique<KalmanFilter<double, P7, 6>>();
  auto rls = std::make_unique<RlsForgetting<double, P7, 6>>();
  if (kf->reset(PV::Zero(), PV::Constant(settings.p0), Model7::structure()) != UpdateStatus::ok ||
      rls->reset(PV::Zero(), PV::Constant(settings.p0), mu, 0.0, Model7::structure()) != UpdateStatus::ok) {
    throw InputError("tracking: filter reset failed");
  }
  Vec6 r, w;
  for (int j = 0; j < 6; ++j) {
    r[j] = settings.sigma[j] * settings.sigma[j];
    w[j] = 1.0 / settings.sigma[j];
  }
  Model7::Regressor<double> K;
  return run_changed_beta(d, profile, joint, beta0, std::array<const char*, 2>{"Kalman", "exponential forgetting"},
                          [&](Eigen::Index, const Vec6& q, const Vec6& qd, const Vec6& qdd, const Vec6& tau,
                              std::array<double, 2>& beta_hat) {
                            Model7::regressor(q, qd, qdd, Vec6::Zero().eval(), K);
                            // A rejected sample leaves the estimate as it was: the tracking error then shows it.
                            (void)kf->update(K, tau, r);
                            (void)rls->update(K, tau, w);
                            beta_hat = {kf->estimate()[col], rls->estimate()[col]};
                          });
}

TrackingResult track_friction_after_calibration(const SurveyData& d, const Estimate& calibration,
                                                const MethodSettings& settings, ChangeProfile profile, int joint,
                                                double mu) {
  if (joint < 1 || joint > 6) throw InputError("tracking: joint 1..6");
  if (calibration.base.size() != Robot::kNumBase ||
      calibration.friction.size() != static_cast<size_t>(6 * friction_count(calibration.model))) {
    throw InputError("tracking: calibration has the wrong number of parameters");
  }
  const double beta0 = d.scenario.friction[joint - 1].beta;
  TrackingResult r;
  switch (calibration.model) {
    case FrictionModel::eq7:
      r = track_amplitudes<LinearFrictionAmplitudes<kFrictionEq7>>(d, calibration, settings, profile, joint, mu, beta0);
      break;
    case FrictionModel::eq8:
      r = track_amplitudes<LinearFrictionAmplitudes<kFrictionEq8>>(d, calibration, settings, profile, joint, mu, beta0);
      break;
    case FrictionModel::eq9:
      r = track_amplitudes<LinearFrictionAmplitudes<kFrictionEq9>>(d, calibration, settings, profile, joint, mu, beta0);
      break;
    case FrictionModel::eq4:
      r = track_amplitudes<NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq4>>(d, calibration, settings, profile,
                                                                                     joint, mu, beta0);
      break;
    case FrictionModel::eq5:
      r = track_amplitudes<NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq5>>(d, calibration, settings, profile,
                                                                                     joint, mu, beta0);
      break;
    case FrictionModel::eq6:
      r = track_amplitudes<NonlinearFrictionAmplitudes<NonlinearFrictionModel::eq6>>(d, calibration, settings, profile,
                                                                                     joint, mu, beta0);
      break;
  }
  r.method =
      std::string(kConsistentForgetting) +
      (calibration.model == FrictionModel::eq7 ? "" : std::string(" (Eq. ") + (model_key(calibration.model) + 2) + ")");
  return r;
}

char follow_level(double ramp_relative_lag, double step_relative_lag) {
  if (ramp_relative_lag < 0.2) return 'A';
  return step_relative_lag < 0.2 ? 'B' : 'C';
}

}  // namespace dyncal::host::survey
