#include "dyncal_host/survey/methods/methods.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <memory>
#include <type_traits>

#include "dyncal/extended_kalman_filter.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Vec6 = Eigen::Matrix<double, 6, 1>;

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Vec6 row(const Eigen::MatrixXd& m, Eigen::Index s) {
  return m.row(s).transpose();
}

/// The lib/ identification model of a linear friction model (survey Eq. 10).
template <FrictionModel M>
struct LinearModel;
template <>
struct LinearModel<FrictionModel::eq7> {
  using type = IdentificationModel<Robot, kFrictionEq7>;
};
template <>
struct LinearModel<FrictionModel::eq8> {
  using type = IdentificationModel<Robot, kFrictionEq8>;
};
template <>
struct LinearModel<FrictionModel::eq9> {
  using type = IdentificationModel<Robot, kFrictionEq9>;
};

template <FrictionModel M>
using ModelTag = std::integral_constant<FrictionModel, M>;

/// Calls f(ModelTag<M>{}) for the linear model `model`.
template <class F>
Estimate with_linear_model(FrictionModel model, F&& f) {
  switch (model) {
    case FrictionModel::eq7:
      return f(ModelTag<FrictionModel::eq7>{});
    case FrictionModel::eq8:
      return f(ModelTag<FrictionModel::eq8>{});
    case FrictionModel::eq9:
      return f(ModelTag<FrictionModel::eq9>{});
    default:
      throw InputError(std::string("a linear method takes Eq. 7, 8 or 9, not ") + model_key(model));
  }
}

/// Estimate of a parameter vector of LinearModel<M>: base, then the friction terms in
/// friction_parameter_names order (Fc, beta, then fp or fl).
template <FrictionModel M>
Estimate linear_estimate(const Eigen::VectorXd& phi, const char* method) {
  using Model = typename LinearModel<M>::type;
  if (phi.size() != Model::kNumParams) {
    throw InputError(std::string("an estimate of ") + model_key(M) + " has " + std::to_string(Model::kNumParams) +
                     " parameters");
  }
  const int k = friction_count(M);
  Estimate e;
  e.method = method;
  e.model = M;
  e.base = phi.head<Robot::kNumBase>();
  e.friction.assign(static_cast<size_t>(6 * k), 0.0);
  for (int i = Robot::kNumBase; i < Model::kNumParams; ++i) {
    const ParamInfo info = Model::info(i);
    const int slot = info.term == term::coulomb ? 0 : (info.term == term::viscous ? 1 : 2);
    e.friction[static_cast<size_t>(k * (info.joint - 1) + slot)] = phi[i];
  }
  return e;
}

}  // namespace

Estimate eq7_estimate(const Eigen::VectorXd& phi, const char* method) {
  return linear_estimate<FrictionModel::eq7>(phi, method);
}

void complete_estimate(Estimate& e, const RunData& d, const MethodSettings& settings) {
  if (e.standard.size() != kStandard) {
    e.standard = minimum_norm_standard(e.base);
    e.standard_prior = standard_from_base(e.base, settings.prior);
  }
  const int k = friction_count(e.model);
  e.tau_hat.resize(d.q.rows(), 6);
  Eigen::Matrix<double, 6, Robot::kNumBase> Yb;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    Robot::base_regressor(row(d.q, s), row(d.qd, s), row(d.qdd, s), Yb);
    Vec6 tau = Yb * e.base;
    for (int j = 0; j < 6; ++j) {
      tau[j] += friction_torque(e.model, e.friction.data() + k * j, d.qd(s, j), d.tau_load(s, j));
    }
    e.tau_hat.row(s) = tau.transpose();
  }
}

Estimate pseudo_inverse(const RunData& d, const MethodSettings& settings, FrictionModel model) {
  return with_linear_model(model, [&](auto tag) {
    constexpr FrictionModel M = decltype(tag)::value;
    using Model = typename LinearModel<M>::type;
    const auto t0 = std::chrono::steady_clock::now();
    const Eigen::Index S = d.q.rows();
    Eigen::MatrixXd W(6 * S, Model::kNumParams);
    Eigen::VectorXd y(6 * S);
    typename Model::template Regressor<double> K;
    for (Eigen::Index s = 0; s < S; ++s) {
      Model::regressor(row(d.q, s), row(d.qd, s), row(d.qdd, s), row(d.tau_load, s), K);
      W.middleRows(6 * s, 6) = K;
      y.segment<6>(6 * s) = row(d.tau, s);
    }
    const Eigen::VectorXd phi = W.colPivHouseholderQr().solve(y);
    Estimate e = linear_estimate<M>(phi, "pseudo-inverse");
    e.seconds = seconds_since(t0);
    complete_estimate(e, d, settings);
    return e;
  });
}

