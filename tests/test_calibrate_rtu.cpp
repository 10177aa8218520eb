// The same calibration over Modbus RTU on a pseudo-terminal pair (socat), drive on one end.
#include <gtest/gtest.h>

#include <cstdlib>
#include <sstream>

#include "dyncal_host/calibration/calibrate.hpp"

namespace {

using namespace dyncal::host;

TEST(CalibrateRtu, CalibratesAndFlashesOverAPtyPair) {
  const char* device = std::getenv("DYNCAL_RTU_DEVICE");
  ASSERT_TRUE(device) << "run through ctest";
  const auto robot = load_robot(default_robots_dir(), "er20");
  CalibrateOptions o;
  o.uri = std::string("rtu:") + device;
  o.terms = parse_model("eq7,rotor_inertia,offset");
  o.sample_rate_hz = 100;  // the survey's rate; RTU frames are slower than TCP
  o.periods = 2;
  o.verify_periods = 1;
  o.progress = false;
  std::ostringstream progress;
  const CalibrateResult r = calibrate(robot, o, progress);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_EQ(r.samples, 2000);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  for (int j = 0; j < 6; ++j) EXPECT_LT(r.drive_error_after[j], 0.5 * r.drive_error_before[j]) << "joint " << j + 1;
  print_calibrate_report(std::cout, r);
}

}  // namespace
