// dyncal: the command-line tool. Each subcommand lives in its own file (commands.hpp).
#include <iostream>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"

int main(int argc, char** argv) {
  CLI::App app{"dyncal: dynamic calibration of serial robot arms (1 to 7 joints)"};
  app.require_subcommand(1);
  dyncal::app::Action run;
  dyncal::app::add_commands(app, run);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    return run ? run() : 0;
  } catch (const dyncal::host::InputError& e) {
    std::cerr << "dyncal: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "dyncal: internal error: " << e.what() << "\n";
    return 1;
  }
}
