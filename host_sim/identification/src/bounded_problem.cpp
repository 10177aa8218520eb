#include "bounded_problem.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal_host/identification/standard_parameters.hpp"

namespace dyncal::host::detail {

BoundedProblem::BoundedProblem(const RunData& data, FrictionModel model, const MethodSettings& settings,
                               const OptimiserSettings& options)
    : data_(data),
      model_(model),
      settings_(settings),
      options_(options),
      objective_(data, model, settings.sigma),
      ranges_(search_ranges(data, model, nearest_consistent(settings.prior.mean), options.range_width)),
      cad_(nearest_consistent(settings.prior.mean)) {
  const int kf = objective_.friction_per_joint();
  for (int i = 0; i < static_cast<int>(ranges_.lo.size()); ++i) {
    if (ranges_.fixed(i)) continue;
    free_.push_back(i);
    logarithmic_.push_back(i >= kStandard && is_scale_parameter(model, (i - kStandard) % kf) && ranges_.lo[i] > 0);
  }
}

double BoundedProblem::scale(int k, const Eigen::VectorXd& x) const {
  const int i = free_[static_cast<size_t>(k)];
  return logarithmic_[static_cast<size_t>(k)] ? x[i] * std::log(ranges_.hi[i] / ranges_.lo[i])
                                              : ranges_.hi[i] - ranges_.lo[i];
}

Eigen::VectorXd BoundedProblem::full(const double* u) const {
  Eigen::VectorXd x = ranges_.lo;
  for (size_t k = 0; k < free_.size(); ++k) {
    const int i = free_[k];
    const double t = std::clamp(u[k], 0.0, 1.0);
    x[i] = logarithmic_[k] ? ranges_.lo[i] * std::pow(ranges_.hi[i] / ranges_.lo[i], t)
                           : ranges_.lo[i] + t * (ranges_.hi[i] - ranges_.lo[i]);
  }
  return x;
}

Eigen::VectorXd BoundedProblem::unit(const Eigen::VectorXd& x) const {
  Eigen::VectorXd u(free_.size());
  for (size_t k = 0; k < free_.size(); ++k) {
    const int i = free_[k];
    const double t = logarithmic_[k] ? std::log(std::max(x[i], ranges_.lo[i]) / ranges_.lo[i]) /
                                           std::log(ranges_.hi[i] / ranges_.lo[i])
                                     : (x[i] - ranges_.lo[i]) / (ranges_.hi[i] - ranges_.lo[i]);
    u[static_cast<Eigen::Index>(k)] = std::clamp(t, 0.0, 1.0);
  }
  return u;
}

Eigen::VectorXd BoundedProblem::with_fitted_amplitudes(const Eigen::VectorXd& x, std::array<double, 6>& mean,
                                                       std::array<double, 6>& var) const {
  Eigen::VectorXd y = x;
  objective_.fit_amplitudes(y.data(), ranges_.lo.data(), ranges_.hi.data(), &mean, &var);
  return y;
}

Estimate BoundedProblem::estimate(const Eigen::VectorXd& x, const char* method,
                                  std::chrono::steady_clock::time_point t0, int iterations) const {
  Estimate e;
  e.method = method;
  e.model = model_;
  e.standard = x.head(kStandard);
  e.base = base_map() * e.standard;
  // The optimisers have no prior (the survey's), so the directions the data do not determine stay
  // where the search left them; standard_prior (e_d prior) fills those from the CAD prior, as for
  // the base-parameter methods: same base parameters, same torques.
  e.standard_prior = standard_from_base(e.base, settings_.prior);
  e.friction.assign(x.data() + kStandard, x.data() + x.size());
  e.iterations = iterations;
  for (int l = 0; l < kLinks; ++l) {
    e.pseudo_inertia_min_eigenvalue.push_back(pseudo_inertia_min_eigenvalue(x.data() + 10 * l, nullptr));
  }
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  complete_estimate(e, data_, settings_);
  return e;
}

}  // namespace dyncal::host::detail
