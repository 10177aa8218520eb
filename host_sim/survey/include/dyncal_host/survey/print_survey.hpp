#pragma once
// The survey study's tables beside the published ones (dyncal survey).

#include <iosfwd>
#include <nlohmann/json.hpp>

namespace dyncal::host::survey {

/// Prints our Tables 5, 6, 8, 9 and 11 next to the published ones (`published`: the data file
/// robots/er20/survey_published.json).
void print_survey(std::ostream& out, const nlohmann::json& result, const nlohmann::json& published);

}  // namespace dyncal::host::survey
