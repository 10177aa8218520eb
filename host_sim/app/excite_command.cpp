// dyncal excite: excitation trajectory design (survey Sec. 4, Eq. 26, 27).
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/excitation/excitation.hpp"

namespace dyncal::app {
namespace {

struct ExciteSettings {
  RobotOption robot;
  host::ExciteOptions options;
  std::string out, criterion = "cond", model = "eq7";
};

void print_design(const host::RobotDescription& robot, const ExciteSettings& s, const host::ExciteResult& r) {
  const host::ExciteOptions& x = s.options;
  std::cout << std::fixed << std::setprecision(2) << "excitation for " << robot.name << ": Eq. 27, L = " << x.harmonics
            << ", f_f = " << x.f_f << " Hz, K of " << s.model << ", columns unit-scaled\n"
            << "cond(K): best of " << x.candidates << " random starts " << r.start_cond << " -> optimised " << r.cond
            << " (" << s.criterion << ", " << r.evaluations << " evaluations); log det " << r.logdet << "\n"
            << "joint   position   velocity   acceleration   (fraction of the limit)\n";
  for (int i = 0; i < robot.num_joints; ++i) {
    const auto k = static_cast<size_t>(i);
    std::cout << std::setw(5) << i + 1 << std::setw(11) << r.position_use[k] << std::setw(11) << r.velocity_use[k]
              << std::setw(15) << r.acceleration_use[k] << "\n";
  }
  std::cout << "written to " << s.out << "\n";
}

int run_excite(ExciteSettings& s) {
  check_outputs({{s.out, "trajectory"}});
  const auto robot = s.robot.load();
  s.options.criterion = s.criterion == "logdet" ? host::ExcitationCriterion::logdet : host::ExcitationCriterion::cond;
  s.options.model = s.model == "eq4" ? host::FrictionModel::eq4 : host::FrictionModel::eq7;
  const auto r = host::design_excitation(robot, s.options);
  nlohmann::json j = host::trajectory_to_json(robot, r.trajectory);
  j["design"] = {{"criterion", s.criterion},  {"model", s.model},           {"cond", r.cond},
                 {"logdet", r.logdet},        {"start_cond", r.start_cond}, {"evaluations", r.evaluations},
                 {"margin", s.options.margin}};
  write_json_file(s.out, j, "trajectory");
  print_design(robot, s, r);
  return 0;
}

}  // namespace

void add_excite_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<ExciteSettings>();
  host::ExciteOptions& x = s->options;
  s->robot.default_robot = true;
  auto* cmd = app.add_subcommand(
      "excite", "design an excitation trajectory (Fourier series, Eq. 27) minimising cond(K) (Eq. 26) or -log det");
  s->robot.add_to(cmd, "robot (robots/<name>/; robots/default.txt names the default)");
  cmd->add_option("--omega-f", x.f_f, "fundamental frequency [Hz]")->capture_default_str();
  cmd->add_option("--harmonics", x.harmonics, "L")->capture_default_str();
  cmd->add_option("--criterion", s->criterion, "cond | logdet")
      ->check(CLI::IsMember({"cond", "logdet"}))
      ->capture_default_str();
  cmd->add_option("--model", s->model, "K of eq7 (linear friction) or eq4 (Stribeck, at the robot file's values)")
      ->check(CLI::IsMember({"eq7", "eq4"}))
      ->capture_default_str();
  cmd->add_option("--margin", x.margin, "fraction of every limit the motion may use")->capture_default_str();
  cmd->add_option("--candidates", x.candidates, "random starts; the best is optimised")->capture_default_str();
  cmd->add_option("--evaluations", x.max_evaluations, "criterion evaluations")->capture_default_str();
  cmd->add_option("--seed", x.seed, "seed of the random starts")->capture_default_str();
  cmd->add_option("--out", s->out, "trajectory file to write (JSON; dyncal calibrate --trajectory)")->required();
  cmd->callback([&run, s] { run = [s] { return run_excite(*s); }; });
}

}  // namespace dyncal::app
