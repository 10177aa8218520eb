#pragma once
// TermSetModel of IdentificationModel<Robot, Terms>: its layout and the generated regressor.
// Included only by the robots' translation units (register_robot.hpp).

#include "dyncal/identification_model.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

/// The TermSetModel of IdentificationModel<Robot, Terms>.
template <class Robot, unsigned Terms>
TermSetModel term_set_model_of() {
  using Model = IdentificationModel<Robot, Terms>;
  constexpr int N = Robot::kNumJoints, P = Model::kNumParams;
  using Vec = Eigen::Matrix<double, N, 1>;
  TermSetModel m;
  m.terms = Terms;
  m.num_joints = N;
  m.num_params = P;
  m.num_base = Robot::kNumBase;
  for (int i = 0; i < P; ++i) {
    const ParamInfo info = Model::info(i);
    m.info.push_back(info);
    m.names.push_back(info.kind == ParamKind::base ? std::string(Robot::base_param_name(info.base_index))
                                                   : std::string(term_name(info.term)) + std::to_string(info.joint));
  }
  for (int j = 0; j < N; ++j) {
    m.rotor_inertia_separate.push_back(Robot::rotor_inertia_separate(j) ? 1 : 0);
    m.rotor_inertia_absorbed_into.push_back(Robot::rotor_inertia_absorbed_into(j));
  }
  m.regressor = [](const double* q, const double* qd, const double* qdd, double* K) {
    typename Model::template Regressor<double> k;
    Model::regressor(Vec(Eigen::Map<const Vec>(q)), Vec(Eigen::Map<const Vec>(qd)), Vec(Eigen::Map<const Vec>(qdd)),
                     Vec(Vec::Zero()), k);
    Eigen::Map<Eigen::Matrix<double, N, P>> out(K);
    out = k;
  };
  return m;
}

}  // namespace dyncal::host
