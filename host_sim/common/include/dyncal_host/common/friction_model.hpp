#pragma once
// The survey's six friction models by name: what the simulated drive simulates, what excitation
// design and the identification methods fit.

#include <string>

namespace dyncal::host {

/// Survey Eq. 4 (Stribeck), Eq. 5, Eq. 6 (nonlinear), Eq. 7 (Coulomb + viscous), Eq. 8 (+ velocity
/// power), Eq. 9 (+ load-dependent); see drive/scenario.hpp for each formula.
enum class FrictionModel { eq4, eq5, eq6, eq7, eq8, eq9 };

/// Parses a friction model name ("eq4".."eq9"). Throws InputError naming the accepted ones.
FrictionModel parse_friction_model(const std::string& name);

}  // namespace dyncal::host
