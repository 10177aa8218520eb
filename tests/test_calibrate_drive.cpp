// dyncal calibrate against the simulated drive over Modbus (fixture-started server): on noise-free
// data with declared effects only, the batch fit recovers the set parameters.
#include "support/calibration_check.hpp"
#include "support/test_paths.hpp"

namespace {

TEST(CalibrateDrive, NoiseFreeDeclaredModelRecoversTheSetParameters) {
  dyncal::host::calibrate_and_compare("DYNCAL_DRIVE_NOISE_FREE_READY",
                                      std::string(dyncal::test::source_dir()) + "/tests/data/scenarios/noise_free.json",
                                      0.02, 0.05);
}

}  // namespace
