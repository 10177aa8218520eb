#pragma once
// A model validated on logs it was not fitted to: the identified parameters (a parameter file, or
// identify's own result) predict the torque of another log, through the same filtering and
// regressor as identification; per-joint RMS, R^2 and e_T_abs of the prediction error.

#include <Eigen/Core>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/stacked_data.hpp"

namespace dyncal::host {

/// Identified parameters of one robot and model, in the model's parameter order.
struct ParameterSet {
  std::string robot, model, source;
  unsigned terms = 0;                ///< dyncal::term bits of `model`
  std::vector<ModelEffect> effects;  ///< effect terms of `model` after the compiled ones (model_effects.hpp)
  std::vector<CoupledMotor> motors;  ///< coupled motors of `model` (their terms are the compiled ones)
  bool friction_per_motor = false;   ///< "friction_per": "motor" (robot.json's coupling modelled) or "joint"
  std::vector<std::string> names;    ///< the compiled robot's parameter names for the terms, then the effects'
  Eigen::VectorXd values;
  /// Standard deviation of each value as identify reported it (NaN where the file gives none or the
  /// parameter was not determined); empty when the values are not an identification's.
  Eigen::VectorXd stdev;
  /// Each link's consistent inertials (identify --method pcls; file key "links"), empty when the set
  /// has none (other methods: the base parameters do not determine them).
  std::vector<LinkInertial> links;
  /// A set identified from motor currents (file key "torque_constants"): each motor's torque
  /// constant [Nm/A] the logs were converted with, its std [Nm/A] (NaN: a nominal value without
  /// one, robot.json's) and where they come from; empty for a set identified from joint torques.
  /// Logs of currents the set is applied to are converted with the same constants (payload).
  Eigen::VectorXd torque_constants, torque_constants_std;
  std::string torque_constants_source;
};

/// Reads a `dyncal identify --params` file (docs/cli.md). Throws InputError with the file and what
/// is wrong: not JSON, not a dyncal parameter file, robot or model missing, a robot not compiled into
/// this build, a model not built, a wrong parameter count, a name that is not the model's parameter
/// at that place, a value that is not a finite number.
ParameterSet read_parameter_file(const std::string& path);

/// The parameter file of `p` (docs/cli.md "--params schema"; read_parameter_file reads it): format,
/// version, robot, model, `method`, friction_per, params [{name, value, std}] (std only when the set
/// has them; null where not determined), links [{link, mass, com, inertia_about_com}] when it has them,
/// torque_constants {source, values, std} when the set has them.
nlohmann::json parameter_file_json(const ParameterSet& p, const std::string& method);

/// A parameter file's "torque_constants" of `p` (it has them): {source, values [Nm/A], std (null where
/// none)}.
nlohmann::json torque_constants_json(const ParameterSet& p);

/// [{link, mass, com, inertia_about_com, pseudo_inertia_min_eigenvalue}]: the "links" of a report
/// and of a parameter file (read_parameter_file reads the latter back).
nlohmann::json link_inertials_json(const std::vector<LinkInertial>& links);

/// The parameters identify reports (IdentifyResult::params) as a set.
ParameterSet parameter_set(const IdentifyResult& r);

/// Per-joint metrics of a prediction: y and prediction stacked (row s * N + j), rows whose
/// prediction is NaN skipped; e_T_abs and e_T_abs_std: mean and std of |error| / tau_max.
std::vector<JointMetrics> torque_metrics(const Eigen::VectorXd& y, const Eigen::VectorXd& prediction, int N,
                                         const Eigen::VectorXd& tau_max);

/// As above with the prediction made sample by sample instead of stored (no (S N) vector):
/// predicted(s, j) says whether row s * N + j has a prediction, prediction(s) computes sample s's N
/// predicted torques [Nm] (called once per sample with a predicted row, the pointer read before the
/// next call). The same sums in the same order as above: the same figures, bit for bit.
std::vector<JointMetrics> torque_metrics(const Eigen::VectorXd& y, int N, const Eigen::VectorXd& tau_max,
                                         const std::function<bool(Eigen::Index s, int j)>& predicted,
                                         const std::function<const double*(Eigen::Index s)>& prediction);

/// `options` for preparing a log that `params` predict (prepare_stacked): the set's terms, effects,
/// coupled motors and friction per motor or per joint. Throws InputError: params for another robot.
IdentifyOptions prediction_options(const RobotDescription& robot, IdentifyOptions options, const ParameterSet& params);

/// The torque (S N) [Nm] `params` predict on data prepared with prediction_options: W phi, or
/// [W E] phi with effect terms. Throws InputError if the data's parameters are not the set's.
Eigen::VectorXd predicted_torque(const StackedData& d, const ParameterSet& params);

/// The torque of `log` predicted by `params` (every sample, none fitted): log prepared as identify
/// prepares it with `options` (filter, cut-off, decimation; terms and friction per motor or per joint
/// taken from params), tau_hat = W phi, or [W E] phi with effect terms (effect_model.hpp).
/// Throws InputError: params for another robot than `robot`, and whatever prepare_stacked throws.
LogPrediction predict(const RobotDescription& robot, const JointLog& log, IdentifyOptions options,
                      const ParameterSet& params);

/// A log's torque and its prediction, sample by sample, for plots (report pages).
struct TorqueTrace {
  Eigen::VectorXd t;                    ///< S kept samples' times [s]
  Eigen::MatrixXd measured, predicted;  ///< S x N [Nm]; predicted NaN where the model predicts nothing
};

/// The torque of `log` and its prediction by `params`, prepared exactly as predict() prepares it (the
/// same samples, filter and decimation, so the figures predict() reports are these samples'). Throws
/// as predict().
TorqueTrace predicted_trace(const RobotDescription& robot, const JointLog& log, IdentifyOptions options,
                            const ParameterSet& params);

}  // namespace dyncal::host
