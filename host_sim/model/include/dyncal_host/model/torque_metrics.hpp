#pragma once
// The per-joint figures of a torque prediction (RMS, relative RMS, R^2, e_T_abs): the one metrics
// function of identify's validation, predict, diagnose and calibrate.

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "dyncal_host/model/identify_result.hpp"

namespace dyncal::host {

/// Per-joint metrics of a prediction: y and prediction stacked (row s * N + j), rows whose
/// prediction is NaN skipped; e_T_abs and e_T_abs_std: mean and std of |error| / tau_max.
std::vector<JointMetrics> torque_metrics(const Eigen::VectorXd& y, const Eigen::VectorXd& prediction, int N,
                                         const Eigen::VectorXd& tau_max);

/// As above with the prediction made sample by sample instead of stored (no (S N) vector):
/// predicted(s, j) says whether row s * N + j has a prediction, prediction(s) computes sample s's N
/// predicted torques [Nm] (called once per sample with a predicted row, the pointer read before the
/// next call). The same sums in the same order as above: the same figures, bit for bit.
std::vector<JointMetrics> torque_metrics(const Eigen::VectorXd& y, int N, const Eigen::VectorXd& tau_max,
                                         const std::function<bool(Eigen::Index s, int j)>& predicted,
                                         const std::function<const double*(Eigen::Index s)>& prediction);

}  // namespace dyncal::host
