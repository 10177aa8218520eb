#include "dyncal_host/identification/pipeline/parameter_scales.hpp"

#include <cmath>
#include <string>

#include "dyncal/friction.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {

Eigen::VectorXd parameter_scales(const RobotDescription& robot, const TermSetModel& model) {
  const CompiledRobot& c = compiled_robot_for(robot);
  const Eigen::VectorXd nominal = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  const Eigen::VectorXd standard_scale = prior_std(nominal, 1.0);
  const Eigen::MatrixXd K = base_map(c);
  Eigen::VectorXd scale(model.num_params);
  for (int i = 0; i < model.num_base; ++i) scale[i] = (K.row(i).transpose().cwiseProduct(standard_scale)).norm();
  for (int i = model.num_base; i < model.num_params; ++i) {
    const ParamInfo& p = model.info[static_cast<size_t>(i)];
    const int j = p.joint - 1;
    const double tau = robot.tau_max[j], qd = robot.qd_max[j], qdd = robot.qdd_max[j];
    if (!(tau > 0.0) || !(qd > 0.0) || !(qdd > 0.0))
      throw InputError("robot " + robot.name + ", joint " + std::to_string(p.joint) +
                       ": tau_max, qd_max and qdd_max must be > 0 to judge its parameters");
    switch (p.term) {
      case term::viscous:
        scale[i] = tau / qd;
        break;
      case term::power:
        scale[i] = tau / std::cbrt(qd);
        break;
      case term::load:
        scale[i] = 1.0;
        break;
      case term::rotor_inertia:
        scale[i] = tau / qdd;
        break;
      default:  // Coulomb, offset
        scale[i] = tau;
    }
  }
  return scale;
}

}  // namespace dyncal::host
