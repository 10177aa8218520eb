// The test robots (tests/robots/: a 3-joint arm, a 7-joint cobot with y-axis joints, fixed tool frames
// and a massive base) through the whole loop: their simulated drive (built from robot.json, Coulomb +
// viscous friction from tests/data/scenarios/<robot>_friction.json, torque noise,
// 20-bit joint encoders) served over Modbus TCP by a fixture, `calibrate` (excitation, online KF/RLS, batch fit, flash,
// verification), run twice. Stated tolerances after the second run: friction (Fc, Fv) within 4 of
// identify's standard deviations, every other parameter's error moving no joint's torque by more than
// 1 % of that joint's RMS torque over the excitation; each flashed table at least halves the drive's model error
// RMS(tau - tau_ff) of the factory table on every joint. The second run's log and control law
// (--save-log, --save-law) also go through IDIM-IV: converged, friction within 4 std.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/drive/ground_truth.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "support/test_paths.hpp"
#include "support/torque_share.hpp"

namespace {

using namespace dyncal::host;

/// IDIM-IV on a calibrate run's log and law (calibrate --save-log --save-law: the drive's PD gains
/// from the Modbus map, the table active during the run, the trajectory, the rates): it converges,
/// with the scenario's friction within its standard deviations as WLS's. Both fit as calibrate's
/// batch does (rows below 2 % of a joint's top speed left out: stiction at reversals).
void idim_iv_on_saved_law(const std::string& name, const Scenario& scenario, const std::string& log,
                          const std::string& law_file, const std::filesystem::path& out) {
  std::ifstream law_in(law_file);
  const nlohmann::json law = nlohmann::json::parse(law_in);
  ASSERT_EQ(law["kp"].size(), static_cast<size_t>(scenario.num_joints));
  for (int j = 0; j < scenario.num_joints; ++j) EXPECT_GT(law["kp"][static_cast<size_t>(j)].get<double>(), 0.0);
  ASSERT_TRUE(law.contains("feed_forward_table"));
  auto identify_run = [&](const std::string& method) {
    const std::string report = (out / (method + ".json")).string();
    const std::string cmd = std::string(dyncal::test::dyncal_binary()) + " identify --robots-dir " +
                            std::string(dyncal::test::source_dir()) + "/tests/robots" + " --robot " + name +
                            " --data " + log + " --model eq7 --min-speed 0.02 --method " + method +
                            (method == "iv" ? " --law " + law_file : std::string()) + " --report " + report +
                            " > /dev/null";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream in(report);
    return nlohmann::json::parse(in);
  };
  const nlohmann::json wls = identify_run("wls"), iv = identify_run("iv");
  int converged = 0;
  for (const auto& n : iv["notes"]) {
    const std::string note = n.get<std::string>();
    std::printf("note: %s\n", note.c_str());
    converged += note.rfind("IDIM-IV: converged after", 0) == 0;
  }
  EXPECT_EQ(converged, 1);
  double z2_iv = 0, z2_wls = 0;
  int n = 0;
  for (size_t i = 0; i < iv["params"].size(); ++i) {
    const std::string p = iv["params"][i]["name"];
    if (p.rfind("Fc", 0) != 0 && p.rfind("Fv", 0) != 0) continue;
    const int j = std::stoi(p.substr(2)) - 1;
    const double truth = p[1] == 'c' ? scenario.friction[j].Fc : scenario.friction[j].beta;
    const double z_iv = (iv["params"][i]["value"].get<double>() - truth) / iv["params"][i]["std"].get<double>();
    const double z_wls = (wls["params"][i]["value"].get<double>() - truth) / wls["params"][i]["std"].get<double>();
    std::printf("%s: truth %.4g, wls %.4g (%.2f std), iv %.4g (%.2f std)\n", p.c_str(), truth,
                wls["params"][i]["value"].get<double>(), z_wls, iv["params"][i]["value"].get<double>(), z_iv);
    EXPECT_LE(std::abs(z_iv), 4.0) << p;
    z2_iv += z_iv * z_iv, z2_wls += z_wls * z_wls, ++n;
  }
  std::printf("friction RMS error in standard deviations: wls %.2f, iv %.2f\n", std::sqrt(z2_wls / n),
              std::sqrt(z2_iv / n));
  EXPECT_LE(std::sqrt(z2_iv / n), 2.0);
}

void calibrate_test_robot(const std::string& name) {
  const char* dir = std::getenv("DYNCAL_DRIVES_DIR");  // the fixtures' ready files: DIR/<robot>.ready
  ASSERT_NE(dir, nullptr) << "run through ctest";
  std::string uri;
  std::getline(std::ifstream(std::string(dir) + "/" + name + ".ready"), uri);
  ASSERT_FALSE(uri.empty()) << "the " << name << " drive fixture is not running";
  RobotDescription robot = load_robot(std::string(dyncal::test::source_dir()) + "/tests/robots", name);
  derive_tau_max(robot);
  const Scenario scenario = load_scenario(
      std::string(dyncal::test::source_dir()) + "/tests/data/scenarios/" + name + "_friction.json", robot);
  CalibrateOptions o;
  o.uri = uri;
  o.terms = dyncal::kFrictionEq7;
  o.progress = false;
  // Twice, as a user iterates: the first run starts from the factory table (no friction in the
  // feed-forward), so the light distal joints stick at each reversal under PD alone and their
  // friction comes out biased (Fc7 -7 %, Fv7 +22 % on cobot7); the second run excites through the
  // flashed table's feed-forward.
  std::ostringstream progress;
  const CalibrateResult first = calibrate(robot, o, progress);
  ASSERT_TRUE(first.flashed) << first.flash_message;
  // The second run also records its log and control law (calibrate --save-log --save-law).
  const auto out = std::filesystem::temp_directory_path() / ("dyncal_law_" + name + std::to_string(::getpid()));
  std::filesystem::create_directories(out);
  CalibrateOptions second = o;
  second.save_log = (out / "log.csv").string();
  second.save_law = (out / "law.json").string();
  const CalibrateResult r = calibrate(robot, second, progress);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  ASSERT_TRUE(std::filesystem::exists(out / "law.table"));
  idim_iv_on_saved_law(name, scenario, second.save_log, second.save_law, out);
  std::filesystem::remove_all(out);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_EQ(r.num_joints, robot.num_joints);
  const auto truth = true_parameters(scenario, o.terms);
  ASSERT_EQ(truth.size(), r.phi_batch.size());
  // The Eq. 7 model's columns on the played excitation (2000 points of one period).
  const CompiledRobot& c = compiled_robot_for(robot);
  const int n = robot.num_joints, cols = static_cast<int>(truth.size());
  const ExcitationTrajectory traj = default_excitation(robot, o.f_f, o.harmonics, o.candidates, o.seed, nullptr);
  Eigen::VectorXd phi_true(cols);
  for (int i = 0; i < cols; ++i) phi_true[i] = truth[static_cast<size_t>(i)].value;
  dyncal::test::Eq7TorqueShare shares(c, phi_true);
  for (int k = 0; k < 2000; ++k) {
    Eigen::Matrix<double, 7, 1> q7, qd7, qdd7;
    traj.evaluate(traj.period() * k / 2000, q7, qd7, qdd7);
    shares.add(q7.head(n), qd7.head(n), qdd7.head(n));
  }
  double worst = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    const double t = truth[i].value, e = r.phi_batch[i];
    const double share = shares.share(static_cast<int>(i), e - t);
    SCOPED_TRACE(truth[i].name + ": true " + std::to_string(t) + ", identified " + std::to_string(e));
    EXPECT_EQ(truth[i].name, r.names[i]);
    const bool friction = truth[i].name.rfind("Fc", 0) == 0 || truth[i].name.rfind("Fv", 0) == 0;
    if (friction) {
      // Within 4 of its standard deviations (identify's, corrected for the residual's
      // autocorrelation): a two-sided 6e-5 chance per parameter under the noise alone.
      const double sd = r.batch.params[i].std;
      EXPECT_LE(std::abs(e - t), 4 * sd) << "std " << sd;
      std::printf("%s: error %.2f std\n", truth[i].name.c_str(), std::abs(e - t) / sd);
    } else {
      EXPECT_LE(share, 0.01);
      worst = std::max(worst, share);
    }
  }
  for (int j = 0; j < n; ++j) {
    SCOPED_TRACE("joint " + std::to_string(j + 1));
    EXPECT_LT(first.drive_error_after[j], 0.5 * first.drive_error_before[j]);
    EXPECT_LT(r.drive_error_after[j], 0.5 * first.drive_error_before[j]);
  }
  std::printf("%s: %zu parameters, largest inertial error share %.4f of a joint's RMS torque\n", name.c_str(),
              truth.size(), worst);
  print_calibrate_report(std::cout, r);
}

// Built once per test robot (tests/CMakeLists.txt), each with its own drive fixture. The second
// calibrate run's saved log and law also go through IDIM-IV (identify --method iv --law).
TEST(CalibrateRobotFolder, OverModbus) {
  calibrate_test_robot(DYNCAL_TEST_ROBOT);
}

}  // namespace
