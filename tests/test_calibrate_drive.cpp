// dyncal calibrate against the simulated drive over Modbus (fixture-started server): on noise-free
// data with declared effects only, the batch fit recovers the set parameters.
#include "dyncal_host/excite.hpp"
#include "support/calibration_check.hpp"

namespace {

TEST(CalibrateDrive, NoiseFreeDeclaredModelRecoversTheSetParameters) {
  dyncal::host::calibrate_and_compare("DYNCAL_DRIVE_NOISE_FREE_READY",
                                      DYNCAL_SOURCE_DIR "/tests/data/scenarios/noise_free.json", 0.02, 0.05);
}

// The same with a designed excitation (dyncal excite: cond(K) minimised within 80 % of the limits)
// played instead of the random one: the drive follows it and the fit meets the same bounds.
TEST(CalibrateDrive, DesignedExcitationRecoversTheSetParameters) {
  const auto robot = dyncal::host::load_robot(dyncal::host::default_robots_dir(), "er20");
  const auto designed = dyncal::host::design_excitation(robot, {});
  dyncal::host::calibrate_and_compare("DYNCAL_DRIVE_NOISE_FREE_READY",
                                      DYNCAL_SOURCE_DIR "/tests/data/scenarios/noise_free.json", 0.02, 0.05,
                                      designed.trajectory);
}

}  // namespace
