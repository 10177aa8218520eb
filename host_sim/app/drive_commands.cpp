#include "drive_commands.hpp"

#include <unistd.h>

#include <csignal>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibrate.hpp"
#include "dyncal_host/drive/drive_server.hpp"
#include "dyncal_host/excite.hpp"
#include "dyncal_host/identify.hpp"
#include "dyncal_host/identify_report.hpp"
#include "dyncal_host/input_error.hpp"
#include "dyncal_port/modbus_drive.hpp"

namespace {

using dyncal::host::InputError;
namespace mm = dyncal::modbus_map;

std::atomic<bool> g_stop{false};
void on_signal(int) {
  g_stop.store(true);
}

struct Settings {
  std::string robots_dir, robot = "er20", uri = "tcp://127.0.0.1:1502";
  // drive
  std::string scenario, table_file, ready_file, rtu;
  std::string listen = "127.0.0.1:1502";
  bool lockstep = false;
  int flash_delay_ms = 0;
  // calibrate
  dyncal::host::CalibrateOptions cal;
  std::string model = "eq7,rotor_inertia,offset", report, trajectory;
  bool no_flash = false, quiet = false;
  // flash
  std::string params;
};

std::unique_ptr<dyncal::linux_port::ModbusDrive> connect(const std::string& uri) {
  std::string error;
  auto d = dyncal::linux_port::ModbusDrive::connect(uri, &error);
  if (!d) throw InputError(error);
  return d;
}

int run_drive(Settings& s) {
  const auto robot = dyncal::host::load_robot(s.robots_dir, s.robot);
  const auto scenario =
      s.scenario.empty() ? dyncal::host::default_scenario(robot) : dyncal::host::load_scenario(s.scenario, robot);
  if (s.table_file.empty()) s.table_file = "dyncal-drive-" + robot.name + ".table";
  dyncal::host::SimulatedDrive drive(robot, scenario, s.table_file);
  drive.lockstep = s.lockstep;
  drive.flash_chunk_delay_ms = s.flash_delay_ms;
  std::cout << "dyncal drive: " << robot.name << ", " << (s.lockstep ? "lockstep" : "real-time") << ", "
            << drive.startup_note() << std::endl;
  dyncal::host::DriveServerOptions o;
  o.ready_file = s.ready_file;
  if (!s.rtu.empty()) {
    o.rtu_device = s.rtu;
  } else {
    const size_t colon = s.listen.rfind(':');
    if (colon == std::string::npos) throw InputError("--tcp wants HOST:PORT");
    o.tcp_host = s.listen.substr(0, colon);
    o.tcp_port = std::stoi(s.listen.substr(colon + 1));
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  dyncal::host::serve_drive(drive, o, g_stop);
  std::cout << "dyncal drive: stopped" << std::endl;
  return 0;
}

int run_calibrate(Settings& s) {
  const auto robot = dyncal::host::load_robot(s.robots_dir, s.robot);
  s.cal.uri = s.uri;
  s.cal.terms = dyncal::host::parse_model(s.model);
  s.cal.flash = !s.no_flash;
  s.cal.progress = !s.quiet && isatty(2);  // the bar redraws with \r: only on a terminal
  if (!s.trajectory.empty()) {
    std::ifstream in(s.trajectory);
    if (!in) throw InputError("cannot read '" + s.trajectory + "'");
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
      throw InputError(s.trajectory + ": invalid JSON: " + e.what());
    }
    s.cal.excitation = dyncal::host::trajectory_from_json(robot, j);
  }
  const auto r = dyncal::host::calibrate(robot, s.cal, std::cerr);
  dyncal::host::print_calibrate_report(std::cout, r);
  if (!s.report.empty()) {
    nlohmann::json j;
    j["batch"] = dyncal::host::identify_report_json(r.batch);
    j["samples"] = r.samples;
    j["lost"] = r.lost;
    j["samples_per_second"] = r.samples_per_second;
    j["trajectory_cond"] = r.trajectory_cond;
    j["params"] = nlohmann::json::array();
    for (size_t i = 0; i < r.names.size(); ++i) {
      j["params"].push_back(
          {{"name", r.names[i]}, {"batch", r.phi_batch[i]}, {"kf", r.phi_kf[i]}, {"rls", r.phi_rls[i]}});
    }
    j["joints"] = nlohmann::json::array();
    for (int k = 0; k < 6; ++k) {
      j["joints"].push_back({{"joint", k + 1},
                             {"verify_rms_batch", r.verify_batch.rms[k]},
                             {"verify_rms_kf", r.verify_kf.rms[k]},
                             {"verify_rms_rls", r.verify_rls.rms[k]},
                             {"drive_error_before", r.drive_error_before[k]},
                             {"drive_error_after", r.drive_error_after[k]}});
    }
    j["flashed"] = r.flashed;
    j["flash_message"] = r.flash_message;
    j["total_seconds"] = r.total_seconds;
    std::ofstream out(s.report);
    if (!out) throw InputError("cannot write '" + s.report + "'");
    out << j.dump(2) << "\n";
  }
  return r.flashed || s.no_flash ? 0 : 3;
}

int run_table(Settings& s) {
  auto d = connect(s.uri);
  dyncal::ParameterTable t;
  dyncal::TableStatus reason;
  const auto st = d->read(t, &reason);
  if (st == dyncal::port::PortStatus::transport_error) throw InputError("drive: " + d->error());
  if (st != dyncal::port::PortStatus::ok)
    throw InputError(std::string("the drive's table is invalid: ") + to_string(reason));
  std::cout << "active table: robot id 0x" << std::hex << std::setw(8) << std::setfill('0') << t.robot_id << std::dec
            << std::setfill(' ') << ", model " << dyncal::host::model_name(t.model_id) << " (id " << t.model_id << "), "
            << t.count << " parameters, CRC ok\n";
  for (int i = 0; i < t.count; ++i) std::cout << "  " << std::setw(3) << i + 1 << "  " << t.values[i] << "\n";
  return 0;
}

int run_flash(Settings& s) {
  std::ifstream in(s.params);
  if (!in) throw InputError("cannot read '" + s.params + "'");
  nlohmann::json j;
  try {
    in >> j;
  } catch (const nlohmann::json::exception& e) {
    throw InputError(s.params + ": invalid JSON: " + e.what());
  }
  if (j.value("format", "") != "dyncal-parameters") throw InputError(s.params + ": not a dyncal parameter file");
  auto d = connect(s.uri);
  dyncal::linux_port::DriveInfo info;
  if (!d->read_info(info)) throw InputError("drive: " + d->error());
  dyncal::ParameterTable t;
  t.robot_id = info.robot_id;
  if (j.value("robot", "") != s.robot) {
    throw InputError(s.params + ": parameters are for robot '" + j.value("robot", "") + "', not '" + s.robot + "'");
  }
  t.model_id = dyncal::host::parse_model(j.value("model", ""));
  const auto& p = j["params"];
  if (!p.is_array() || p.empty() || p.size() > dyncal::kTableMaxParams) throw InputError(s.params + ": bad 'params'");
  t.count = static_cast<std::uint16_t>(p.size());
  for (size_t i = 0; i < p.size(); ++i) t.values[i] = p[i]["value"].get<float>();
  dyncal::TableStatus reason = dyncal::TableStatus::ok;
  const auto st = d->write(t, &reason);
  if (st == dyncal::port::PortStatus::rejected) {
    std::cerr << "dyncal: the drive rejected the table: " << to_string(reason) << "; its active table is unchanged\n";
    return 3;
  }
  if (st != dyncal::port::PortStatus::ok) throw InputError("flash failed: " + d->error());
  std::cout << "flashed " << t.count << " parameters; read back and compared: identical\n";
  return 0;
}

int run_registers() {
  std::cout << "| name | bank | address | registers | type | unit | description |\n|---|---|---|---|---|---|---|\n";
  for (const auto& f : mm::kRegisterMap) {
    const char* type = f.type == mm::Type::u16   ? "u16"
                       : f.type == mm::Type::u32 ? "u32"
                       : f.type == mm::Type::f32 ? "f32"
                                                 : "bytes";
    std::cout << "| `" << f.name << "` | "
              << (f.bank == mm::Bank::input ? "input (04, read)" : "holding (03/06/16, read-write)") << " | "
              << f.address << " | " << f.words << " | " << type << " | " << f.unit << " | " << f.description << " |\n";
  }
  return 0;
}

}  // namespace

