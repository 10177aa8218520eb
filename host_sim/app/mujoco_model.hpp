#pragma once
// MuJoCo's own reading of an MJCF file (Debian's libmujoco-dev): dyncal export mjcf writes a file
// only after MuJoCo's inverse dynamics of it reproduces dyncal's model (docs/export.md).

#include <Eigen/Core>
#include <string>

struct mjModel_;
struct mjData_;

namespace dyncal::app {

/// An MJCF file compiled by MuJoCo (mj_loadXML) with its mjData. Not copyable.
class MujocoModel {
 public:
  /// Throws host::InputError naming `path` with MuJoCo's own error text when it does not compile.
  explicit MujocoModel(const std::string& path);
  ~MujocoModel();
  MujocoModel(const MujocoModel&) = delete;
  MujocoModel& operator=(const MujocoModel&) = delete;

  /// Degrees of freedom (nv).
  int dofs() const;
  /// Name of joint `i` (0-based, MuJoCo's order), "" when unnamed.
  std::string joint_name(int i) const;
  /// MuJoCo's inverse dynamics (mj_inverse, qfrc_inverse) at (q [rad], qd [rad/s], qdd [rad/s^2]),
  /// each of size dofs(): M(q) qdd (armature included) + bias (Coriolis, centrifugal, gravity) +
  /// damping qd [Nm], with the constraint solver disabled (frictionloss, limits and contacts are
  /// constraints in MuJoCo: frictionloss is its solver's dry friction, not a function of the state).
  Eigen::VectorXd inverse_dynamics(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);

 private:
  mjModel_* model_ = nullptr;
  mjData_* data_ = nullptr;
};

}  // namespace dyncal::app
