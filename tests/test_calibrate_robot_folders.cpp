// The test robots (tests/robots/: a 3-joint arm, a 7-joint cobot with y-axis joints, fixed tool frames
// and a massive base) through the whole loop: their simulated drive (built from robot.json, Coulomb +
// viscous friction from tests/data/scenarios/<robot>_friction.json, torque noise,
// 20-bit joint encoders) served over Modbus TCP by a fixture, `calibrate` (excitation, online KF/RLS, batch fit, flash,
// verification), run twice. Stated tolerances after the second run: friction (Fc, Fv) within 4 of
// identify's standard deviations, every other parameter's error moving no joint's torque by more than
// 1 % of that joint's RMS torque over the excitation; each flashed table at least halves the drive's model error
// RMS(tau - tau_ff) of the factory table on every joint.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/drive/ground_truth.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/identification/compiled_robot.hpp"
#include "support/torque_share.hpp"

namespace {

using namespace dyncal::host;

void calibrate_test_robot(const std::string& name) {
  const char* dir = std::getenv("DYNCAL_DRIVES_DIR");  // the fixtures' ready files: DIR/<robot>.ready
  ASSERT_NE(dir, nullptr) << "run through ctest";
  std::string uri;
  std::getline(std::ifstream(std::string(dir) + "/" + name + ".ready"), uri);
  ASSERT_FALSE(uri.empty()) << "the " << name << " drive fixture is not running";
  RobotDescription robot = load_robot(DYNCAL_SOURCE_DIR "/tests/robots", name);
  derive_tau_max(robot);
  const Scenario scenario = load_scenario(DYNCAL_SOURCE_DIR "/tests/data/scenarios/" + name + "_friction.json", robot);
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
  const CalibrateResult r = calibrate(robot, o, progress);
  ASSERT_TRUE(r.flashed) << r.flash_message;
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

// Built once per test robot (tests/CMakeLists.txt), each with its own drive fixture.
TEST(CalibrateRobotFolder, OverModbus) {
  calibrate_test_robot(DYNCAL_TEST_ROBOT);
}

}  // namespace
