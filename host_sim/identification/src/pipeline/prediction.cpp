#include "dyncal_host/identification/pipeline/prediction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {

IdentifyOptions prediction_options(const RobotDescription& robot, IdentifyOptions options, const ParameterSet& params) {
  if (params.robot != robot.name)
    throw InputError(params.source + ": parameters are for robot '" + params.robot + "', not '" + robot.name + "'");
  options.terms = params.terms;
  options.effects = params.effects;
  options.motors = params.motors;
  options.friction_per_joint = !params.friction_per_motor;
  options.load_regressor = false;
  return options;
}

Eigen::VectorXd predicted_torque(const StackedData& d, const ParameterSet& params) {
  std::vector<std::string> names = d.names;
  for (const ModelEffect& e : params.effects)
    for (const std::string& n : effect_param_names(e)) names.push_back(n);
  if (names != params.names)
    throw InputError(params.source + ": parameter names differ from robot '" + params.robot + "' with model '" +
                     params.model + "'");
  return params.effects.empty()
             ? Eigen::VectorXd(d.W * params.values)
             : Eigen::VectorXd(model_design(d, params.effects, params.values, params.tau_model_reference) *
                               params.values);
}

LogPrediction predict(const RobotDescription& robot, const JointLog& log, IdentifyOptions options,
                      const ParameterSet& params) {
  const StackedData d = prepare_stacked(robot, log, prediction_options(robot, std::move(options), params));
  LogPrediction p;
  p.source = log.source;
  p.samples = static_cast<long>(d.t.size());
  p.notes = d.notes;
  p.joints = torque_metrics(d.y, predicted_torque(d, params), robot.num_joints, robot.tau_max);
  return p;
}

TorqueTrace predicted_trace(const RobotDescription& robot, const JointLog& log, IdentifyOptions options,
                            const ParameterSet& params) {
  const StackedData d = prepare_stacked(robot, log, prediction_options(robot, std::move(options), params));
  const Eigen::VectorXd prediction = predicted_torque(d, params);
  const Eigen::Index S = d.t.size(), N = robot.num_joints;
  TorqueTrace trace{d.t, Eigen::MatrixXd(S, N), Eigen::MatrixXd(S, N)};
  for (Eigen::Index s = 0; s < S; ++s)
    for (Eigen::Index j = 0; j < N; ++j) {
      trace.measured(s, j) = d.y[s * N + j];
      trace.predicted(s, j) = prediction[s * N + j];
    }
  return trace;
}

}  // namespace dyncal::host
