// calibrate on an arm whose robot.json couples a motor to two joints (the TX40: motor 6 turns with
// q5 + q6): the simulated drive runs the published friction, rotor inertia and offsets per motor
// (tests/data/scenarios/tx40_published.json), so motor 6's friction and rotor inertia act at its
// own velocity on both joints. The batch fit is per motor by default and flashed through
// parameter_table (motor 6's terms as a coupling term of the table); with --friction-per-joint it
// cannot represent the motor. Stated: motor 6's Fc, Fv, Ia within 4 of identify's standard
// deviations; the per-motor table at least halves the factory table's drive model error on every
// joint; on joints 5 and 6 the per-motor batch predicts the fresh trajectory better than the
// per-joint one by more than the noise's share.
#include <gtest/gtest.h>

#include <cstdlib>
#include <iostream>
#include <sstream>

#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/drive/ground_truth.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "support/drive_uri.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace dyncal::host;

CalibrateOptions options(const std::string& uri) {
  CalibrateOptions o;
  o.uri = uri;
  o.terms = parse_model("eq7,rotor_inertia,offset");
  o.progress = false;
  return o;
}

TEST(CalibrateCoupledMotor, PerMotorFitRecoversMotor6AndItsTableCutsTheModelError) {
  const std::string uri = fixture_drive_uri("DYNCAL_DRIVE_TX40_READY");
  ASSERT_FALSE(uri.empty()) << "run through ctest (fixture drive_tx40)";
  const RobotDescription robot = load_robot(default_robots_dir(), "tx40");
  const Scenario scenario =
      load_scenario(std::string(dyncal::test::source_dir()) + "/tests/data/scenarios/tx40_published.json", robot);
  const CalibrateOptions o = options(uri);
  std::ostringstream progress;
  // The per-joint fit first, not flashed: the drive keeps its factory table for the runs after it.
  CalibrateOptions per_joint = o;
  per_joint.identify.friction_per_joint = true;
  per_joint.flash = false;
  const CalibrateResult joint_fit = calibrate(robot, per_joint, progress);
  EXPECT_FALSE(joint_fit.friction_per_motor);
  // Twice per motor, as a user iterates (the second run excites through the first table's feed-forward).
  const CalibrateResult first = calibrate(robot, o, progress);
  ASSERT_TRUE(first.flashed) << first.flash_message;
  const CalibrateResult r = calibrate(robot, o, progress);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  print_calibrate_report(std::cout, r);
  EXPECT_TRUE(r.friction_per_motor);
  ASSERT_EQ(r.table_notes.size(), 1u);
  EXPECT_NE(r.table_notes[0].find("motor 6 (turns with q6 +1 q5)"), std::string::npos) << r.table_notes[0];

  // Motor 6's terms against the scenario's (true_parameters: the scenario's friction[m] and rotor
  // inertia are motor m's).
  const auto truth = true_parameters(scenario, o.terms);
  ASSERT_EQ(truth.size(), r.phi_batch.size());
  for (const char* name : {"Fc6", "Fv6", "Ia6", "Fc5", "Fv5"}) {
    size_t i = 0;
    while (i < truth.size() && truth[i].name != name) ++i;
    ASSERT_LT(i, truth.size()) << name;
    ASSERT_EQ(r.names[i], name);
    const double sd = r.batch.params[i].std, e = r.phi_batch[i], t = truth[i].value;
    EXPECT_LE(std::abs(e - t), 4 * sd) << name << ": true " << t << ", identified " << e << ", std " << sd;
    std::printf("%s: true %.4f, identified %.4f, error %.2f std\n", name, t, e, std::abs(e - t) / sd);
  }
  for (int j = 0; j < robot.num_joints; ++j) {
    SCOPED_TRACE("joint " + std::to_string(j + 1));
    EXPECT_LT(first.drive_error_after[j], 0.5 * first.drive_error_before[j]);
    EXPECT_LT(r.drive_error_after[j], 0.5 * first.drive_error_before[j]);
  }
  // Joints 5 and 6: the per-joint model gives joint 5 a friction of its own where the motor turns
  // with both; its prediction of the fresh trajectory stays well above the per-motor one's.
  for (int j : {4, 5}) {
    std::printf("joint %d: fresh-trajectory RMS per motor %.3f Nm, per joint %.3f Nm\n", j + 1, r.verify_batch.rms[j],
                joint_fit.verify_batch.rms[j]);
    EXPECT_LT(1.5 * r.verify_batch.rms[j], joint_fit.verify_batch.rms[j]) << "joint " << j + 1;
  }
}

}  // namespace