void add_drive_commands(CLI::App& app, std::function<int()>& run, const std::string& default_robots_dir) {
  auto s = std::make_shared<Settings>();
  s->robots_dir = default_robots_dir;

  auto* drive = app.add_subcommand("drive", "run the simulated er20 drive (Modbus server)");
  drive->add_option("--robot", s->robot, "robot (the simulated drive runs er20)")->capture_default_str();
  drive->add_option("--robots-dir", s->robots_dir, "directory holding the robot descriptions");
  drive->add_option("--scenario", s->scenario, "scenario JSON: friction models, effects, noise (docs/modbus.md)");
  drive->add_option("--tcp", s->listen, "serve Modbus TCP on HOST:PORT (port 0: any free port)")->capture_default_str();
  drive->add_option("--rtu", s->rtu, "serve Modbus RTU on this serial device instead (e.g. a socat pty)");
  drive->add_option("--table", s->table_file, "the simulated flash file (default dyncal-drive-<robot>.table)");
  drive->add_option("--ready-file", s->ready_file, "write the drive's URI here once it serves requests");
  drive->add_flag("--lockstep", s->lockstep, "virtual time: advance only as fast as the host reads samples");
  drive->add_option("--flash-delay-ms", s->flash_delay_ms, "sleep per 64 bytes written to flash (tests)");
  drive->callback([&run, s] { run = [s] { return run_drive(*s); }; });

  auto* cal = app.add_subcommand("calibrate", "excite the drive, identify online and in batch, flash, verify");
  cal->add_option("--drive", s->uri, "tcp://HOST:PORT or rtu:DEVICE")->capture_default_str();
  cal->add_option("--robot", s->robot)->capture_default_str();
  cal->add_option("--robots-dir", s->robots_dir);
  cal->add_option("--model", s->model, "identification model terms (as dyncal identify)")->capture_default_str();
  cal->add_option("--rate", s->cal.sample_rate_hz, "sample rate [Hz], 100..1000")->capture_default_str();
  cal->add_option("--omega-f", s->cal.f_f, "Fourier fundamental frequency [Hz] (Eq. 27)")->capture_default_str();
  cal->add_option("--harmonics", s->cal.harmonics, "L (Eq. 27)")->capture_default_str();
  cal->add_option("--periods", s->cal.periods, "excitation periods")->capture_default_str();
  cal->add_option("--verify-periods", s->cal.verify_periods, "periods of the fresh verification trajectory")
      ->capture_default_str();
  cal->add_option("--seed", s->cal.seed, "trajectory seed")->capture_default_str();
  cal->add_option("--trajectory", s->trajectory, "play this excitation (a dyncal excite file) instead of a random one");
  cal->add_option("--mu", s->cal.rls_mu, "RLS forgetting factor")->capture_default_str();
  cal->add_option("--min-speed", s->cal.identify.min_speed_fraction,
                  "fit only rows where |qd_j| >= this fraction of joint j's top speed (stiction)")
      ->capture_default_str();
  cal->add_flag("--no-flash", s->no_flash, "identify and verify, but leave the drive's table alone");
  cal->add_flag("--diagnose", s->cal.diagnose,
                "diagnose the residual (as dyncal diagnose) and flash the effects found with the table");
  cal->add_option("--save-log", s->cal.save_log,
                  "write the excitation log here (CSV, as dyncal identify --data reads)");
  cal->add_option("--fault-dir", s->cal.fault_dir,
                  "where a run the drive stops on a fault leaves the samples recorded before it")
      ->capture_default_str();
  cal->add_flag("--quiet", s->quiet, "no progress output");
  cal->add_option("--report", s->report, "write the report as JSON");
  cal->callback([&run, s] { run = [s] { return run_calibrate(*s); }; });

  auto* table = app.add_subcommand("table", "read and print the drive's active parameter table");
  table->add_option("--drive", s->uri)->capture_default_str();
  table->callback([&run, s] { run = [s] { return run_table(*s); }; });

  auto* flash = app.add_subcommand("flash", "flash a parameter file (dyncal identify --params) to the drive");
  flash->add_option("--drive", s->uri)->capture_default_str();
  flash->add_option("--robot", s->robot)->capture_default_str();
  flash->add_option("--params", s->params, "parameter JSON from dyncal identify --params")->required();
  flash->callback([&run, s] { run = [s] { return run_flash(*s); }; });

  auto* regs = app.add_subcommand("registers", "print the Modbus register map (Markdown)");
  regs->callback([&run] { run = [] { return run_registers(); }; });
}
