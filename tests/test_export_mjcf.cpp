// dyncal export mjcf (issue 72): an arm identified with pcls from a simulated log is written as
// MJCF, and MuJoCo itself (Debian's libmujoco-dev, called here directly, not through dyncal's
// wrapper) compiles the file: its inverse dynamics at 200 seeded random states must equal the
// compiled model's torques with the parameter file's values -- the rigid body of the file's links,
// plus Ia qdd + Fv qd per joint -- and its joints must carry the file's Coulomb friction as
// frictionloss (a constraint in MuJoCo, so compared as a value).
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <filesystem>

#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"
#include "support/dyncal_cli.hpp"
#include "support/simulated_log.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace dyncal::host;
using namespace dyncal::test;

class ExportMjcf : public ::testing::TestWithParam<const char*> {};

TEST_P(ExportMjcf, MujocoInverseDynamicsIsTheCompiledModel) {
  const std::string name = GetParam();
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_mjcf_" + name + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string robots = " --robots-dir " + std::string(source_dir()) + "/tests/robots";
  const RobotDescription robot = test_robot(name);
  write_csv_log((dir / "log.csv").string(), simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 31, 3).log);
  ASSERT_EQ(run_dyncal("identify --robot " + name + robots + " --method pcls --data " + (dir / "log.csv").string() +
                       " --params " + (dir / "p.json").string()),
            0);
  const std::filesystem::path out = dir / (name + ".xml");
  ASSERT_EQ(run_dyncal("export mjcf --params " + (dir / "p.json").string() + " --out " + out.string() + robots), 0);

  // The parameter file's model, read here from the file itself.
  const nlohmann::json file = read_json(dir / "p.json");
  const CompiledRobot& c = compiled_robot_for(robot);
  const int n = robot.num_joints;
  Eigen::VectorXd phi = Eigen::VectorXd::Zero(c.num_standard);
  for (const auto& l : file["links"]) {
    const auto com = l["com"].get<std::array<double, 3>>();
    const auto I = l["inertia_about_com"].get<std::array<double, 6>>();
    const std::array<double, 10> physical = {
        l["mass"].get<double>(), com[0], com[1], com[2], I[0], I[1], I[2], I[3], I[4], I[5]};
    standard_from_physical(physical, phi.data() + 10 * (l["link"].get<int>() - 1));
  }
  auto term = [&](const std::string& key, int joint) {
    for (const auto& p : file["params"])
      if (p["name"] == key + std::to_string(joint + 1)) return p["value"].get<double>();
    return 0.0;
  };
  Eigen::VectorXd Ia(n), Fv(n), Fc(n);
  for (int j = 0; j < n; ++j) {
    Ia[j] = term("Ia", j);
    Fv[j] = term("Fv", j);
    Fc[j] = term("Fc", j);
  }
  ASSERT_GT(Fc.minCoeff(), 0.0);  // the simulated arm has friction on every joint
  ASSERT_GT(Ia.maxCoeff(), 0.0);  // and rotor inertia

  char error[1000] = "";
  mjModel* m = mj_loadXML(out.c_str(), nullptr, error, sizeof error);
  ASSERT_NE(m, nullptr) << error;
  ASSERT_EQ(m->nv, n);
  for (int j = 0; j < n; ++j) {
    EXPECT_DOUBLE_EQ(m->dof_frictionloss[j], Fc[j]) << "joint " << j + 1;
    EXPECT_DOUBLE_EQ(m->dof_armature[j], Ia[j]) << "joint " << j + 1;
    EXPECT_DOUBLE_EQ(m->dof_damping[j], Fv[j]) << "joint " << j + 1;
  }
  m->opt.disableflags |= mjDSBL_CONSTRAINT;  // dry friction, limits and contacts are MuJoCo constraints
  mjData* d = mj_makeData(m);
  std::mt19937_64 rng(2072);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  double worst = 0;
  for (int k = 0; k < 200; ++k) {
    Eigen::VectorXd q(n), qd(n), qdd(n);
    for (int j = 0; j < n; ++j) {
      q[j] = robot.q_min[j] + 0.5 * (u(rng) + 1.0) * (robot.q_max[j] - robot.q_min[j]);
      qd[j] = u(rng) * robot.qd_max[j];
      qdd[j] = u(rng) * robot.qdd_max[j];
      d->qpos[j] = q[j];
      d->qvel[j] = qd[j];
      d->qacc[j] = qdd[j];
    }
    mj_inverse(m, d);
    const Eigen::VectorXd want = c.inverse_dynamics(q, qd, qdd, phi) + Ia.cwiseProduct(qdd) + Fv.cwiseProduct(qd);
    for (int j = 0; j < n; ++j)
      worst = std::max(worst, std::abs(d->qfrc_inverse[j] - want[j]) / std::max(1.0, std::abs(want[j])));
  }
  mj_deleteData(d);
  mj_deleteModel(m);
  std::printf("%s: MuJoCo's inverse dynamics of the exported MJCF against the compiled model: %.2g (relative)\n",
              name.c_str(), worst);
  EXPECT_LT(worst, 1e-9);
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(TestRobots, ExportMjcf, ::testing::Values("arm6", "cobot7", "scara4", "torso7"));

// A base-parameter file (wls) has no link inertials: one line, exit 2, no file.
TEST(ExportMjcfErrors, BaseParametersAloneAreRefused) {
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_mjcf_wls" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const RobotDescription robot = test_robot("arm3");
  write_csv_log((dir / "log.csv").string(), simulate(robot, uniform_times(500.0, 20.0), MotionClock{}, 31, 3).log);
  const std::string robots = " --robots-dir " + std::string(source_dir()) + "/tests/robots";
  ASSERT_EQ(run_dyncal("identify --robot arm3 --data " + (dir / "log.csv").string() + " --params " +
                       (dir / "p.json").string() + robots),
            0);
  EXPECT_EQ(
      run_dyncal("export mjcf --params " + (dir / "p.json").string() + " --out " + (dir / "x.xml").string() + robots),
      2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.xml"));
  std::filesystem::remove_all(dir);
}

// The TX40's wrist: motor 6 turns with joints 5 and 6 (robot.json's transmission). Its rotor
// inertia and friction act on both joints, which no MuJoCo joint attribute can hold: they are
// listed and kept as custom numerics, joint 6 holds none of them, and MuJoCo still reproduces the
// part it holds (the export's own check).
TEST(ExportMjcfErrors, CoupledTransmissionTermsAreListedNotHeld) {
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_mjcf_tx40" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  ASSERT_EQ(run_dyncal("identify --format tx40 --data " + std::string(source_dir()) +
                       "/tests/data/staubli_tx40 --method pcls --params " + (dir / "p.json").string()),
            0);
  const std::string out = (dir / "tx40.xml").string();
  const CliResult r = run_dyncal_captured("export mjcf --params " + (dir / "p.json").string() + " --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("Ia6"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("coupled transmission of motor 6"), std::string::npos) << r.output;
  char error[1000] = "";
  mjModel* m = mj_loadXML(out.c_str(), nullptr, error, sizeof error);
  ASSERT_NE(m, nullptr) << error;
  EXPECT_EQ(m->dof_armature[5], 0.0);
  EXPECT_EQ(m->dof_frictionloss[5], 0.0);
  EXPECT_GT(m->dof_armature[4], 0.0);  // joint 5's own motor
  EXPECT_GE(mj_name2id(m, mjOBJ_NUMERIC, "dyncal_Ia6"), 0);
  mj_deleteModel(m);
  std::filesystem::remove_all(dir);
}

}  // namespace
