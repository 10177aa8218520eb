#include "bounded_problem.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host::detail {

BoundedProblem::BoundedProblem(const RunData& data, FrictionModel model, const MethodSettings& settings,
                               const OptimiserSettings& options)
    : data_(data), model_(model), settings_(settings), options_(options), objective_(data, model, settings.sigma) {
  const Eigen::VectorXd cad = nearest_consistent(settings.prior.mean);
  SearchRanges ranges = search_ranges(data, model, cad, options.range_width);
  const int kf = objective_.friction_per_joint();
  std::vector<bool> logarithmic(static_cast<size_t>(ranges.lo.size()), false);
  for (int i = kStandard; i < static_cast<int>(ranges.lo.size()); ++i) {
    logarithmic[static_cast<size_t>(i)] = is_scale_parameter(model, (i - kStandard) % kf);
  }
  set_box(std::move(ranges.lo), std::move(ranges.hi), logarithmic, cad);
}

Eigen::VectorXd BoundedProblem::with_fitted_amplitudes(const Eigen::VectorXd& x, std::vector<double>& mean,
                                                       std::vector<double>& var) const {
  Eigen::VectorXd y = x;
  std::array<double, 6> m{}, v{};
  objective_.fit_amplitudes(y.data(), lo().data(), hi().data(), &m, &v);
  mean.assign(m.begin(), m.end());
  var.assign(v.begin(), v.end());
  return y;
}

void BoundedProblem::fit_population(std::vector<Eigen::VectorXd>& xs, std::vector<std::vector<double>>& means,
                                    std::vector<std::vector<double>>& vars) const {
  std::vector<double*> ptrs;
  for (Eigen::VectorXd& x : xs) ptrs.push_back(x.data());
  std::vector<std::array<double, 6>> m, v;
  objective_.fit_amplitudes(ptrs, lo().data(), hi().data(), &m, &v);
  means.resize(xs.size());
  vars.resize(xs.size());
  for (size_t i = 0; i < xs.size(); ++i) {
    means[i].assign(m[i].begin(), m[i].end());
    vars[i].assign(v[i].begin(), v[i].end());
  }
}

Eigen::VectorXd BoundedProblem::data_start() const {
  Eigen::VectorXd seed(objective_.dimension());
  seed.head(kStandard) = cad();
  const std::vector<double> f = friction_start(data_, model_, cad());
  seed.tail(static_cast<Eigen::Index>(f.size())) =
      Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
  return seed;
}

std::vector<std::vector<int>> BoundedProblem::scale_groups() const {
  if (is_linear(model_)) return {};
  std::vector<std::vector<int>> groups(6);
  const int kf = friction_count(model_);
  for (int k = 0; k < free_dimension(); ++k) {
    const int i = free_index(k) - kStandard;
    if (i >= 0 && is_scale_parameter(model_, i % kf)) groups[static_cast<size_t>(i / kf)].push_back(k);
  }
  if (groups[0].empty()) return {};
  return groups;
}

double BoundedProblem::joint_cost(double m, double v) const {
  return options_.objective == Objective::eq25 ? std::fabs(m) + options_.k_e * std::sqrt(v) : m * m + v;
}

bool BoundedProblem::memetic_child(const Eigen::VectorXd& best, Eigen::VectorXd& child) const {
  if (is_linear(model_)) return false;
  std::vector<double> mean, var, mean_scan, var_scan;
  child = with_fitted_amplitudes(best, mean, var);
  Eigen::VectorXd y = child;
  const std::vector<double> f = friction_start(data_, model_, child.head(kStandard));
  y.tail(static_cast<Eigen::Index>(f.size())) =
      Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
  y = with_fitted_amplitudes(y, mean_scan, var_scan);
  const int kf = friction_count(model_);
  for (size_t j = 0; j < 6; ++j) {
    if (joint_cost(mean_scan[j], var_scan[j]) < joint_cost(mean[j], var[j])) {
      child.segment(kStandard + kf * static_cast<Eigen::Index>(j), kf) =
          y.segment(kStandard + kf * static_cast<Eigen::Index>(j), kf);
    }
  }
  return true;
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
