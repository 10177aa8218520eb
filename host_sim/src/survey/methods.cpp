#include "dyncal_host/survey/methods.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <memory>

#include "dyncal/extended_kalman_filter.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal_host/input_error.hpp"
#include "dyncal_host/survey/standard_parameters.hpp"
#include "er20/robot.hpp"

namespace dyncal::host::survey {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Model7 = IdentificationModel<Robot, kFrictionEq7>;
constexpr int P7 = Model7::kNumParams;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Ekf = SurveyEkf;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Vec6 row(const Eigen::MatrixXd& m, Eigen::Index s) {
  return m.row(s).transpose();
}

}  // namespace

Estimate eq7_estimate(const Eigen::VectorXd& phi, const char* method) {
  if (phi.size() != P7) throw InputError("an Eq. 7 estimate has " + std::to_string(P7) + " parameters");
  Estimate e;
  e.method = method;
  e.model = FrictionModel::eq7;
  e.base = phi.head<Robot::kNumBase>();
  e.friction.assign(12, 0.0);
  for (int i = Robot::kNumBase; i < P7; ++i) {
    const ParamInfo info = Model7::info(i);
    e.friction[static_cast<size_t>(2 * (info.joint - 1) + (info.term == term::coulomb ? 0 : 1))] = phi[i];
  }
  return e;
}

void complete_estimate(Estimate& e, const SurveyData& d, const MethodSettings& settings) {
  if (e.standard.size() != kStandard) {
    e.standard = minimum_norm_standard(e.base);
    e.standard_prior = standard_from_base(e.base, settings.prior, settings.prior_relative_std);
  }
  const int k = static_cast<int>(friction_parameter_names(e.model).size());
  e.tau_hat.resize(d.q.rows(), 6);
  Eigen::Matrix<double, 6, Robot::kNumBase> Yb;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    Robot::base_regressor(row(d.q, s), row(d.qd, s), row(d.qdd, s), Yb);
    Vec6 tau = Yb * e.base;
    for (int j = 0; j < 6; ++j) tau[j] += friction_torque(e.model, e.friction.data() + k * j, d.qd(s, j));
    e.tau_hat.row(s) = tau.transpose();
  }
}

Estimate pseudo_inverse(const SurveyData& d, const MethodSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::Index S = d.q.rows();
  Eigen::MatrixXd W(6 * S, P7);
  Eigen::VectorXd y(6 * S);
  Model7::Regressor<double> K;
  for (Eigen::Index s = 0; s < S; ++s) {
    Model7::regressor(row(d.q, s), row(d.qd, s), row(d.qdd, s), Vec6::Zero().eval(), K);
    W.middleRows(6 * s, 6) = K;
    y.segment<6>(6 * s) = row(d.tau, s);
  }
  const Eigen::Matrix<double, P7, 1> phi = W.colPivHouseholderQr().solve(y);
  Estimate e = eq7_estimate(phi, "pseudo-inverse");
  e.seconds = seconds_since(t0);
  complete_estimate(e, d, settings);
  return e;
}

namespace {

/// One pass of a lib/ Eq. 7 updater over the samples in order; `update(filter, K, tau)` feeds one.
template <class Filter, class Update>
Estimate run_linear_recursive(const SurveyData& d, const MethodSettings& settings, Filter& filter, Update update,
                              const char* method, std::chrono::steady_clock::time_point t0) {
  Model7::Regressor<double> K;
  int rejected = 0;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    Model7::regressor(row(d.q, s), row(d.qd, s), row(d.qdd, s), Vec6::Zero().eval(), K);
    if (update(filter, K, row(d.tau, s)) != UpdateStatus::ok) ++rejected;
  }
  Estimate e = eq7_estimate(filter.estimate(), method);
  e.seconds = seconds_since(t0);
  if (rejected) e.note = std::to_string(rejected) + " samples rejected";
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace

Estimate kalman_filter(const SurveyData& d, const MethodSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  auto kf = std::make_unique<KalmanFilter<double, P7, 6>>();
  using PV = Eigen::Matrix<double, P7, 1>;
  if (kf->reset(PV::Zero(), PV::Constant(settings.p0), Model7::structure()) != UpdateStatus::ok)
    throw InputError("KF reset failed");
  Vec6 r;
  for (int j = 0; j < 6; ++j) r[j] = settings.sigma[j] * settings.sigma[j];
  return run_linear_recursive(
      d, settings, *kf, [&](auto& f, const auto& K, const Vec6& tau) { return f.update(K, tau, r); }, "Kalman", t0);
}

Estimate exponential_forgetting(const SurveyData& d, const MethodSettings& settings) {
  const auto t0 = std::chrono::steady_clock::now();
  auto rls = std::make_unique<RlsForgetting<double, P7, 6>>();
  using PV = Eigen::Matrix<double, P7, 1>;
  if (rls->reset(PV::Zero(), PV::Constant(settings.p0), settings.mu, 0.0, Model7::structure()) != UpdateStatus::ok)
    throw InputError("RLS reset failed");
  Vec6 w;
  for (int j = 0; j < 6; ++j) w[j] = 1.0 / settings.sigma[j];
  return run_linear_recursive(
      d, settings, *rls, [&](auto& f, const auto& K, const Vec6& tau) { return f.update(K, tau, w); },
      "exponential forgetting", t0);
}

std::unique_ptr<SurveyEkf> make_survey_ekf(const MethodSettings& settings, double mu) {
  auto ekf = std::make_unique<Ekf>();
  Ekf::ParamVector phi0 = Ekf::ParamVector::Zero(), p0 = Ekf::ParamVector::Constant(settings.p0);
  for (int j = 0; j < 6; ++j) {
    phi0[Ekf::column(0, j)] = phi0[Ekf::column(1, j)] = 10.0;
    phi0[Ekf::column(2, j)] = 0.3;
    p0[Ekf::column(2, j)] = 0.01;
  }
  if (ekf->reset(phi0, p0, mu) != UpdateStatus::ok) throw InputError("EKF reset failed");
  return ekf;
}

Estimate extended_kalman_filter(const SurveyData& d, const MethodSettings& settings, double mu) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto ekf = make_survey_ekf(settings, mu);
  Vec6 r;
  for (int j = 0; j < 6; ++j) r[j] = settings.sigma[j] * settings.sigma[j];
  int rejected = 0;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    if (ekf->update(row(d.q, s), row(d.qd, s), row(d.qdd, s), row(d.tau, s), r) != UpdateStatus::ok) ++rejected;
  }
  Estimate e;
  e.method = mu < 1 ? "exponential forgetting (EKF)" : "extended Kalman";
  e.model = FrictionModel::eq4;
  e.base = ekf->estimate().head<Robot::kNumBase>();
  e.friction.assign(ekf->estimate().data() + Robot::kNumBase, ekf->estimate().data() + Ekf::kNumParams);
  e.seconds = seconds_since(t0);
  if (rejected) e.note = std::to_string(rejected) + " samples rejected";
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace dyncal::host::survey
