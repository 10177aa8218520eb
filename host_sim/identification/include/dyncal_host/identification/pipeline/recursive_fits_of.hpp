#pragma once
// The recursive estimators of a TermSetModel (identify --method kf | rls): lib/ KalmanFilter and
// RlsForgetting of IdentificationModel<Robot, Terms>'s size. Included only by the robots'
// calibration units (host_sim/robots/robot_calibration.cpp.in), which compile the same filters for
// calibrate's online path: each is compiled once per robot and term set.

#include <memory>
#include <utility>

#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/identification/pipeline/compiled_robot.hpp"
#include "dyncal_host/identification/pipeline/term_set_model.hpp"

namespace dyncal::host {

template <class Filter, int P, int N>
class RecursiveOf final : public RecursiveFit {
 public:
  Filter filter;
  UpdateStatus update(const double* K, const double* tau, const double* noise) override {
    const Eigen::Matrix<double, N, P> k = Eigen::Map<const Eigen::Matrix<double, N, P>>(K);
    const Eigen::Matrix<double, N, 1> t = Eigen::Map<const Eigen::Matrix<double, N, 1>>(tau);
    const Eigen::Matrix<double, N, 1> r = Eigen::Map<const Eigen::Matrix<double, N, 1>>(noise);
    return filter.update(k, t, r);
  }
  Eigen::VectorXd estimate() const override { return filter.estimate(); }
  Eigen::VectorXd covariance_diagonal() const override {
    Eigen::Matrix<double, P, 1> d;
    filter.covariance().diagonal(d);
    return d.cwiseSqrt();
  }
};

/// Sets m.make_kalman_filter and m.make_rls for IdentificationModel<Robot, Terms>.
template <class Robot, unsigned Terms>
void add_recursive_fits(TermSetModel& m) {
  constexpr int N = Robot::kNumJoints, P = IdentificationModel<Robot, Terms>::kNumParams;
  using ParamVec = Eigen::Matrix<double, P, 1>;
  m.make_kalman_filter = [](double p0, UpdateStatus* status) -> std::unique_ptr<RecursiveFit> {
    auto f = std::make_unique<RecursiveOf<KalmanFilter<double, P, N>, P, N>>();
    *status = f->filter.reset(ParamVec::Zero(), ParamVec::Constant(p0));
    if (*status != UpdateStatus::ok) return nullptr;
    return f;
  };
  m.make_rls = [](double p0, double mu, UpdateStatus* status) -> std::unique_ptr<RecursiveFit> {
    auto f = std::make_unique<RecursiveOf<RlsForgetting<double, P, N>, P, N>>();
    *status = f->filter.reset(ParamVec::Zero(), ParamVec::Constant(p0), mu);
    if (*status != UpdateStatus::ok) return nullptr;
    return f;
  };
}

/// Registers the recursive estimators of the built term sets First..First+3 (register_robot
/// completes the entry's models with them).
template <class Robot, int First, int... I>
bool register_recursive_fits(std::integer_sequence<int, I...>) {
  CompiledRobot c;
  c.name = Robot::kName;
  (add_recursive_fits<Robot, built_term_set(First + I)>(c.models[First + I]), ...);
  return register_robot(c);
}

}  // namespace dyncal::host
