#include "dyncal_host/survey/indices.hpp"

#include <cmath>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"
#include "dyncal_host/survey/survey_data.hpp"

namespace dyncal::host::survey {
double mean_relative_error(const double* set, const double* est, int n) {
  double sum = 0;
  int k = 0;
  for (int i = 0; i < n; ++i) {
    if (set[i] == 0.0) continue;
    sum += std::fabs((set[i] - est[i]) / set[i]);
    ++k;
  }
  return k ? sum / k : 0.0;
}

double link_inertial_error(const Eigen::VectorXd& phi_standard, int link) {
  const auto s = physical_parameters(set_standard().data() + 10 * link);
  const auto e = physical_parameters(phi_standard.data() + 10 * link);
  return mean_relative_error(s.data(), e.data(), 10);
}

double inertial_parameter_error(const Eigen::VectorXd& phi_standard) {
  double sum = 0;
  for (int l = 0; l < kLinks; ++l) sum += link_inertial_error(phi_standard, l);
  return sum / kLinks;
}

Indices evaluate(const Estimate& est, const Scenario& scenario, const Eigen::MatrixXd& tau,
                 const std::array<double, 6>& tau_max) {
  Indices x;
  x.e_d = inertial_parameter_error(est.standard);
  x.e_d_prior = inertial_parameter_error(est.standard_prior);
  const std::vector<double> f = set_friction(scenario, est.model);
  if (f.size() != est.friction.size()) throw InputError("estimate has the wrong number of friction parameters");
  x.e_f = mean_relative_error(f.data(), est.friction.data(), static_cast<int>(f.size()));
  const Eigen::VectorXd set_b = base_map() * set_standard();
  x.e_b = mean_relative_error(set_b.data(), est.base.data(), kBase);
  // Torque error normalised per joint by its maximum driving torque, pooled over joints and samples.
  const double n = static_cast<double>(tau.size());
  double sum = 0, sum_abs = 0, sum_sq = 0;
  for (Eigen::Index s = 0; s < tau.rows(); ++s) {
    for (int j = 0; j < 6; ++j) {
      const double e = (tau(s, j) - est.tau_hat(s, j)) / tau_max[j];
      sum += e;
      sum_abs += std::fabs(e);
      sum_sq += e * e;
    }
  }
  const double mean = sum / n;
  x.e_T = std::fabs(mean);
  x.e_T_abs = sum_abs / n;
  x.e_T_std = std::sqrt(std::max(0.0, sum_sq / n - mean * mean) * n / std::max(n - 1.0, 1.0));
  x.J_e = x.e_d + x.e_f + x.e_T + x.e_T_std;
  x.J_e_prior = x.e_d_prior + x.e_f + x.e_T + x.e_T_std;
  return x;
}

char level(double value, double a, double b) {
  return value < a ? 'A' : (value < b ? 'B' : 'C');
}

}  // namespace dyncal::host::survey
