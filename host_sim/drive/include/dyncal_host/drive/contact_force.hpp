#pragma once
// The joint torques of a force on a point of a link (the simulated drive's external contacts,
// scenario.hpp ExternalContact): forward kinematics of the generated joint origins.

#include <Eigen/Core>
#include <array>

#include "dyncal_host/drive/scenario.hpp"

namespace dyncal::host {

/// Joint i's fixed transform before its motion along z, as the generated kJointOrigins give it:
/// rotation R (row-major) and offset p [m] in the parent frame, T(i-1, i) = [R p] Rz(q_i), or
/// [R p] Tz(q_i) for a prismatic joint (kJointPrismatic).
struct JointOrigin {
  std::array<double, 9> R{1, 0, 0, 0, 1, 0, 0, 0, 1};
  std::array<double, 3> p{};
  bool prismatic = false;
};
using JointOrigins = std::array<JointOrigin, kMaxDriveJoints>;

/// Position [m], base frame, of `point` [m] given in link `link`'s frame (1-based; the frame joint
/// `link` moves), at joint positions q [rad] of a chain of `joints` joints.
Eigen::Vector3d link_point_position(const JointOrigins& origins, int joints, const double* q, int link,
                                    const std::array<double, 3>& point);

/// tau = J_p(q)^T F [Nm; N for a prismatic joint] per joint (entries past `joints` 0): the torques
/// a force F [N, base frame] on that point exerts on the joints, tau_j = z_j . ((p - o_j) x F) for
/// the revolute joints that move the point and z_j . F for the prismatic ones (z_j, o_j joint j's
/// axis and origin in the base frame), 0 for the others.
std::array<double, kMaxDriveJoints> contact_joint_torque(const JointOrigins& origins, int joints, const double* q,
                                                         int link, const std::array<double, 3>& point,
                                                         const Eigen::Vector3d& force);

}  // namespace dyncal::host
