#pragma once
// The parameters a simulated drive really has, in the order of an identification model: what a
// calibration on noise-free data with declared effects only must recover.

#include <string>
#include <vector>

#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

/// True base parameters (nominal standard parameters mapped to the base set, rotor inertia of
/// joints whose Ia is not separable added to the base parameter that absorbs it) followed by the
/// true term values (Fc, beta, Ia, offset ...) of `scenario`, for the model of scenario.robot
/// (compiled into this build, drive_plant.hpp) with `terms`. Throws InputError for a robot not
/// compiled in, a term set that is not built, or rotor inertia on a joint the model gives no column.
std::vector<TrueParameter> true_parameters(const Scenario& scenario, unsigned terms);

}  // namespace dyncal::host
