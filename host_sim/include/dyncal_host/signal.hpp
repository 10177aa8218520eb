#pragma once

#include <Eigen/Core>

namespace dyncal::host {

/// Central differences of each column of x (rows = samples, uniform period dt [s]):
/// (x[i+1] - x[i-1]) / (2 dt) inside, one-sided first differences at both ends.
Eigen::MatrixXd central_difference(const Eigen::MatrixXd& x, double dt);

}  // namespace dyncal::host
