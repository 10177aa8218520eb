#include "dyncal_host/identification/methods/search_problem.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host::detail {

void SearchProblem::set_box(Eigen::VectorXd lo, Eigen::VectorXd hi, const std::vector<bool>& logarithmic,
                            Eigen::VectorXd cad) {
  lo_ = std::move(lo);
  hi_ = std::move(hi);
  cad_ = std::move(cad);
  num_links_ = static_cast<int>(cad_.size() / 10);
  free_.clear();
  logarithmic_.clear();
  for (int i = 0; i < dimension(); ++i) {
    if (lo_[i] == hi_[i]) continue;
    free_.push_back(i);
    logarithmic_.push_back(logarithmic[static_cast<size_t>(i)] && lo_[i] > 0);
  }
  cad_norm_.clear();
  for (int l = 0; l < num_links_; ++l) cad_norm_.push_back(pseudo_inertia(cad_.data() + 10 * l).norm());
}

double SearchProblem::scale(int k, const Eigen::VectorXd& x) const {
  const int i = free_[static_cast<size_t>(k)];
  return logarithmic_[static_cast<size_t>(k)] ? x[i] * std::log(hi_[i] / lo_[i]) : hi_[i] - lo_[i];
}

Eigen::VectorXd SearchProblem::full(const double* u) const {
  Eigen::VectorXd x = lo_;
  for (size_t k = 0; k < free_.size(); ++k) {
    const int i = free_[k];
    const double t = std::clamp(u[k], 0.0, 1.0);
    x[i] = logarithmic_[k] ? lo_[i] * std::pow(hi_[i] / lo_[i], t) : lo_[i] + t * (hi_[i] - lo_[i]);
  }
  return x;
}

Eigen::VectorXd SearchProblem::unit(const Eigen::VectorXd& x) const {
  Eigen::VectorXd u(free_.size());
  for (size_t k = 0; k < free_.size(); ++k) {
    const int i = free_[k];
    const double t = logarithmic_[k] ? std::log(std::max(x[i], lo_[i]) / lo_[i]) / std::log(hi_[i] / lo_[i])
                                     : (x[i] - lo_[i]) / (hi_[i] - lo_[i]);
    u[static_cast<Eigen::Index>(k)] = std::clamp(t, 0.0, 1.0);
  }
  return u;
}

void SearchProblem::fit_population(std::vector<Eigen::VectorXd>& xs, std::vector<std::vector<double>>& means,
                                   std::vector<std::vector<double>>& vars) const {
  means.resize(xs.size());
  vars.resize(xs.size());
  for (size_t i = 0; i < xs.size(); ++i) xs[i] = with_fitted_amplitudes(xs[i], means[i], vars[i]);
}

double SearchProblem::violation(const Eigen::VectorXd& x) const {
  double v = 0;
  for (int l = 0; l < num_links_; ++l) {
    const double lam = pseudo_inertia_min_eigenvalue(x.data() + 10 * l, nullptr);
    if (lam < 0) v += -lam / std::max(cad_norm_[static_cast<size_t>(l)], 1e-12);
  }
  return v;
}

double SearchProblem::link_margin(int l) const {
  return 1e-6 * cad_norm_[static_cast<size_t>(l)];
}

}  // namespace dyncal::host::detail
