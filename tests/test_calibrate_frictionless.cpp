// calibrate on a drive whose joints have no friction at all (the TX40's default simulated drive:
// robot.json declares none): an unconstrained fit gives about half of the Coulomb and viscous
// coefficients small negative values, which no drive accepts (lib/ table_check.hpp). calibrate fits
// them sign-constrained (IdentifyOptions::sign_constraints), names what it held at 0, and flashes.
#include <gtest/gtest.h>

#include <sstream>

#include "dyncal_host/calibration/calibrate.hpp"
#include "support/drive_uri.hpp"

namespace {

using namespace dyncal::host;

TEST(CalibrateFrictionless, NegligibleFrictionIsHeldAtZeroAndTheTableFlashes) {
  const std::string uri = fixture_drive_uri("DYNCAL_DRIVE_TX40_PLAIN_READY");
  ASSERT_FALSE(uri.empty()) << "run through ctest (fixture drive_tx40_plain)";
  const RobotDescription robot = load_robot(default_robots_dir(), "tx40");
  CalibrateOptions o;
  o.uri = uri;
  o.terms = parse_model("eq7,rotor_inertia,offset");
  o.progress = false;
  std::ostringstream progress;
  // Unconstrained first (not flashed): some friction comes out negative, and the table conversion
  // names the first such parameter.
  CalibrateOptions free_fit = o;
  free_fit.identify.sign_constraints = false;
  free_fit.flash = false;
  const CalibrateResult unconstrained = calibrate(robot, free_fit, progress);
  int negative = 0;
  for (size_t i = 0; i < unconstrained.names.size(); ++i) {
    const std::string& n = unconstrained.names[i];
    if ((n.rfind("Fc", 0) == 0 || n.rfind("Fv", 0) == 0 || n.rfind("Ia", 0) == 0) && unconstrained.phi_batch[i] < 0)
      ++negative;
  }
  EXPECT_GT(negative, 0) << "the drive has no friction: some estimate should fall below 0 by chance";
  const CalibrateResult r = calibrate(robot, o, progress);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  bool noted = false;
  for (const std::string& n : r.batch.notes) noted = noted || n.rfind("sign constraints: ", 0) == 0;
  EXPECT_TRUE(noted);
  for (size_t i = 0; i < r.names.size(); ++i) {
    const std::string& n = r.names[i];
    if (n.rfind("Fc", 0) == 0 || n.rfind("Fv", 0) == 0 || n.rfind("Ia", 0) == 0) {
      EXPECT_GE(r.phi_batch[i], 0.0) << n;
    }
  }
  // The wrist's rotor inertia (robots/tx40/drive.json) is what the factory table lacks: it goes.
  for (int j = 3; j < 6; ++j) EXPECT_LT(r.drive_error_after[j], 0.7 * r.drive_error_before[j]) << "joint " << j + 1;
}

}  // namespace
