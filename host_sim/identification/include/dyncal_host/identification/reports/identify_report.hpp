#pragma once

#include <nlohmann/json.hpp>
#include <ostream>

#include "dyncal_host/identification/pipeline/identify.hpp"

namespace dyncal::host {

/// Human-readable report: header, per-joint validation table, parameters with std deviations.
void print_identify_report(std::ostream& out, const IdentifyResult& r);

/// One other log's prediction (identify --validate-on, dyncal predict) as a table.
void print_log_prediction(std::ostream& out, const LogPrediction& p);

/// Per-joint metrics as the report's "joints" array.
nlohmann::json joint_metrics_json(const std::vector<JointMetrics>& joints);

/// One other log's prediction: data, samples, joints (as the report's), notes.
nlohmann::json log_prediction_json(const LogPrediction& p);

/// The `--report` JSON document (schema in docs/cli.md).
nlohmann::json identify_report_json(const IdentifyResult& r);

/// Adds the robot's CAD values (robot.json's inertials, the compiled kNominalStandard) to an
/// identify report: "cad" to each base parameter (Gautier's map of the CAD standard parameters),
/// "cad_mass" [kg] and "cad_com" [m] to each link. The terms (friction, Ia, offsets) have none.
void add_cad_values(nlohmann::json& report, const std::string& robot);

/// The `--params` JSON parameter table (schema in docs/cli.md).
nlohmann::json parameter_table_json(const IdentifyResult& r);

}  // namespace dyncal::host
