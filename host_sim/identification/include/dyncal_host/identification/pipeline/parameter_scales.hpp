#pragma once
// The physical scale of each identified parameter: the size a parameter of that kind plausibly
// has on this robot, against which identifiability.hpp judges its standard deviation.

#include <Eigen/Core>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

/// Scale of each of `model`'s P parameters (> 0), in the parameter's unit:
/// - a base parameter phi_b = K phi (Gautier): the root sum of squares of K's row times the
///   standard parameters' scales, each max(|nominal|, 5 % of the largest nominal of its kind in the
///   link: inertia, first moment, mass) from robot.json's inertials (prior_std at relative std 1);
/// - a term of joint j: the value at which the term alone reaches the joint's rated torque tau_max
///   at its rated motion: Coulomb and offset tau_max [Nm], viscous tau_max / qd_max [Nm s/rad],
///   power (Eq. 8) tau_max / qd_max^(1/3), load friction (Eq. 9) 1, rotor inertia
///   tau_max / qdd_max [kg m^2].
/// Throws InputError if the robot is not compiled or a rating is not positive.
Eigen::VectorXd parameter_scales(const RobotDescription& robot, const TermSetModel& model);

}  // namespace dyncal::host
