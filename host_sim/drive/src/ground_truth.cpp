#include "dyncal_host/drive/ground_truth.hpp"

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"

namespace dyncal::host {
namespace {

using Robot = dyncal::generated::er20::Robot;
namespace g = dyncal::generated::er20;

template <unsigned Terms>
std::vector<TrueParameter> truth(const Scenario& s) {
  using Model = IdentificationModel<Robot, Terms>;
  Eigen::Matrix<double, Robot::kNumStandard, 1> phi;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = g::kNominalStandard[i];
  Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
  g::standard_to_base(phi, phi_b);
  for (int j = 0; j < Robot::kNumJoints; ++j) {
    const bool own_column = Model::has_column(term::rotor_inertia, j);
    if (!Robot::rotor_inertia_separate(j)) {
      phi_b[Robot::rotor_inertia_absorbed_into(j)] +=
          g::kRotorInertiaAbsorbedCoefficient[j] * s.effects[j].rotor_inertia;
    } else if (!own_column && s.effects[j].rotor_inertia != 0) {
      throw InputError("joint " + std::to_string(j + 1) + " has rotor inertia the model does not declare");
    }
  }
  std::vector<TrueParameter> out;
  for (int i = 0; i < Model::kNumParams; ++i) {
    const ParamInfo info = Model::info(i);
    TrueParameter p;
    if (info.kind == ParamKind::base) {
      p.name = Robot::base_param_name(info.base_index);
      p.value = phi_b[info.base_index];
    } else {
      const int j = info.joint - 1;
      p.name = std::string(term_name(info.term)) + std::to_string(info.joint);
      switch (info.term) {
        case term::coulomb:
          p.value = s.friction[j].Fc;
          break;
        case term::viscous:
          p.value = s.friction[j].beta;
          break;
        case term::power:
          p.value = s.friction[j].fp;
          break;
        case term::rotor_inertia:
          p.value = s.effects[j].rotor_inertia;
          break;
        case term::offset:
          p.value = s.effects[j].offset;
          break;
        default:
          p.value = 0;
      }
    }
    out.push_back(p);
  }
  return out;
}

template <unsigned Terms>
struct Truth {
  static std::vector<TrueParameter> run(const Scenario& s) { return truth<Terms>(s); }
};

}  // namespace

std::vector<TrueParameter> true_parameters(const Scenario& s, unsigned terms) {
  return with_term_set<Truth>(terms, s);
}

}  // namespace dyncal::host
