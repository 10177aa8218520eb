#pragma once
// The survey study's results against committed ones (dyncal survey --check).

#include <nlohmann/json.hpp>
#include <string>

namespace dyncal::host::survey {

/// Compares every index and parameter of `ours` with `reference` (solution times excepted):
/// |a - b| <= relative_tolerance * max(|a|, |b|) + 1e-9. Returns the differences found (empty: equal).
std::string compare_survey(const nlohmann::json& ours, const nlohmann::json& reference, double relative_tolerance);

}  // namespace dyncal::host::survey
