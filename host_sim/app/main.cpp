// dyncal: the command-line tool. Each subcommand lives in its own file (commands.hpp).
#include <iostream>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"

int main(int argc, char** argv) {
  CLI::App app{"dyncal: dynamic calibration of serial robot arms (1 to 7 joints)"};
  app.require_subcommand(1);
  dyncal::app::Action run;
  for (auto add :
       {dyncal::app::add_identify_command, dyncal::app::add_predict_command, dyncal::app::add_payload_command,
        dyncal::app::add_monitor_command, dyncal::app::add_diagnose_command, dyncal::app::add_excite_command,
        dyncal::app::add_survey_command, dyncal::app::add_drive_command, dyncal::app::add_calibrate_command,
        dyncal::app::add_table_command, dyncal::app::add_flash_command, dyncal::app::add_registers_command,
        dyncal::app::add_robot_command, dyncal::app::add_export_command}) {
    add(app, run);
  }
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
