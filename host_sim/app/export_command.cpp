// dyncal export urdf: the identified model written into the URDF the robot was imported from
// (docs/export.md). The URDF work is codegen/import_urdf.py's (urdf_export.py); this file gives it
// the identified inertials and terms and dyncal's own rigid-body torques at random states, which
// KDL's inverse dynamics of the written file must reproduce before it is written.
#include <unistd.h>

#include <Eigen/Core>
#include <filesystem>
#include <iostream>
#include <random>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/output_file.hpp"
#include "dyncal_host/common/temporary_folder.hpp"
#include "dyncal_host/identification/methods/inertial_parameters.hpp"
#include "dyncal_host/identification/pipeline/compiled_robot.hpp"
#include "dyncal_host/identification/reports/prediction.hpp"

namespace dyncal::app {
namespace {

using host::InputError;

/// Random states of the KDL check: q within the joint range, |qd| <= qd_max, |qdd| <= qdd_max.
constexpr int kCheckStates = 64;

struct ExportSettings {
  std::string params, out, robots_dir;
};

int run_export_urdf(const ExportSettings& s) {
  host::check_output_path(s.out, "URDF");  // before the work: a FIFO, a device, a folder, a missing folder
  const host::ParameterSet p = host::read_parameter_file(s.params);
  if (p.links.empty())
    throw InputError(s.params +
                     ": export urdf needs each link's inertials and the file has none: the base parameters do not "
                     "determine them; identify with --method pcls (physically consistent, Wensing et al.) writes them");
  const host::RobotDescription robot = host::load_checked_robot(s.robots_dir, p.robot);
  const host::CompiledRobot& c = host::compiled_robot(p.robot);
  const int n = c.num_joints;
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(c.num_standard);
  nlohmann::json links = nlohmann::json::array();
  for (const host::LinkInertial& l : p.links) {
    const std::array<double, 10> physical = {l.mass,       l.com[0],     l.com[1],     l.com[2],     l.inertia[0],
                                             l.inertia[1], l.inertia[2], l.inertia[3], l.inertia[4], l.inertia[5]};
    host::standard_from_physical(physical, phi.data() + 10 * (l.link - 1));
    links.push_back({{"mass", l.mass}, {"com", l.com}, {"inertia_about_com", l.inertia}});
  }
  // The links must be the file's rigid body: their base parameters are the file's (Gautier's map).
  const Eigen::VectorXd base = c.standard_to_base(phi);
  const Eigen::VectorXd file_base = p.values.head(c.num_base);
  const double scale = std::max(1e-12, file_base.cwiseAbs().maxCoeff());
  if ((base - file_base).cwiseAbs().maxCoeff() > 1e-6 * scale)
    throw InputError(s.params +
                     ": its links' inertials do not give its base parameters (the file was edited?): "
                     "nothing exported");
  nlohmann::json terms = nlohmann::json::array();
  for (Eigen::Index i = c.num_base; i < p.values.size(); ++i)
    terms.push_back({{"name", p.names[static_cast<size_t>(i)]}, {"value", p.values[i]}});
  nlohmann::json samples = nlohmann::json::array();
  std::mt19937_64 rng(44);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int k = 0; k < kCheckStates; ++k) {
    Eigen::VectorXd q(n), qd(n), qdd(n);
    for (int j = 0; j < n; ++j) {
      q[j] = robot.q_min[j] + 0.5 * (u(rng) + 1.0) * (robot.q_max[j] - robot.q_min[j]);
      qd[j] = u(rng) * robot.qd_max[j];
      qdd[j] = u(rng) * robot.qdd_max[j];
    }
    const Eigen::VectorXd tau = c.inverse_dynamics(q, qd, qdd, phi);
    auto list = [](const Eigen::VectorXd& v) { return std::vector<double>(v.data(), v.data() + v.size()); };
    samples.push_back({{"q", list(q)}, {"qd", list(qd)}, {"qdd", list(qdd)}, {"tau", list(tau)}});
  }
  const nlohmann::json input = {
      {"links", links},
      {"terms", terms},
      {"samples", samples},
      {"provenance",
       {{"params", std::filesystem::path(s.params).filename().string()}, {"robot", p.robot}, {"model", p.model}}}};
  // The tool writes and checks the URDF in a folder of our own; the user's --out is then written by
  // the host's one writer (output_file.hpp): all or nothing, a regular file or a new name only.
  const host::TemporaryFolder folder("dyncal-export");
  const std::string input_file = folder.path() + "/input.json", urdf_name = p.robot + ".urdf";
  write_json_file(input_file, input);
  const int rc = run_urdf_tool({"export", p.robot, "--robots-dir", s.robots_dir, "--input", input_file, "--out",
                                folder.path() + "/" + urdf_name});
  if (rc != 0) return rc;
  const std::string text = folder.read(urdf_name);
  host::write_output_file(s.out, text, "URDF");
  std::cout << p.robot << ": wrote " << s.out << "\n";
  return 0;
}

}  // namespace

void add_export_command(CLI::App& app, Action& run) {
  auto s = std::make_shared<ExportSettings>();
  s->robots_dir = host::default_robots_dir();
  auto* cmd = app.add_subcommand("export", "write the identified model out for other tools");
  cmd->require_subcommand(1);
  auto* urdf = cmd->add_subcommand(
      "urdf",
      "the URDF the robot was imported from with each link's inertial replaced by the identified one (--method "
      "pcls parameter file), friction in <dynamics>, the other terms in a <dyncal> element; written only when "
      "orocos-kdl's inverse dynamics of it reproduces dyncal's model (docs/export.md)");
  urdf->add_option("--params", s->params, "parameter file of identify --method pcls --params")->required();
  urdf->add_option("--out", s->out, "the URDF to write")->required();
  urdf->add_option("--robots-dir", s->robots_dir, "directory holding the robot descriptions");
  urdf->callback([&run, s] { run = [s] { return run_export_urdf(*s); }; });
}

}  // namespace dyncal::app
