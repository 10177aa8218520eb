// dyncal robot import|check: a robot folder from a stock URDF, and its validation (docs/robots.md).
// The URDF work (parsing, merging fixed joints, re-expressing axes, the orocos-kdl check) is done by
// codegen/import_urdf.py with the Debian python3; this file runs it and adds the C++ side of `check`:
// the same robot.json through the tools' loader, and whether this build has compiled the robot.
#include <unistd.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <vector>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::app {
namespace {

using host::InputError;

constexpr double kKdlTolerance = 1e-9;

struct RobotSettings {
  std::string urdf, name, base, tip, robots_dir;
  bool force = false;
};

int run_import(const RobotSettings& s) {
  std::vector<std::string> args{"import", s.urdf, "--name", s.name, "--robots-dir", s.robots_dir};
  if (!s.base.empty()) args.insert(args.end(), {"--base", s.base});
  if (!s.tip.empty()) args.insert(args.end(), {"--tip", s.tip});
  if (s.force) args.push_back("--force");
  const int rc = run_urdf_tool(args);
  if (rc != 0) return rc;
  std::cout << s.name << ": next, build (compiles its model; docs/robots.md): scripts/build dyncal\n";
  return 0;
}

/// The compiled model (generated code, robot.json's inertials) against orocos-kdl's recursive
/// Newton-Euler on the folder's source URDF at 200 seeded random states: |tau - tau_kdl| <=
/// 1e-9 max(1, |tau_kdl|) on every joint. Prints the result; false (with one line on stderr) on a
/// mismatch.
bool compare_with_kdl(const RobotSettings& s, const host::CompiledRobot& c) {
  const std::string file =
      (std::filesystem::temp_directory_path() / ("dyncal-kdl-" + s.name + "-" + std::to_string(getpid()) + ".json"))
          .string();
  const int rc = run_urdf_tool({"samples", s.name, "--robots-dir", s.robots_dir, "--out", file});
  if (rc != 0) throw InputError("the KDL reference of " + s.name + " could not be computed");
  nlohmann::json j;
  try {
    j = read_json_file(file);
  } catch (...) {
    std::filesystem::remove(file);
    throw;
  }
  std::filesystem::remove(file);
  if (j["samples"].is_null()) {
    std::cout << "; KDL torques not comparable (mass off the chain)";
    return true;
  }
  const Eigen::VectorXd phi = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  double worst = 0;
  for (const auto& sample : j["samples"]) {
    const auto vec = [&](const char* key) {
      const auto v = sample.at(key).get<std::vector<double>>();
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
    };
    const Eigen::VectorXd tau_kdl = vec("tau");
    const Eigen::VectorXd tau = c.inverse_dynamics(vec("q"), vec("qd"), vec("qdd"), phi);
    for (int i = 0; i < c.num_joints; ++i)
      worst = std::max(worst, std::abs(tau[i] - tau_kdl[i]) / std::max(1.0, std::abs(tau_kdl[i])));
  }
  std::cout << "; compiled inverse dynamics vs KDL on " << j["urdf"].get<std::string>() << ": " << worst
            << " (relative, " << j["samples"].size() << " states)";
  if (worst <= kKdlTolerance) return true;
  std::cout << "\n";
  std::cerr << "dyncal robot check: " << s.name << ": the compiled model differs from KDL by " << worst
            << " (tolerance " << kKdlTolerance << "): rebuild, or re-import the URDF\n";
  return false;
}

int run_check(const RobotSettings& s) {
  // First the check every command runs when it loads the robot (load_checked_robot), so that the
  // first error is the only line and "valid" means the tools take it; then the schema, KDL and
  // URDF checks of the import tool.
  const auto names = host::compiled_robot_names();
  const bool compiled = std::find(names.begin(), names.end(), s.name) != names.end();
  host::RobotDescription robot =
      compiled ? host::load_checked_robot(s.robots_dir, s.name) : host::load_robot(s.robots_dir, s.name);
  const int rc = run_urdf_tool({"check", s.name, "--robots-dir", s.robots_dir});
  if (rc != 0) return rc;
  std::cout << s.name << ": the tools read robot.json (" << robot.num_joints << " joints)";
  if (!compiled) {
    std::cout << "; not compiled into this build yet: cmake --build --preset release\n";
    return 0;
  }
  const host::CompiledRobot& c = host::compiled_robot_for(robot);
  std::cout << "; compiled: " << c.num_base << " base parameters of " << c.num_standard << " standard";
  if (!compare_with_kdl(s, c)) return 2;
  if (robot.tau_max_derived) {
    std::cout << "; tau_max derived from the nominal model [Nm]:";
    for (int j = 0; j < robot.num_joints; ++j) std::cout << " " << robot.tau_max[j];
  }
  std::cout << "\n";
  return 0;
}

}  // namespace

void add_robot_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<RobotSettings>();
  s->robots_dir = host::default_robots_dir();
  auto* cmd = app.add_subcommand("robot", "add a robot from its URDF, or check a robot folder (docs/robots.md)");
  cmd->require_subcommand(1);
  auto* imp = cmd->add_subcommand("import", "write robots/NAME/ (robot.json, the URDFs) from a stock URDF");
  imp->add_option("urdf", s->urdf, "the maker's URDF")->required();
  imp->add_option("--name", s->name, "robot name: letters, digits and '_', a letter first")->required();
  imp->add_option("--base", s->base, "first link of the chain (default: the root, massless links skipped)");
  imp->add_option("--tip", s->tip, "last link of the chain (default: the only leaf)");
  imp->add_option("--robots-dir", s->robots_dir, "directory of the robot folders");
  imp->add_flag("--force", s->force, "replace an existing robots/NAME/robot.json");
  imp->callback([s, &run] { run = [s] { return run_import(*s); }; });
  auto* chk = cmd->add_subcommand("check", "validate robots/NAME/ (schema, KDL against the source URDF, build)");
  chk->add_option("name", s->name, "robot name")->required();
  chk->add_option("--robots-dir", s->robots_dir, "directory of the robot folders");
  chk->callback([s, &run] { run = [s] { return run_check(*s); }; });
}

}  // namespace dyncal::app
