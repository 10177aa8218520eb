#pragma once
// The outputs every reporting command shares (docs/report.md, docs/gates.md): --report (the JSON
// report), --html (the page made from it) and the gate (--gate FILE, --require KEY=VALUE) evaluated
// on it. Read before the work (paths and the gate checked first), finished after it.

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dyncal_host/report/gate.hpp"

namespace dyncal::app {

struct ReportOutputs {
  std::string command;  ///< identify, predict, diagnose, payload, monitor, calibrate
  std::string report, html, gate_file;
  std::vector<std::string> require;
  host::Gate gate;
  /// Whether the command must build its JSON report (for the file, the page or the gate).
  bool wanted() const { return !report.empty() || !html.empty() || !gate.empty(); }
  /// Whether the page is asked for: the command then adds what only the page draws ("series").
  bool page() const { return !html.empty(); }
};

/// Adds --report (with `report_help`), --html, --gate and --require to `cmd`.
void add_report_options(CLI::App* cmd, ReportOutputs& o, const std::string& command, const std::string& report_help);

/// Before the work: the gate read and checked (read_gate), the output paths checked (check_outputs).
/// Throws InputError.
void prepare_report_outputs(ReportOutputs& o);

/// After the work: the command line and, for `inputs`, their digests (input_digest.hpp) added to
/// `report`; the gate evaluated into report["gate"] and its verdict printed; the JSON report and the
/// page written. Returns 0, or 1 when the gate failed (after writing everything). Throws InputError.
int finish_report(const ReportOutputs& o, nlohmann::json report, const std::vector<std::string>& inputs = {});

/// The command line of this run, as the shell would quote it (set by run_cli).
const std::string& command_line();
void set_command_line(int argc, char** argv);

}  // namespace dyncal::app
