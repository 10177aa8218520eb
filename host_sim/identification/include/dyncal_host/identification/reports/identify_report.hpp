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

/// The `--params` JSON parameter table (schema in docs/cli.md).
nlohmann::json parameter_table_json(const IdentifyResult& r);

}  // namespace dyncal::host
