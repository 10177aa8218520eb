#include "commands.hpp"

namespace dyncal::app {

void add_commands(CLI::App& app, Action& run) {
  for (auto add :
       {add_identify_command, add_predict_command, add_payload_command, add_monitor_command, add_diagnose_command,
        add_excite_command, add_survey_command, add_drive_command, add_calibrate_command, add_table_command,
        add_flash_command, add_registers_command, add_robot_command, add_export_command}) {
    add(app, run);
  }
}

}  // namespace dyncal::app