namespace {

/// One pass of a lib/ linear updater over the samples in order; `update(filter, K, tau)` feeds one.
template <FrictionModel M, class Filter, class Update>
Estimate run_linear_recursive(const RunData& d, const MethodSettings& settings, Filter& filter, Update update,
                              const char* method, std::chrono::steady_clock::time_point t0) {
  using Model = typename LinearModel<M>::type;
  typename Model::template Regressor<double> K;
  int rejected = 0;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    Model::regressor(row(d.q, s), row(d.qd, s), row(d.qdd, s), row(d.tau_load, s), K);
    if (update(filter, K, row(d.tau, s)) != UpdateStatus::ok) ++rejected;
  }
  Estimate e = linear_estimate<M>(filter.estimate(), method);
  e.seconds = seconds_since(t0);
  if (rejected) e.note = std::to_string(rejected) + " samples rejected";
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace

Estimate kalman_filter(const RunData& d, const MethodSettings& settings, FrictionModel model) {
  return with_linear_model(model, [&](auto tag) {
    constexpr FrictionModel M = decltype(tag)::value;
    using Model = typename LinearModel<M>::type;
    constexpr int P = Model::kNumParams;
    const auto t0 = std::chrono::steady_clock::now();
    auto kf = std::make_unique<KalmanFilter<double, P, 6>>();
    using PV = Eigen::Matrix<double, P, 1>;
    if (kf->reset(PV::Zero(), PV::Constant(settings.p0), Model::structure()) != UpdateStatus::ok)
      throw InputError("KF reset failed");
    Vec6 r;
    for (int j = 0; j < 6; ++j) r[j] = settings.sigma[j] * settings.sigma[j];
    return run_linear_recursive<M>(
        d, settings, *kf, [&](auto& f, const auto& K, const Vec6& tau) { return f.update(K, tau, r); }, "Kalman", t0);
  });
}

Estimate exponential_forgetting(const RunData& d, const MethodSettings& settings, FrictionModel model) {
  return with_linear_model(model, [&](auto tag) {
    constexpr FrictionModel M = decltype(tag)::value;
    using Model = typename LinearModel<M>::type;
    constexpr int P = Model::kNumParams;
    const auto t0 = std::chrono::steady_clock::now();
    auto rls = std::make_unique<RlsForgetting<double, P, 6>>();
    using PV = Eigen::Matrix<double, P, 1>;
    if (rls->reset(PV::Zero(), PV::Constant(settings.p0), settings.mu, 0.0, Model::structure()) != UpdateStatus::ok)
      throw InputError("RLS reset failed");
    Vec6 w;
    for (int j = 0; j < 6; ++j) w[j] = 1.0 / settings.sigma[j];
    return run_linear_recursive<M>(
        d, settings, *rls, [&](auto& f, const auto& K, const Vec6& tau) { return f.update(K, tau, w); },
        "exponential forgetting", t0);
  });
}

namespace {

/// The EKF of model M reset to the study's start: base parameters 0 with covariance p0; Coulomb-like
/// amplitudes (Fc, Fs of Eq. 4; f1 of Eq. 5, 6) 10 Nm; the other amplitudes and beta 0; every
/// velocity scale at 0.3 rad/s with a third of it as standard deviation (qds, f3 of Eq. 5 as
/// velocities; f5 of Eq. 5, f3 and f4 of Eq. 6 as inverse velocities 1 / 0.3 s/rad).
template <NonlinearFrictionModel N>
std::unique_ptr<ExtendedKalmanFilter<double, Robot, N>> make_ekf(FrictionModel model, const MethodSettings& settings,
                                                                 double mu) {
  using Filter = ExtendedKalmanFilter<double, Robot, N>;
  auto ekf = std::make_unique<Filter>();
  typename Filter::ParamVector phi0 = Filter::ParamVector::Zero(), p0 = Filter::ParamVector::Constant(settings.p0);
  constexpr double kScale = 0.3;
  for (int j = 0; j < 6; ++j) {
    for (int k = 0; k < Filter::kFrictionParams; ++k) {
      const int c = Filter::column(k, j);
      if (is_scale_parameter(model, k)) {
        phi0[c] = is_inverse_velocity(model, k) ? 1.0 / kScale : kScale;
        p0[c] = phi0[c] * phi0[c] / 9.0;
      } else if (k == 0 || (model == FrictionModel::eq4 && k == 1)) {
        phi0[c] = 10.0;
      }
    }
  }
  if (ekf->reset(phi0, p0, mu) != UpdateStatus::ok) throw InputError("EKF reset failed");
  return ekf;
}

template <NonlinearFrictionModel N>
Estimate run_ekf(FrictionModel model, const RunData& d, const MethodSettings& settings, double mu) {
  using Filter = ExtendedKalmanFilter<double, Robot, N>;
  const auto t0 = std::chrono::steady_clock::now();
  const auto ekf = make_ekf<N>(model, settings, mu);
  Vec6 r;
  for (int j = 0; j < 6; ++j) r[j] = settings.sigma[j] * settings.sigma[j];
  int rejected = 0;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    if (ekf->update(row(d.q, s), row(d.qd, s), row(d.qdd, s), row(d.tau, s), r) != UpdateStatus::ok) ++rejected;
  }
  Estimate e;
  e.method = mu < 1 ? "exponential forgetting (EKF)" : "extended Kalman";
  e.model = model;
  e.base = ekf->estimate().template head<Robot::kNumBase>();
  e.friction.assign(ekf->estimate().data() + Robot::kNumBase, ekf->estimate().data() + Filter::kNumParams);
  e.seconds = seconds_since(t0);
  if (rejected) e.note = std::to_string(rejected) + " samples rejected";
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace

std::unique_ptr<SurveyEkf> make_survey_ekf(const MethodSettings& settings, double mu) {
  return make_ekf<NonlinearFrictionModel::eq4>(FrictionModel::eq4, settings, mu);
}

Estimate extended_kalman_filter(const RunData& d, const MethodSettings& settings, double mu, FrictionModel model) {
  switch (model) {
    case FrictionModel::eq4:
      return run_ekf<NonlinearFrictionModel::eq4>(model, d, settings, mu);
    case FrictionModel::eq5:
      return run_ekf<NonlinearFrictionModel::eq5>(model, d, settings, mu);
    case FrictionModel::eq6:
      return run_ekf<NonlinearFrictionModel::eq6>(model, d, settings, mu);
    default:
      throw InputError(std::string("the extended Kalman filter takes Eq. 4, 5 or 6, not ") + model_key(model));
  }
}

}  // namespace dyncal::host
