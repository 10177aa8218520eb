#pragma once

#include "dyncal/fourier_trajectory.hpp"
#include "dyncal/modbus_map.hpp"

namespace dyncal::host {

/// A Fourier excitation (survey Eq. 27) as a drive plays it: up to modbus_map::kMaxJoints joints and
/// kMaxHarmonics harmonics (the register map's sizes; the same type as linux_port::Trajectory).
using ExcitationTrajectory = FourierTrajectory<double, modbus_map::kMaxJoints, modbus_map::kMaxHarmonics>;

}  // namespace dyncal::host
