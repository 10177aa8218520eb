#pragma once
// Starts a run on a fixture drive for the tests that stream from it.
#include <gtest/gtest.h>

#include "dyncal/modbus_map.hpp"
#include "dyncal_port/modbus_drive.hpp"

/// Plays `periods` periods of a one-harmonic trajectory (0.05 rad on every joint) of fundamental
/// f_f [Hz], sampled at 1 kHz, on `drive`, after a reset (another test may have left a fault).
/// A refusal is a fatal test failure (wrap the call in ASSERT_NO_FATAL_FAILURE).
inline void start_one_harmonic_run(dyncal::linux_port::ModbusDrive& drive, double f_f, int periods) {
  using dyncal::port::PortStatus;
  dyncal::linux_port::Trajectory t;
  t.f_f = f_f;
  t.harmonics = 1;
  for (int j = 0; j < dyncal::modbus_map::kMaxJoints; ++j) t.a(j, 0) = 0.05;
  ASSERT_EQ(drive.reset(), PortStatus::ok) << drive.error();
  ASSERT_EQ(drive.write_trajectory(t, periods, 1000), PortStatus::ok) << drive.error();
  ASSERT_EQ(drive.start(), PortStatus::ok) << drive.error();
}
