// dyncal drive: the simulated drive behind a Modbus server (TCP or RTU).
#include <atomic>
#include <csignal>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/drive/drive_server.hpp"

namespace dyncal::app {
namespace {

std::atomic<bool> g_stop{false};
void on_signal(int) {
  g_stop.store(true);
}

struct DriveSettings {
  RobotOption robot;
  std::string scenario, table_file, ready_file, rtu;
  std::string listen = "127.0.0.1:1502";
  bool lockstep = false;
  int flash_delay_ms = 0;
  int ring_samples = host::SimulatedDrive::kRingCapacity;
  double watchdog_s = 2.0;
};

int run_drive(DriveSettings& s) {
  const auto robot = s.robot.load();
  const auto scenario = s.scenario.empty() ? host::default_scenario(robot) : host::load_scenario(s.scenario, robot);
  if (s.table_file.empty()) s.table_file = "dyncal-drive-" + robot.name + ".table";
  host::SimulatedDrive drive(robot, scenario, s.table_file);
  drive.lockstep = s.lockstep;
  drive.set_flash_chunk_delay(s.flash_delay_ms);
  drive.set_ring_capacity(s.ring_samples);
  std::cout << "dyncal drive: " << robot.name << ", " << (s.lockstep ? "lockstep" : "real-time") << ", "
            << drive.startup_note() << std::endl;
  host::DriveServerOptions o;
  o.ready_file = s.ready_file;
  o.watchdog_s = s.watchdog_s;
  if (!s.rtu.empty()) {
    o.rtu_device = s.rtu;
  } else {
    const size_t colon = s.listen.rfind(':');
    if (colon == std::string::npos) throw host::InputError("--tcp wants HOST:PORT");
    o.tcp_host = s.listen.substr(0, colon);
    o.tcp_port = std::stoi(s.listen.substr(colon + 1));
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  host::serve_drive(drive, o, g_stop);
  std::cout << "dyncal drive: stopped" << std::endl;
  return 0;
}

}  // namespace

void add_drive_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<DriveSettings>();
  s->robot.default_robot = true;
  auto* cmd = app.add_subcommand("drive", "run the simulated drive of a robot (Modbus server)");
  s->robot.add_to(cmd, "robot (robots/<name>/; robots/default.txt names the default)");
  cmd->add_option("--scenario", s->scenario, "scenario JSON: friction models, effects, noise (docs/modbus.md)");
  cmd->add_option("--tcp", s->listen, "serve Modbus TCP on HOST:PORT (port 0: any free port)")->capture_default_str();
  cmd->add_option("--rtu", s->rtu, "serve Modbus RTU on this serial device instead (e.g. a socat pty)");
  cmd->add_option("--table", s->table_file, "the simulated flash file (default dyncal-drive-<robot>.table)");
  cmd->add_option("--ready-file", s->ready_file, "write the drive's URI here once it serves requests");
  cmd->add_flag("--lockstep", s->lockstep, "virtual time: advance only as fast as the host reads samples");
  cmd->add_option("--watchdog", s->watchdog_s,
                  "stop a playing trajectory when no request arrives for this long [s] (0: off)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  cmd->add_option("--ring-samples", s->ring_samples,
                  "samples the drive's ring buffer holds (a smaller buffer overruns sooner in real time)")
      ->check(CLI::Range(1, host::SimulatedDrive::kRingCapacity))
      ->capture_default_str();
  cmd->add_option("--flash-delay-ms", s->flash_delay_ms, "sleep per 64 bytes written to flash (tests)");
  cmd->callback([&run, s] { run = [s] { return run_drive(*s); }; });
}

}  // namespace dyncal::app
