#include "commands.hpp"

#include <unistd.h>

#include <iostream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/interrupt.hpp"
#include "dyncal_host/common/progress.hpp"
#include "entry_points.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {

void add_commands(CLI::App& app, Action& run) {
  for (auto add :
       {add_identify_command, add_predict_command, add_payload_command, add_monitor_command, add_diagnose_command,
        add_excite_command, add_survey_launcher, add_drive_command, add_calibrate_command, add_table_command,
        add_flash_command, add_registers_command, add_robot_command, add_export_command}) {
    add(app, run);
  }
}

int run_cli(void (*add)(CLI::App&, Action&), int argc, char** argv) {
  CLI::App app{"dyncal: dynamic calibration of serial robot arms (1 to 7 joints)"};
  app.require_subcommand(1);
  Action run;
  add(app, run);
  set_command_line(argc, argv);
  // Progress of the long commands on one updating line, on a terminal only (progress.hpp).
  if (isatty(STDERR_FILENO)) host::set_progress_sink(host::terminal_progress(std::cerr));
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    return run ? run() : 0;
  } catch (const host::Interrupted& e) {
    std::cerr << "dyncal: " << e.what() << "\n";
    return 128 + e.signal();
  } catch (const host::InputError& e) {
    std::cerr << "dyncal: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "dyncal: internal error: " << e.what() << "\n";
    return 1;
  }
}

int run_dyncal(int argc, char** argv) {
  return run_cli(add_commands, argc, argv);
}

}  // namespace dyncal::app
