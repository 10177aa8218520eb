// dyncal-survey: the survey's simulation study on the er20 (`dyncal survey` runs this program).
// Invoked as `dyncal-survey survey OPTIONS`; dyncal's launcher passes "dyncal" as argv[0], so that
// usage and help read `dyncal survey`.
#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"dyncal: dynamic calibration of serial robot arms (1 to 7 joints)"};
  app.require_subcommand(1);
  dyncal::app::Action run;
  dyncal::app::add_survey_command(app, run);
  return dyncal::app::run_cli(app, run, argc, argv);
}
