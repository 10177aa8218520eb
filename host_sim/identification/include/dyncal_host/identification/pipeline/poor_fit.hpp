#pragma once
// Why a joint fits badly, named in the report (issue 68): a joint whose cross-validated R^2 is low
// gets a note with what the log shows of it -- too little motion, an effort quantised coarsely
// against the residual, a torque that hardly varies -- or that none of these explains it.

#include <string>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// The R^2 below which a joint's fit is explained in a note (a reporting level, not a decision: the
/// fit is the same whatever it is).
inline constexpr double kPoorFitR2 = 0.9;

/// What the raw log shows of each joint, taken before identification consumes it.
struct JointLogFacts {
  std::vector<double> q_span;       ///< max - min of q_j [rad]
  std::vector<double> tau_quantum;  ///< smallest non-zero |tau_j(k+1) - tau_j(k)| [Nm] (0: never changes)
  std::vector<double> tau_std;      ///< standard deviation of tau_j about its mean [Nm]
  std::vector<double> tau_noise;    ///< white-noise std of tau_j (signal.hpp white_noise_std) [Nm]
};
JointLogFacts joint_log_facts(const JointLog& raw);

/// One note per joint with R^2 < kPoorFitR2: "joint j fits badly (cross-validated R^2 x): ..." with
/// each cause that holds: its motion spans less than a tenth of its range (robot.json's q_min..q_max);
/// its effort comes in steps whose rounding noise (step / sqrt 12) is at least 30 % of the residual
/// RMS; its torque's sample-to-sample noise is half its variation or more (its std about its mean:
/// R^2 is then low whatever the model). With none, the note says so and points to dyncal diagnose.
std::vector<std::string> poor_fit_notes(const JointLogFacts& facts, const RobotDescription& robot,
                                        const std::vector<JointMetrics>& joints);

}  // namespace dyncal::host
