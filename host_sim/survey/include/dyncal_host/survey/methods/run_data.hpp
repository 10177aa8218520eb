#pragma once
// One recorded run as the identification methods take it (pseudo-inverse, Kalman filter, forgetting,
// extended Kalman filter, physically consistent LS, IDIM-IV, the optimisers): joint states and torques
// at the samples, and Eq. 9's load torque.

#include <Eigen/Core>

namespace dyncal::host {

/// One recorded run. S samples; matrices are S x N, joint j in column j - 1. Joint side, SI units.
struct RunData {
  Eigen::VectorXd t;           ///< [s]
  Eigen::MatrixXd q, qd, qdd;  ///< joint states at the samples [rad, rad/s, rad/s^2]
  Eigen::MatrixXd q_meas;      ///< measured position [rad] (IDIM-IV differentiates it itself)
  Eigen::MatrixXd tau;         ///< measured joint torque [Nm]
  Eigen::MatrixXd tau_load;    ///< load torque of Eq. 9 [Nm] (load_torque); only Eq. 9 reads it
  double sample_rate_hz = 0;
};

/// Rows [from, from + n) of every sampled signal of `d` (t, q, qd, qdd, q_meas, tau, tau_load); the
/// rest copied. Throws InputError unless 0 <= from, 0 <= n, from + n <= S.
RunData sample_rows(const RunData& d, Eigen::Index from, Eigen::Index n);

/// Eq. 9's load torque as a user has it: the torque the joint holds against gravity and the
/// velocity-product terms, Y_b(q, qd, 0) phi_b (the simulated drive's load torque h(q, qd); with the
/// inertial term the friction would depend on the acceleration it causes), phi_b from an Eq. 9
/// least-squares fit of (q, qd, qdd, tau) with its own load torque, from tau_load = tau, repeated
/// until it changes by less than 1e-9 of max |tau| (at most 50 times). S x 6 [Nm] (er20 model).
Eigen::MatrixXd load_torque(const Eigen::MatrixXd& q, const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd,
                            const Eigen::MatrixXd& tau);

}  // namespace dyncal::host
