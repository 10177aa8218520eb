#pragma once

#include <nlohmann/json.hpp>
#include <ostream>

#include "dyncal_host/identification/identify.hpp"

namespace dyncal::host {

/// Human-readable report: header, per-joint validation table, parameters with std deviations.
void print_identify_report(std::ostream& out, const IdentifyResult& r);

/// The `--report` JSON document (schema in docs/cli.md).
nlohmann::json identify_report_json(const IdentifyResult& r);

/// The `--params` JSON parameter table (schema in docs/cli.md).
nlohmann::json parameter_table_json(const IdentifyResult& r);

}  // namespace dyncal::host
