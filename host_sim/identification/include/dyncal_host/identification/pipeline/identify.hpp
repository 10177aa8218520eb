#pragma once

#include <Eigen/Core>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/logs/joint_log.hpp"
#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/identify_result.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {

/// Identifies the model from `log` and validates it on data each fit never saw.
/// Throws InputError on bad options (see check in identify.cpp: filter order, cut-off below Nyquist
/// and above 2 / duration, folds >= 2 with blocks of at least one cut-off period, validate_last in
/// (0, 0.9] covering at least one cut-off period, mu in (0, 1], p0 > 0), too little data, a robot not compiled into
/// this build (compiled_robot.hpp) or a model not built (model_terms.hpp). Pass the log with
/// std::move when it is not needed afterwards: a uniform log is then processed without a copy.
IdentifyResult identify(const RobotDescription& robot, JointLog log, const IdentifyOptions& options);

/// Prepares `log` for the declared model options.terms (a built term set, model_terms.hpp) of
/// `robot` (a compiled robot, compiled_robot.hpp). Throws InputError.
StackedData prepare_stacked(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options);

}  // namespace dyncal::host
