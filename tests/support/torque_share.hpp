#pragma once
// How much a parameter error moves the torque, for any compiled robot's Eq. 7 model: the tolerance
// the robot-folder tests state ("an error may move no joint's torque by more than 1 % of that
// joint's RMS torque").
#include <Eigen/Core>
#include <cmath>

#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::test {

/// RMS over the given motion of every Eq. 7 column (Y_b, then sgn(qd_j) and qd_j per joint) and of
/// the torque K phi, per joint.
class Eq7TorqueShare {
 public:
  Eq7TorqueShare(const host::CompiledRobot& robot, const Eigen::VectorXd& phi)
      : robot_(robot),
        phi_(phi),
        col_ss_(Eigen::MatrixXd::Zero(robot.num_joints, phi.size())),
        tau_ss_(Eigen::VectorXd::Zero(robot.num_joints)) {}

  /// Adds one sample of the motion (q [rad], qd [rad/s], qdd [rad/s^2], N entries).
  void add(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
    const int n = robot_.num_joints;
    Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, phi_.size());
    K.leftCols(robot_.num_base) = robot_.base_regressor(q, qd, qdd);
    for (int j = 0; j < n; ++j) {
      K(j, robot_.num_base + 2 * j) = qd[j] > 0 ? 1.0 : (qd[j] < 0 ? -1.0 : 0.0);
      K(j, robot_.num_base + 2 * j + 1) = qd[j];
    }
    col_ss_ += K.cwiseAbs2();
    tau_ss_ += (K * phi_).cwiseAbs2();
    ++samples_;
  }

  /// max_j RMS(K_ji) |error| / RMS(tau_j): the largest share of a joint's RMS torque an error of
  /// parameter i moves.
  double share(int i, double error) const {
    const Eigen::VectorXd col_rms = (col_ss_.col(i) / static_cast<double>(samples_)).cwiseSqrt();
    const Eigen::VectorXd tau_rms = (tau_ss_ / static_cast<double>(samples_)).cwiseSqrt();
    return (col_rms * std::abs(error)).cwiseQuotient(tau_rms).maxCoeff();
  }

 private:
  const host::CompiledRobot& robot_;
  Eigen::VectorXd phi_;
  Eigen::MatrixXd col_ss_;
  Eigen::VectorXd tau_ss_;
  long samples_ = 0;
};

}  // namespace dyncal::test
