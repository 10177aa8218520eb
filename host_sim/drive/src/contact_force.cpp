#include "dyncal_host/drive/contact_force.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace dyncal::host {
namespace {

/// Frames of joints 1..link in the base frame: rotation and origin of each (after its Rz(q_i) or Tz(q_i)).
void chain(const JointOrigins& origins, const double* q, int link, Eigen::Matrix3d* R, Eigen::Vector3d* o) {
  Eigen::Matrix3d Rc = Eigen::Matrix3d::Identity();
  Eigen::Vector3d pc = Eigen::Vector3d::Zero();
  for (int i = 0; i < link; ++i) {
    const JointOrigin& f = origins[static_cast<size_t>(i)];
    const Eigen::Matrix3d Ri = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(f.R.data());
    const Eigen::Vector3d pi(f.p[0], f.p[1], f.p[2]);
    pc = pc + Rc * pi;
    if (f.prismatic) {
      Rc = Rc * Ri;
      pc = pc + Rc.col(2) * q[i];
    } else {
      Rc = Rc * Ri * Eigen::AngleAxisd(q[i], Eigen::Vector3d::UnitZ()).toRotationMatrix();
    }
    R[i] = Rc;
    o[i] = pc;
  }
}

}  // namespace

Eigen::Vector3d link_point_position(const JointOrigins& origins, int joints, const double* q, int link,
                                    const std::array<double, 3>& point) {
  Eigen::Matrix3d R[kMaxDriveJoints];
  Eigen::Vector3d o[kMaxDriveJoints];
  chain(origins, q, std::min(link, joints), R, o);
  const int l = std::min(link, joints) - 1;
  return o[l] + R[l] * Eigen::Vector3d(point[0], point[1], point[2]);
}

std::array<double, kMaxDriveJoints> contact_joint_torque(const JointOrigins& origins, int joints, const double* q,
                                                         int link, const std::array<double, 3>& point,
                                                         const Eigen::Vector3d& force) {
  Eigen::Matrix3d R[kMaxDriveJoints];
  Eigen::Vector3d o[kMaxDriveJoints];
  const int n = std::min(link, joints);
  chain(origins, q, n, R, o);
  const Eigen::Vector3d p = o[n - 1] + R[n - 1] * Eigen::Vector3d(point[0], point[1], point[2]);
  std::array<double, kMaxDriveJoints> tau{};
  for (int j = 0; j < n; ++j) {
    // Joint j turns about (slides along) its frame's z: Rz(q_j) and Tz(q_j) leave z where the origin put it.
    const JointOrigin& f = origins[static_cast<size_t>(j)];
    tau[static_cast<size_t>(j)] = f.prismatic ? R[j].col(2).dot(force) : R[j].col(2).dot((p - o[j]).cross(force));
  }
  return tau;
}

}  // namespace dyncal::host
