#pragma once
// The dyncal subcommands, one file each. Each add_*_command adds its subcommand to the app; when the
// user chooses it, its parse callback sets `run` to the action, which main() then calls. Actions
// throw InputError on bad input (main prints it on one line, exit 2) and return the exit code.

#include <CLI/CLI.hpp>
#include <functional>
#include <initializer_list>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "options.hpp"

namespace dyncal::app {

using Action = std::function<int()>;

void add_identify_command(CLI::App& app, Action& run);
void add_diagnose_command(CLI::App& app, Action& run);
void add_excite_command(CLI::App& app, Action& run);
/// The survey study itself, run in-process: the `survey` subcommand of the program dyncal-survey.
void add_survey_command(CLI::App& app, Action& run);
/// dyncal's `survey`: hands its arguments to the program dyncal-survey beside the running program
/// (execv; the study and its methods typed on the study's arm are compiled into that program alone, so that
/// building `dyncal` does not compile them). Throws InputError (one line) when that program is not
/// there or cannot be run.
void add_survey_launcher(CLI::App& app, Action& run);
void add_drive_command(CLI::App& app, Action& run);
void add_calibrate_command(CLI::App& app, Action& run);
void add_table_command(CLI::App& app, Action& run);
void add_flash_command(CLI::App& app, Action& run);
void add_registers_command(CLI::App& app, Action& run);
void add_robot_command(CLI::App& app, Action& run);
void add_predict_command(CLI::App& app, Action& run);
void add_payload_command(CLI::App& app, Action& run);
void add_export_command(CLI::App& app, Action& run);
void add_monitor_command(CLI::App& app, Action& run);
/// Adds every subcommand above but add_survey_command to `app` (the dyncal program's, and the Python
/// module's; the module has no `survey`: it runs commands with --report, which the study lacks).
void add_commands(CLI::App& app, Action& run);
/// A program's command line: a CLI::App with the subcommands `add` adds (one of them required),
/// argv parsed into it and the chosen action run. A parse error is CLI11's message (exit 2, 0 for
/// --help); InputError is one line "dyncal: error: ..." (exit 2); any other exception one line
/// "dyncal: internal error: ..." (exit 1). The main() of dyncal and of dyncal-survey.
int run_cli(void (*add)(CLI::App&, Action&), int argc, char** argv);
/// `survey`'s one-line help, as dyncal lists it and dyncal-survey prints it.
inline constexpr const char* kSurveyHelp =
    "reproduce the survey's simulation study (Sec. 6: Tables 5, 6, 8-12, Fig. 4) next to its numbers";

/// Runs codegen/import_urdf.py (the URDF work: import, check, export; orocos-kdl checks) with `args`
/// under the Debian python3; its messages go straight to our stdout/stderr. Returns its exit code;
/// throws InputError when it cannot be run.
int run_urdf_tool(const std::vector<std::string>& args);

}  // namespace dyncal::app
