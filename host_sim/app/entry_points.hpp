#pragma once
// The programs' entry points, declared apart from commands.hpp so that each main() compiles
// without CLI11 and the host headers (it is compiled once per program).

namespace dyncal::app {

/// The dyncal program: every subcommand (commands.hpp, add_commands). Returns the exit code.
int run_dyncal(int argc, char** argv);
/// The dyncal-survey program: the survey study (add_survey_command). Returns the exit code.
int run_dyncal_survey(int argc, char** argv);

}  // namespace dyncal::app
