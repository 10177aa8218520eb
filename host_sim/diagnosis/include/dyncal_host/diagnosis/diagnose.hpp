#pragma once
// `dyncal diagnose`: fit the declared model, then test a library of candidate effects against the
// residual, add the significant ones greedily (validation error and BIC), and report before/after.

#include <nlohmann/json.hpp>
#include <optional>
#include <ostream>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/diagnosis/diagnose_result.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"

namespace dyncal::host {

/// Runs the diagnosis. Throws InputError on bad input (too few samples, a joint that does not
/// move, constant velocity on every joint, a method other than wls or ols).
DiagnoseResult diagnose(const RobotDescription& robot, const JointLog& log, const DiagnoseOptions& options);

void print_diagnose_report(std::ostream& out, const DiagnoseResult& r);

/// Writes SVG plots with gnuplot into `dir` (created): per joint, residual vs velocity, residual vs
/// position, residual spectrum over the joint angle, measured and predicted torque before/after.
/// Returns the files written. Throws InputError when gnuplot is missing or fails.
std::vector<std::string> write_diagnose_plots(const DiagnoseResult& r, const std::string& dir);

/// The effect as a model term (identify's --model vocabulary); none for drift and a torque delay.
std::optional<ModelEffect> model_effect(const DiagnosedEffect& e);

/// The declared model's parameter set (`declared`: the identify fit the diagnosis started from, its
/// names the diagnosis's declared_names) with the diagnosis's re-estimated declared parameters and
/// its effects appended as effect terms (model_effect; drift, a torque delay and a shape, which no
/// table term holds, skipped and named in *skipped): what a drive table of the diagnosed model
/// holds (parameter_table). Throws
/// InputError when the counts differ.
ParameterSet diagnosed_parameter_set(const ParameterSet& declared, const DiagnoseResult& r,
                                     std::vector<std::string>* skipped);
nlohmann::json diagnose_report_json(const DiagnoseResult& r);

}  // namespace dyncal::host
