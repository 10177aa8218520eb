#pragma once
// What an identification method (survey Sec. 3) returns: base, standard and friction parameters,
// the torque it predicts, and how it got there.

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "dyncal_host/identification/methods/friction_parameters.hpp"

namespace dyncal::host {

struct Estimate {
  std::string method;
  FrictionModel model = FrictionModel::eq7;
  Eigen::VectorXd base;            ///< 36 base parameters
  Eigen::VectorXd standard;        ///< 60 standard parameters as the method gives them (from base:
                                   ///< the minimum-norm ones, as a pseudo-inverse of the standard regressor)
  Eigen::VectorXd standard_prior;  ///< 60 with the CAD prior in the unidentifiable directions
  std::vector<double> friction;    ///< joint-major, friction_parameter_names order
  Eigen::MatrixXd tau_hat;         ///< S x 6 torque of Eq. 2 with the estimate [Nm]
  double seconds = 0;              ///< wall time of the calculation
  int iterations = 0;              ///< outer iterations (IDIM-IV, optimisers), 0 if not iterative
  /// Physically consistent methods: per link the smallest eigenvalue of J = L L^T from the factor L
  /// itself (sigma_min(L)^2, exact to rounding even where J is nearly singular); empty otherwise.
  std::vector<double> pseudo_inertia_min_eigenvalue;
  std::string note;
};

}  // namespace dyncal::host
