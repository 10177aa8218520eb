// dyncal calibrate: excite a drive over Modbus, identify online and in batch, flash, verify.
#include <unistd.h>

#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/identification/reports/identify_report.hpp"
#include "dyncal_host/report/torque_series.hpp"
#include "report_outputs.hpp"

namespace dyncal::app {
namespace {

struct CalibrateSettings {
  RobotOption robot;
  std::string uri = "tcp://127.0.0.1:1502";
  host::CalibrateOptions options;
  std::string model = "eq7,rotor_inertia,offset", trajectory, stream = "auto";
  ReportOutputs out;
  bool no_flash = false, quiet = false;
};

int run_calibrate(CalibrateSettings& s) {
  prepare_report_outputs(s.out);
  const auto robot = s.robot.load();
  host::CalibrateOptions& o = s.options;
  o.uri = s.uri;
  o.terms = host::parse_model(s.model);
  o.flash = !s.no_flash;
  o.stream = host::parse_stream_mode(s.stream);
  o.progress = !s.quiet && isatty(2);  // the bar redraws with \r: only on a terminal
  o.keep_trace = s.out.page();         // the page draws the excitation's torque against the batch fit's
  if (!s.trajectory.empty()) o.excitation = host::trajectory_from_json(robot, read_json_file(s.trajectory));
  const auto r = host::calibrate(robot, o, std::cerr);
  host::print_calibrate_report(std::cout, r);
  const int rc = r.flashed || s.no_flash ? 0 : 3;
  if (!s.out.wanted()) return rc;
  nlohmann::json report = host::calibrate_report_json(r);
  host::add_cad_values(report["batch"], robot.name);
  if (s.out.page())
    report["batch"]["series"] = host::torque_series_json(r.trace.t, r.trace.measured, r.trace.predicted);
  const int gate =
      finish_report(s.out, std::move(report),
                    s.trajectory.empty() ? std::vector<std::string>{} : std::vector<std::string>{s.trajectory});
  return rc != 0 ? rc : gate;
}

}  // namespace

void add_calibrate_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<CalibrateSettings>();
  host::CalibrateOptions& o = s->options;
  s->robot.default_robot = true;
  auto* cmd = app.add_subcommand("calibrate", "excite the drive, identify online and in batch, flash, verify");
  cmd->add_option("--drive", s->uri, "tcp://HOST:PORT or rtu:DEVICE")->capture_default_str();
  s->robot.add_to(cmd, "robot (robots/<name>/; robots/default.txt names the default)");
  cmd->add_option("--model", s->model, "identification model terms (as dyncal identify)")->capture_default_str();
  cmd->add_option("--rate", o.sample_rate_hz, "sample rate [Hz], 100..1000")->capture_default_str();
  cmd->add_option("--omega-f", o.f_f, "Fourier fundamental frequency [Hz] (Eq. 27)")->capture_default_str();
  cmd->add_option("--harmonics", o.harmonics, "L (Eq. 27)")->capture_default_str();
  cmd->add_option("--periods", o.periods, "excitation periods")->capture_default_str();
  cmd->add_option("--verify-periods", o.verify_periods, "periods of the fresh verification trajectory")
      ->capture_default_str();
  cmd->add_option("--seed", o.seed, "trajectory seed")->capture_default_str();
  cmd->add_option("--trajectory", s->trajectory, "play this excitation (a dyncal excite file) instead of a random one");
  cmd->add_option("--mu", o.rls_mu, "RLS forgetting factor")->capture_default_str();
  cmd->add_option("--min-speed", o.identify.min_speed_fraction,
                  "fit only rows where |qd_j| >= this fraction of joint j's top speed (stiction)")
      ->capture_default_str();
  cmd->add_flag(
      "--friction-per-joint", o.identify.friction_per_joint,
      "batch fit: friction and rotor inertia per joint, leaving robot.json's coupled motors out (as identify)");
  cmd->add_flag("--no-flash", s->no_flash, "identify and verify, but leave the drive's table alone");
  cmd->add_flag("--diagnose", o.diagnose,
                "diagnose the residual (as dyncal diagnose) and flash the effects found with the table");
  cmd->add_option("--save-log", o.save_log, "write the excitation log here (CSV, as dyncal identify --data reads)");
  cmd->add_option("--save-law", o.save_law,
                  "write the excitation run's control law here (JSON, and the table active during it as .table "
                  "beside it): what identify --method iv --law needs for the --save-log log");
  cmd->add_option("--fault-dir", o.fault_dir,
                  "where a run the drive stops on a fault leaves the samples recorded before it")
      ->capture_default_str();
  cmd->add_option("--stream", s->stream,
                  "auto: each run live if the link carries it, else traced (the drive records the run, the host "
                  "uploads it); live; trace")
      ->capture_default_str();
  cmd->add_flag("--quiet", s->quiet, "no progress output");
  add_report_options(cmd, s->out, "calibrate", "write the report as JSON");
  cmd->callback([&run, s] { run = [s] { return run_calibrate(*s); }; });
}

}  // namespace dyncal::app
