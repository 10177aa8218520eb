// dyncal payload: the load on the last link identified from a log with it, the arm's calibrated
// parameters fixed (docs/payload.md).
#include <cmath>
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/payload/payload.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {
namespace {

struct PayloadSettings {
  LogOption log;
  host::IdentifyOptions options;
  std::string params, save_params, drive;
  ReportOutputs out;
  int periods = 2;
  double rate_hz = 500;
};

constexpr const char* kStandardNames[10] = {"XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M"};

/// --drive: the drive identifies the payload on a run of the default excitation with its active
/// table as the arm's model (command identify_payload, docs/payload.md "On the drive").
int run_drive_payload(const PayloadSettings& s) {
  const auto robot = s.log.robot.load();
  auto drive = connect_drive(s.drive);
  linux_port::DriveInfo info;
  if (drive->read_info(info) != port::PortStatus::ok) throw host::InputError("drive: " + drive->error());
  const host::CompiledRobot& compiled = host::compiled_robot_for(robot);
  if (info.robot_id != compiled.robot_id || info.num_joints != robot.num_joints)
    throw host::InputError("the drive at " + s.drive + " does not run robot '" + robot.name + "'");
  double cond = 0;
  const auto trajectory = host::default_excitation(robot, 0.1, 5, 20, 1, &cond);
  host::StreamRun run{"payload", s.periods, s.rate_hz, ".", true};
  std::cout << "payload on the drive: " << s.periods << " periods of the default excitation at " << s.rate_hz
            << " Hz, the drive's active table as the arm's model\n";
  host::stream_run(*drive, trajectory, run, &std::cout, nullptr, nullptr, {});
  linux_port::DrivePayload p;
  if (drive->read_payload(p) != port::PortStatus::ok) throw host::InputError("drive: " + drive->error());
  nlohmann::json params = nlohmann::json::array();
  std::cout << "  parameter        value          std\n";
  for (size_t i = 0; i < 10; ++i) {
    const bool shown = std::isfinite(p.value[i]);
    std::cout << "  " << std::left << std::setw(10) << kStandardNames[i] << std::right;
    if (shown)
      std::cout << std::setw(13) << std::setprecision(6) << p.value[i] << std::setw(13) << std::setprecision(2)
                << p.std[i] << "\n";
    else
      std::cout << "  not determined\n";
    params.push_back({{"name", kStandardNames[i]},
                      {"value", shown ? nlohmann::json(p.value[i]) : nlohmann::json(nullptr)},
                      {"std", shown ? nlohmann::json(p.std[i]) : nlohmann::json(nullptr)}});
  }
  const bool written = p.state == modbus_map::PayloadState::written;
  if (written) {
    std::cout << "  mass " << std::setprecision(6) << p.value[9] << " kg, centre of mass";
    for (size_t k = 6; k < 9; ++k)
      std::cout << " " << (std::isfinite(p.value[k]) ? std::to_string(p.value[k] / p.value[9]) : std::string("-"));
    std::cout << " m (last link's frame); written into the drive's active table\n";
  }
  nlohmann::json quantities = nlohmann::json::array();
  if (written)
    quantities.push_back({{"name", "mass"},
                          {"unit", "kg"},
                          {"value", p.value[9]},
                          {"std", std::isfinite(p.std[9]) ? nlohmann::json(p.std[9]) : nlohmann::json(nullptr)}});
  const int rc = s.out.wanted() ? finish_report(s.out, {{"robot", robot.name},
                                                        {"drive", s.drive},
                                                        {"state", written ? "written" : "not written"},
                                                        {"standard", params},
                                                        {"quantities", quantities}})
                                : 0;
  if (!written)
    throw host::InputError(
        "the run did not determine the payload's mass (no load on the arm, or too little "
        "motion): the drive's table is unchanged");
  return rc;
}

int run_payload(PayloadSettings& s) {
  prepare_report_outputs(s.out);
  check_outputs({{s.save_params, "parameters"}});
  if (!s.drive.empty()) {
    if (!s.log.data.empty() || !s.params.empty())
      throw host::InputError("--drive identifies on the drive with its own table: no --data or --params");
    return run_drive_payload(s);
  }
  if (s.log.data.empty() || s.params.empty())
    throw host::InputError("payload needs --data and --params (or --drive URI)");
  std::vector<std::string> time_shapes;  // a change over the identification log: not this log's
  const host::ParameterSet arm = host::without_time_shapes(host::read_parameter_file(s.params), &time_shapes);
  if (s.log.robot.name.empty()) s.log.robot.name = arm.robot;
  if (s.log.robot.name != arm.robot)
    throw host::InputError(s.params + ": parameters are for robot '" + arm.robot + "', not '" + s.log.robot.name + "'");
  auto robot = s.log.load_robot();
  std::vector<std::string> dropped = time_shapes;
  const bool currents = s.log.torque_from == "current";
  // Currents are converted with the constants the arm's set was identified with (a Kt error then
  // scales the load's torque only, and its std enters the payload's), robot.json's otherwise.
  if (currents && arm.torque_constants.size() == robot.num_joints) {
    robot.torque_constants = arm.torque_constants;
    dropped.push_back("currents converted with " + s.params + "'s torque constants (" + arm.torque_constants_source +
                      "), as the arm's parameters were");
  }
  const auto log = s.log.load_log(robot, &dropped);
  host::PayloadResult r = host::identify_payload(robot, log, arm, s.options, currents);
  r.notes.insert(r.notes.begin(), dropped.begin(), dropped.end());
  host::print_payload_report(std::cout, r);
  if (!s.save_params.empty()) {
    const host::ParameterSet loaded = host::with_payload(arm, robot, r.standard);
    write_json_file(s.save_params, host::loaded_parameter_file_json(loaded, r), "parameters");
    std::cout << "loaded model written to " << s.save_params << " (the arm's parameters with the payload on link "
              << r.link << ")\n";
  }
  if (!s.out.wanted()) return 0;
  std::vector<std::string> inputs = s.log.data;
  inputs.push_back(s.params);
  return finish_report(s.out, host::payload_report_json(r), inputs);
}

}  // namespace

void add_payload_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<PayloadSettings>();
  auto* cmd = app.add_subcommand("payload",
                                 "identify the load on the last link from a log with it, the arm's parameters fixed");
  s->log.add_to(cmd, false);
  cmd->add_option("--params", s->params, "the arm's parameter JSON (dyncal identify --params), without the load");
  cmd->add_option("--drive", s->drive,
                  "instead of a log: have the drive at this URI (tcp://HOST:PORT, rtu:DEVICE) identify the payload on "
                  "a run of the default excitation with its active table as the arm's model, and write it into that "
                  "table (docs/payload.md \"On the drive\")");
  cmd->add_option("--periods", s->periods, "--drive: excitation periods to play")->check(CLI::Range(1, 100));
  cmd->add_option("--rate", s->rate_hz, "--drive: recording rate [Hz]")->check(CLI::Range(100.0, 1000.0));
  cmd->add_option("--cutoff", s->options.cutoff_hz, "zero-phase Butterworth cut-off [Hz] (as identify's)")
      ->capture_default_str();
  cmd->add_option("--filter-order", s->options.filter_order, "Butterworth order (even)")->capture_default_str();
  add_report_options(cmd, s->out, "payload", "write the payload and its verdicts as JSON");
  cmd->add_option("--save-params", s->save_params,
                  "write the loaded arm's parameter file (predict, flash, table and diagnose take it)");
  cmd->callback([&run, s] { run = [s] { return run_payload(*s); }; });
}

}  // namespace dyncal::app
