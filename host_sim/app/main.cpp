// dyncal: the command-line tool. Each subcommand lives in its own file (commands.hpp).
#include "commands.hpp"

int main(int argc, char** argv) {
  CLI::App app{"dyncal: dynamic calibration of serial robot arms (1 to 7 joints)"};
  app.require_subcommand(1);
  dyncal::app::Action run;
  dyncal::app::add_commands(app, run);
  return dyncal::app::run_cli(app, run, argc, argv);
}
