#pragma once
// The page a person reads (dyncal COMMAND --html FILE, docs/report.md): one self-contained HTML file
// made from the command's JSON report, so that every number on it is the report's number.

#include <nlohmann/json.hpp>
#include <string>

namespace dyncal::host {

/// The HTML page of `report`, the JSON report of `command` (identify, predict, diagnose, payload,
/// monitor, calibrate). No script and no request: a Content-Security-Policy allows only inline
/// styles and data: images; the plots are gnuplot SVGs embedded as data: URIs (class "plot",
/// data-plot naming each). Sections follow what the report holds: the command line and inputs
/// with their SHA-256, the gate's verdict, per-joint figures, measured against predicted torque and
/// the residual's envelope over time per joint ("series"), parameters with their 95 % interval,
/// verdict and CAD value and a plot of their deviation from CAD, link inertials, effects found with
/// before/after, the payload's quantities, contacts on the time axis, notes. Every number printed
/// from the report carries data-path, the JSON pointer of the number it shows (%.6g, integers below 1e15 in full).
/// Throws InputError: gnuplot failed (gnuplot.hpp).
std::string report_page(const std::string& command, const nlohmann::json& report);

}  // namespace dyncal::host
