// dyncal export urdf (issue 44): an arm identified with pcls from a simulated log is written back
// into the URDF it was imported from, and the written file is read by independent code: robot
// import (the Python importer, with its own orocos-kdl check of the merged chain against the file)
// and orocos-kdl's inverse dynamics of the re-imported file at seeded random states, from which the
// compiled model's base regressor must recover the parameter file's base parameters (Gautier's
// base parameters are what the data determine: the same file, the same model).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Dense>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dyncal_host/logs/joint_log.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "support/dyncal_cli.hpp"
#include "support/simulated_log.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace dyncal::host;
using namespace dyncal::test;

std::string read_text(const std::filesystem::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class ExportUrdf : public ::testing::TestWithParam<const char*> {};

TEST_P(ExportUrdf, RoundTripsThroughKdlAndRobotImport) {
  const std::string name = GetParam();
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_export_" + name + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "robots");
  std::filesystem::copy(std::string(dyncal::test::source_dir()) + "/tests/robots/" + name, dir / "robots" / name);
  const std::string robots = " --robots-dir " + (dir / "robots").string();
  const RobotDescription robot = test_robot(name);
  write_csv_log((dir / "log.csv").string(), simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 31, 3).log);
  ASSERT_EQ(run_dyncal("identify --robot " + name + robots + " --method pcls --data " + (dir / "log.csv").string() +
                       " --params " + (dir / "p.json").string()),
            0);
  const std::filesystem::path out = dir / (name + "_identified.urdf");
  ASSERT_EQ(run_dyncal("export urdf --params " + (dir / "p.json").string() + " --out " + out.string() + robots), 0);
  const std::string text = read_text(out);
  {  // issue 67: the exported file's mode follows the umask (it was always 0600)
    const mode_t mask = ::umask(022);
    ::umask(mask);
    struct stat st {};
    ASSERT_EQ(::stat(out.c_str(), &st), 0);
    EXPECT_EQ(st.st_mode & 0777, 0666u & ~mask);
  }
  EXPECT_NE(text.find("<dynamics damping="), std::string::npos);
  EXPECT_NE(text.find("<dyncal "), std::string::npos);
  EXPECT_NE(text.find("offset=\""), std::string::npos);           // the default model's offsets, in <dyncal>
  EXPECT_NE(text.find("<!-- dyncal: mass "), std::string::npos);  // each link's mass with its std

  // Every link's mass carries its std (issue 68), and the simulated arm's mass (robot.json's) lies in
  // its 99 % interval on all links but at most one.
  const CompiledRobot& compiled = compiled_robot_for(robot);
  nlohmann::json file = read_json(dir / "p.json");
  int covered = 0;
  for (size_t l = 0; l < file["links"].size(); ++l) {
    const auto& link = file["links"][l];
    ASSERT_TRUE(link.contains("mass_std")) << "link " << l + 1;
    const double m = link["mass"].get<double>(), sd = link["mass_std"].get<double>(),
                 truth = compiled.nominal_standard[10 * l + 9];
    std::printf("link %zu: mass %.4g +- %.2g kg (true %.4g)\n", l + 1, m, sd, truth);
    EXPECT_GT(sd, 0.0);
    covered += std::abs(m - truth) <= 2.58 * sd;
  }
  EXPECT_GE(covered + 1, static_cast<int>(file["links"].size()));
  // A link whose mass rests on neither the log nor a prior (its 95 % interval holds 0 and the fit had
  // no prior; here the file is edited so) is refused, nothing written; --force writes it, marked.
  file["links"][0]["mass_std"] = file["links"][0]["mass"].get<double>();
  file["links"][0]["mass_basis"] = "neither";
  std::ofstream(dir / "wide.json") << file.dump();
  const std::filesystem::path wide = dir / "wide.urdf";
  EXPECT_EQ(run_dyncal("export urdf --params " + (dir / "wide.json").string() + " --out " + wide.string() + robots), 2);
  EXPECT_FALSE(std::filesystem::exists(wide));
  const CliResult forced = run_dyncal_captured("export urdf --params " + (dir / "wide.json").string() + " --out " +
                                               wide.string() + robots + " --force");
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  EXPECT_NE(read_text(wide).find("NOT DETERMINED"), std::string::npos);

  // Re-import the written file as a new robot, on the chain the robot was imported with (its base and
  // tip: torso7's URDF branches to wheels and fingers): its merged chain must pass the importer's KDL check.
  const nlohmann::json source = read_json(std::filesystem::path(robot.directory) / "robot.json")["source"];
  ASSERT_EQ(run_dyncal("robot import " + out.string() + " --name roundtrip --base " +
                       source["base"].get<std::string>() + " --tip " + source["tip"].get<std::string>() + robots),
            0);
  const std::string samples = (dir / "samples.json").string();
  ASSERT_EQ(std::system(("/usr/bin/python3 " + std::string(dyncal::test::source_dir()) +
                         "/codegen/import_urdf.py samples roundtrip" + robots + " --out " + samples)
                            .c_str()),
            0);
  // KDL's torques of the re-imported file, and the compiled model's base regressor at the same
  // states: least squares gives the base parameters of the written file.
  const CompiledRobot& c = compiled_robot_for(robot);
  const nlohmann::json s = read_json(samples)["samples"];
  const int n = robot.num_joints;
  Eigen::MatrixXd Y(static_cast<Eigen::Index>(s.size()) * n, c.num_base);
  Eigen::VectorXd tau(Y.rows());
  for (size_t k = 0; k < s.size(); ++k) {
    auto v = [&](const char* key) {
      const auto x = s[k][key].get<std::vector<double>>();
      return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(x.data(), n));
    };
    Y.middleRows(static_cast<Eigen::Index>(k) * n, n) = c.base_regressor(v("q"), v("qd"), v("qdd"));
    tau.segment(static_cast<Eigen::Index>(k) * n, n) = v("tau");
  }
  const Eigen::VectorXd base = Y.colPivHouseholderQr().solve(tau);
  const nlohmann::json params = read_json(dir / "p.json")["params"];
  double scale = 0;
  for (int i = 0; i < c.num_base; ++i) scale = std::max(scale, std::abs(params[i]["value"].get<double>()));
  double worst = 0;
  for (int i = 0; i < c.num_base; ++i)
    worst = std::max(worst, std::abs(base[i] - params[i]["value"].get<double>()) / scale);
  std::printf(
      "%s: base parameters of the re-imported URDF against the parameter file: %.2g (relative to the "
      "largest)\n",
      name.c_str(), worst);
  EXPECT_LT(worst, 1e-8);
  std::filesystem::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(TestRobots, ExportUrdf, ::testing::Values("arm3", "arm6", "cobot7", "scara4", "torso7"));

// A parameter file without link inertials (wls) cannot be exported: one line, exit 2, no file.
TEST(ExportUrdfErrors, BaseParametersAloneAreRefused) {
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_export_wls" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const RobotDescription robot = test_robot("arm3");
  write_csv_log((dir / "log.csv").string(), simulate(robot, uniform_times(500.0, 20.0), MotionClock{}, 31, 3).log);
  const std::string robots = " --robots-dir " + std::string(dyncal::test::source_dir()) + "/tests/robots";
  ASSERT_EQ(run_dyncal("identify --robot arm3 --model eq7 --data " + (dir / "log.csv").string() + " --params " +
                       (dir / "p.json").string() + robots),
            0);
  EXPECT_EQ(
      run_dyncal("export urdf --params " + (dir / "p.json").string() + " --out " + (dir / "x.urdf").string() + robots),
      2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.urdf"));
  std::filesystem::remove_all(dir);
}

}  // namespace
