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
#include "dyncal_host/model/parameter_set.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "dyncal_host/model/torque_metrics.hpp"

namespace dyncal::host {

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
