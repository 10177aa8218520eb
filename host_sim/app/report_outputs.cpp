// --report, --html and the gate of a reporting command (report_outputs.hpp).
#include "report_outputs.hpp"

#include <iostream>

#include "dyncal_host/common/output_file.hpp"
#include "dyncal_host/report/input_digest.hpp"
#include "dyncal_host/report/report_page.hpp"
#include "options.hpp"

namespace dyncal::app {
namespace {

std::string& stored_command_line() {
  static std::string line;
  return line;
}

std::string shell_quoted(const std::string& a) {
  if (!a.empty() && a.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,+@%") ==
                        std::string::npos)
    return a;
  std::string out = "'";
  for (const char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

const std::string& command_line() {
  return stored_command_line();
}

void set_command_line(int argc, char** argv) {
  std::string line = "dyncal";
  for (int i = 1; i < argc; ++i) line += " " + shell_quoted(argv[i]);
  stored_command_line() = line;
}

void add_report_options(CLI::App* cmd, ReportOutputs& o, const std::string& command, const std::string& report_help) {
  o.command = command;
  cmd->add_option("--report", o.report, report_help);
  cmd->add_option("--html", o.html,
                  "write a self-contained HTML page of the report: plots, intervals, CAD values, notes "
                  "(docs/report.md)");
  cmd->add_option("--gate", o.gate_file,
                  "gate file (YAML or JSON, a section per command): thresholds the report must meet; exit 1 "
                  "with the failed items when one is not met (docs/gates.md)");
  cmd->add_option("--require", o.require,
                  "a gate item KEY=VALUE (or KEY=V1,V2,... per joint), added to --gate's (docs/gates.md); "
                  "repeatable");
}

void prepare_report_outputs(ReportOutputs& o) {
  o.gate = host::read_gate(o.command, o.gate_file, o.require);
  check_outputs({{o.report, "report"}, {o.html, "HTML page"}});
}

int finish_report(const ReportOutputs& o, nlohmann::json report, const std::vector<std::string>& inputs) {
  report["command_line"] = command_line();
  if (!inputs.empty()) report["inputs"] = host::input_digests(inputs);
  int rc = 0;
  if (!o.gate.empty()) {
    const host::GateResult g = host::evaluate_gate(o.gate, report);
    report["gate"] = host::gate_json(g);
    std::cout << host::gate_text(g);
    rc = g.passed ? 0 : 1;
  }
  if (!o.report.empty()) write_json_file(o.report, report, "report");
  if (!o.html.empty()) {
    host::write_output_file(o.html, host::report_page(o.command, report), "HTML page");
    std::cout << "page: " << o.html << "\n";
  }
  return rc;
}

}  // namespace dyncal::app
