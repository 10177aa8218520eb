#pragma once
// Instantiates the host tools' code for one generated robot type and registers it under the
// robot's name (compiled_robot.hpp). Included only by the robots' translation units, which the
// build generates from host_sim/robots/*.cpp.in for every robots/<name>/ folder.

#include <string>
#include <utility>

#include "dyncal/direct_residual.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/nonlinear_friction.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/robots/term_set_model_of.hpp"

namespace dyncal::host {

/// CompiledRobot::ExcitationRegressorFn for `Robot`.
template <class Robot>
Eigen::MatrixXd excitation_regressor(const ExcitationTrajectory& t, FrictionModel model,
                                     const std::vector<NominalFriction>& friction, int grid) {
  constexpr int N = Robot::kNumJoints, B = Robot::kNumBase;
  using Model7 = IdentificationModel<Robot, kFrictionEq7>;
  using Vec = typename Robot::template JointVector<double>;
  const bool eq4 = model == FrictionModel::eq4;
  const int cols = eq4 ? B + 4 * N : Model7::kNumParams;
  Eigen::MatrixXd W(N * grid, cols);
  typename Model7::template Regressor<double> K;
  Eigen::Matrix<double, N, B> Yb;
  for (int k = 0; k < grid; ++k) {
    Vec q, qd, qdd;
    t.evaluate(t.period() * k / grid, q, qd, qdd);
    if (!eq4) {
      Model7::regressor(q, qd, qdd, Vec::Zero().eval(), K);
      W.middleRows(N * k, N) = K;
      continue;
    }
    Robot::base_regressor(q, qd, qdd, Yb);
    W.block(N * k, 0, N, B) = Yb;
    W.block(N * k, B, N, 4 * N).setZero();
    for (int j = 0; j < N; ++j) {
      const NominalFriction& f = friction[static_cast<size_t>(j)];
      const double theta[4] = {f.Fc, f.Fs, f.qds, f.beta};
      double jac[4];
      NonlinearFriction<NonlinearFrictionModel::eq4>::torque(theta, qd[j], jac);
      for (int i = 0; i < 4; ++i) W(N * k + j, B + 4 * j + i) = jac[i];
    }
  }
  for (Eigen::Index i = 0; i < W.cols(); ++i) {
    const double n = W.col(i).norm();
    if (n > 0) W.col(i) /= n;
  }
  return W;
}

/// CompiledRobot::InverseDynamicsFn for `Robot`.
template <class Robot>
Eigen::VectorXd inverse_dynamics(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                                 const Eigen::VectorXd& phi) {
  using Vec = typename Robot::template JointVector<double>;
  const Eigen::Matrix<double, Robot::kNumStandard, 1> p = phi;
  Vec tau;
  Robot::inverse_dynamics(Vec(q), Vec(qd), Vec(qdd), p, tau);
  return tau;
}

/// CompiledRobot::StandardToBaseFn for `Robot`.
template <class Robot>
Eigen::VectorXd standard_to_base(const Eigen::VectorXd& phi) {
  const Eigen::Matrix<double, Robot::kNumStandard, 1> p = phi;
  Eigen::Matrix<double, Robot::kNumBase, 1> b;
  Robot::standard_to_base(p, b);
  return b;
}

/// CompiledRobot::BaseRegressorFn for `Robot`.
template <class Robot>
Eigen::MatrixXd base_regressor(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  using Vec = typename Robot::template JointVector<double>;
  Eigen::Matrix<double, Robot::kNumJoints, Robot::kNumBase> Yb;
  Robot::base_regressor(Vec(q), Vec(qd), Vec(qdd), Yb);
  return Yb;
}

/// CompiledRobot::MomentumResidualFn for `Robot`.
template <class Robot>
void momentum_residual(const ParameterTable& table, double gain, double dt, const Eigen::MatrixXd& q,
                       const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qd_friction, const Eigen::MatrixXd& tau,
                       Eigen::Index from, Eigen::Index to, Eigen::MatrixXd& r) {
  using Vec = typename Robot::template JointVector<double>;
  MomentumObserver<Robot> observer;
  const UpdateStatus configured = observer.configure(table, Vec::Constant(gain), dt);
  if (configured != UpdateStatus::ok)
    throw InputError(std::string("momentum observer: the parameter table or the gain is refused (") +
                     to_string(configured) + ")");
  for (Eigen::Index s = from; s < to; ++s) {
    const UpdateStatus st = observer.update(q.row(s).transpose(), qd.row(s).transpose(), qd_friction.row(s).transpose(),
                                            tau.row(s).transpose());
    if (st != UpdateStatus::ok)
      throw InputError("momentum observer: sample " + std::to_string(s + 1) + " refused (" + to_string(st) + ")");
    r.row(s) = observer.residual().transpose();
  }
}

/// CompiledRobot::DirectResidualFn for `Robot`.
template <class Robot>
void direct_residual(const ParameterTable& table, double gain, double dt, const Eigen::MatrixXd& q,
                     const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qd_friction, const Eigen::MatrixXd& qdd,
                     const Eigen::MatrixXd& tau, Eigen::Index from, Eigen::Index to, Eigen::MatrixXd& r) {
  using Vec = typename Robot::template JointVector<double>;
  DirectResidual<Robot> residual;
  const UpdateStatus configured = residual.configure(table, Vec::Constant(gain), dt);
  if (configured != UpdateStatus::ok)
    throw InputError(std::string("direct residual: the parameter table or the gain is refused (") +
                     to_string(configured) + ")");
  for (Eigen::Index s = from; s < to; ++s) {
    const UpdateStatus st = residual.update(q.row(s).transpose(), qd.row(s).transpose(), qd_friction.row(s).transpose(),
                                            qdd.row(s).transpose(), tau.row(s).transpose());
    if (st != UpdateStatus::ok)
      throw InputError("direct residual: sample " + std::to_string(s + 1) + " refused (" + to_string(st) + ")");
    r.row(s) = residual.residual().transpose();
  }
}

/// Registers the robot's identity, nominal standard parameters (the generated kNominalStandard),
/// excitation regressor, inverse dynamics, momentum observer and direct residual.
template <class Robot>
bool register_robot_model(const double (&nominal_standard)[Robot::kNumStandard]) {
  CompiledRobot c;
  c.name = Robot::kName;
  c.robot_id = Robot::kRobotId;
  c.num_joints = Robot::kNumJoints;
  c.num_standard = Robot::kNumStandard;
  c.num_base = Robot::kNumBase;
  c.nominal_standard.assign(nominal_standard, nominal_standard + Robot::kNumStandard);
  for (int j = 0; j < Robot::kNumJoints; ++j) c.prismatic.push_back(Robot::joint_prismatic(j));
  c.excitation_regressor = &excitation_regressor<Robot>;
  c.inverse_dynamics = &inverse_dynamics<Robot>;
  c.standard_to_base = &standard_to_base<Robot>;
  c.base_regressor = &base_regressor<Robot>;
  c.momentum_residual = &momentum_residual<Robot>;
  c.direct_residual = &direct_residual<Robot>;
  return register_robot(c);
}

/// Registers the identification models (TermSetModel) of every built term set: layout, generated
/// regressor and lib/ least squares of each model's size, the only per-robot code of identify (its
/// KF and RLS run at the model's run-time size: recursive_fit.hpp).
template <class Robot, int... I>
bool register_identification(std::integer_sequence<int, I...>) {
  CompiledRobot c;
  c.name = Robot::kName;
  ((c.models[I] = term_set_model_of<Robot, built_term_set(I)>()), ...);
  return register_robot(c);
}

}  // namespace dyncal::host
