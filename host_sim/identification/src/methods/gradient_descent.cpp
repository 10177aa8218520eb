// Gradient-based optimisation (survey Sec. 3.4 (1)) with NLopt's SLSQP.
#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <nlopt.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/search_problem.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace {

struct Context {
  const detail::SearchProblem* problem = nullptr;
  std::vector<double> margin;  // lambda_min(J_l) >= margin[l]
  int evaluations = 0;
  double best = INFINITY;  // the lowest cost at a feasible point, and that point
  std::vector<double> best_u;
};

double cost(const std::vector<double>& u, std::vector<double>& grad, void* data) {
  auto* c = static_cast<Context*>(data);
  const detail::SearchProblem& p = *c->problem;
  ++c->evaluations;
  const Eigen::VectorXd x = p.full(u.data());
  Eigen::VectorXd g(x.size());
  const double J = p.least_squares(x.data(), grad.empty() ? nullptr : g.data());
  for (size_t k = 0; k < grad.size(); ++k)
    grad[k] = g[p.free_index(static_cast<int>(k))] * p.scale(static_cast<int>(k), x);
  if (J < c->best) {
    bool feasible = true;
    for (int l = 0; l < p.num_links() && feasible; ++l)
      feasible = pseudo_inertia_min_eigenvalue(x.data() + 10 * l, nullptr) >= c->margin[static_cast<size_t>(l)];
    if (feasible) {
      c->best = J;
      c->best_u = u;
    }
  }
  return J;
}

struct LinkConstraint {
  const detail::SearchProblem* problem;
  int link;
  double margin;  // lambda_min >= margin
};

/// margin - lambda_min(J_link) <= 0.
double link_constraint(const std::vector<double>& u, std::vector<double>& grad, void* data) {
  const auto* c = static_cast<LinkConstraint*>(data);
  const detail::SearchProblem& p = *c->problem;
  const Eigen::VectorXd x = p.full(u.data());
  double g10[10];
  const double lam = pseudo_inertia_min_eigenvalue(x.data() + 10 * c->link, g10);
  for (size_t k = 0; k < grad.size(); ++k) {
    const int i = p.free_index(static_cast<int>(k));
    grad[k] = (i / 10 == c->link && i < p.num_standard()) ? -g10[i % 10] * p.scale(static_cast<int>(k), x) : 0.0;
  }
  return c->margin - lam;
}

}  // namespace

namespace detail {

Eigen::VectorXd gradient_search(const SearchProblem& problem, const Eigen::VectorXd& x0, int max_evaluations,
                                GradientAlgorithm algorithm, int& evaluations) {
  const int D = problem.free_dimension();
  nlopt::opt opt(algorithm == GradientAlgorithm::slsqp ? nlopt::LD_SLSQP : nlopt::LD_CCSAQ, static_cast<unsigned>(D));
  opt.set_lower_bounds(std::vector<double>(static_cast<size_t>(D), 0.0));
  opt.set_upper_bounds(std::vector<double>(static_cast<size_t>(D), 1.0));
  Context ctx;
  ctx.problem = &problem;
  opt.set_min_objective(cost, &ctx);
  std::vector<LinkConstraint> links;
  for (int l = 0; l < problem.num_links(); ++l) {
    // A margin of 1e-6 of the CAD pseudo-inertia's size keeps the result strictly inside the cone.
    ctx.margin.push_back(problem.link_margin(l));
    links.push_back({&problem, l, problem.link_margin(l)});
  }
  for (auto& c : links) opt.add_inequality_constraint(link_constraint, &c, 0.0);
  opt.set_ftol_rel(1e-12);
  opt.set_xtol_rel(1e-10);
  opt.set_maxeval(max_evaluations);
  const Eigen::VectorXd u0 = problem.unit(x0);
  std::vector<double> u(u0.data(), u0.data() + D);
  double f = 0;
  try {
    opt.optimize(u, f);
  } catch (const std::exception& ex) {
    // Stopped on rounding, or SLSQP's line search gave up ("more than iter SQP iterations"): the
    // best feasible point it evaluated is the answer; with none, the method failed.
    if (ctx.best_u.empty()) throw InputError(std::string("gradient descent (NLopt) failed: ") + ex.what());
    u = ctx.best_u;
  }
  evaluations += ctx.evaluations;
  return problem.full(u.data());
}

}  // namespace detail

}  // namespace dyncal::host
