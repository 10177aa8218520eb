// dyncal calibrate playing a designed excitation (dyncal excite: cond(K) minimised within 80 % of
// the limits) instead of the random one, on its own fixture drive (a calibration flashes the
// drive's table, and the before/after check needs the factory table): the drive follows it and
// the fit meets the same bounds as with the random excitation.
#include "dyncal_host/excitation/excitation.hpp"
#include "support/calibration_check.hpp"
#include "support/test_paths.hpp"

namespace {

TEST(CalibrateDrive, DesignedExcitationRecoversTheSetParameters) {
  const auto robot = dyncal::host::load_robot(dyncal::host::default_robots_dir(), "er20");
  const auto designed = dyncal::host::design_excitation(robot, {});
  dyncal::host::calibrate_and_compare("DYNCAL_DRIVE_DESIGNED_READY",
                                      std::string(dyncal::test::source_dir()) + "/tests/data/scenarios/noise_free.json",
                                      0.02, 0.05, designed.trajectory);
}

}  // namespace
