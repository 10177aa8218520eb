// Real-coded genetic algorithm (survey Sec. 3.4 (2)) on the Eq. 25 objective within the search
// ranges. Operators: Deb and Agrawal 1995 (simulated binary crossover, polynomial mutation);
// constraints: Deb 2000 (feasibility rules, no penalty factor).
#include <algorithm>
#include <cmath>
#include <random>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/search_problem.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace {

struct Individual {
  Eigen::VectorXd u;  // unit coordinates
  double f = 0, violation = 0;
};

/// Deb's rules: feasible beats infeasible; two feasible: lower objective; two infeasible: lower violation.
bool better(const Individual& a, const Individual& b) {
  if ((a.violation == 0) != (b.violation == 0)) return a.violation == 0;
  return a.violation == 0 ? a.f < b.f : a.violation < b.violation;
}

constexpr double kEtaCrossover = 15, kEtaMutation = 20, kCrossoverProbability = 0.9;
constexpr int kScanEvery = 100;  ///< generations between memetic steps (SearchProblem::memetic_child)

/// Simulated binary crossover of one variable within [0, 1] (bounded form, Deb and Agrawal).
void sbx(double& a, double& b, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  if (U(rng) > 0.5 || std::fabs(a - b) < 1e-14) return;
  const double y1 = std::min(a, b), y2 = std::max(a, b), r = U(rng);
  auto child = [&](double spread_to_bound) {
    const double beta = 1.0 + 2.0 * spread_to_bound / (y2 - y1);
    const double alpha = 2.0 - std::pow(beta, -(kEtaCrossover + 1));
    const double bq = r <= 1.0 / alpha ? std::pow(r * alpha, 1.0 / (kEtaCrossover + 1))
                                       : std::pow(1.0 / (2.0 - r * alpha), 1.0 / (kEtaCrossover + 1));
    return bq;
  };
  const double c1 = 0.5 * ((y1 + y2) - child(y1) * (y2 - y1));
  const double c2 = 0.5 * ((y1 + y2) + child(1.0 - y2) * (y2 - y1));
  const bool swap = U(rng) < 0.5;
  a = std::clamp(swap ? c2 : c1, 0.0, 1.0);
  b = std::clamp(swap ? c1 : c2, 0.0, 1.0);
}

/// Polynomial mutation of one variable within [0, 1].
void mutate(double& y, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double r = U(rng), m = 1.0 / (kEtaMutation + 1);
  double dq;
  if (r < 0.5) {
    dq = std::pow(2 * r + (1 - 2 * r) * std::pow(1 - y, kEtaMutation + 1), m) - 1;
  } else {
    dq = 1 - std::pow(2 * (1 - r) + 2 * (r - 0.5) * std::pow(y, kEtaMutation + 1), m);
  }
  y = std::clamp(y + dq, 0.0, 1.0);
}

}  // namespace

namespace detail {

Eigen::VectorXd genetic_search(const SearchProblem& problem, const OptimiserSettings& options) {
  if (options.population < 4 || options.generations < 1) throw InputError("genetic algorithm: population >= 4");
  const int D = problem.free_dimension(), N = options.population;
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  // Each individual's friction amplitudes are set to their least-squares values given its inertial
  // and scale parameters, and written back (a Lamarckian repair: separable least squares): the
  // search itself is over the inertial and scale parameters, where an amplitude that compensates a
  // wrong Stribeck velocity can no longer hold a population in a wrong basin.
  // The cost: a sum of per-group (joint) terms of the normalised residual's mean and variance.
  const auto cost = [&](const std::vector<double>& mean, const std::vector<double>& var) {
    double c = 0;
    for (size_t j = 0; j < mean.size(); ++j) {
      c += options.objective == Objective::eq25 ? std::fabs(mean[j]) + options.k_e * std::sqrt(var[j])
                                                : mean[j] * mean[j] + var[j];
    }
    return c;
  };
  // Individuals [from, end) of `inds` evaluated as one population (fit_population: the same
  // results as one by one; the operators draw no random number while evaluating, so the children
  // of a generation are made first and evaluated together).
  std::vector<Eigen::VectorXd> xs;
  std::vector<std::vector<double>> means, vars;
  auto evaluate = [&](std::vector<Individual>& inds, size_t from) {
    xs.clear();
    for (size_t i = from; i < inds.size(); ++i) xs.push_back(problem.full(inds[i].u.data()));
    problem.fit_population(xs, means, vars);
    for (size_t i = from; i < inds.size(); ++i) {
      Individual& ind = inds[i];
      ind.u = problem.unit(xs[i - from]);
      ind.f = cost(means[i - from], vars[i - from]);
      ind.violation = problem.violation(xs[i - from]);
    }
  };
  std::vector<Individual> pop(static_cast<size_t>(N));
  for (auto& ind : pop) {
    ind.u.resize(D);
    for (int k = 0; k < D; ++k) ind.u[k] = U(rng);
  }
  // One individual seeded from the data (no set value, no user start): the consistent CAD values and
  // each joint's friction_start (scale parameters from a log-grid scan). Without it the population
  // could lose the right decade of a Stribeck velocity early (Eq. 4 with noise: J_e 1.22 or 0.87
  // depending on rounding, e_f 0.74 or 0.09).
  pop.front().u = problem.unit(problem.data_start());
  evaluate(pop, 0);
  std::uniform_int_distribution<int> pick(0, N - 1);
  auto tournament = [&]() -> const Individual& {
    const Individual& a = pop[static_cast<size_t>(pick(rng))];
    const Individual& b = pop[static_cast<size_t>(pick(rng))];
    return better(a, b) ? a : b;
  };
  const double p_mutation = 1.0 / D;
  std::vector<Individual> all;
  Eigen::VectorXd child;
  for (int g = 0; g < options.generations; ++g) {
    all = pop;
    for (int i = 0; i < N; i += 2) {
      Individual c1 = tournament(), c2 = tournament();
      if (U(rng) < kCrossoverProbability) {
        for (int k = 0; k < D; ++k) sbx(c1.u[k], c2.u[k], rng);
      }
      for (Individual* c : {&c1, &c2}) {
        for (int k = 0; k < D; ++k)
          if (U(rng) < p_mutation) mutate(c->u[k], rng);
        all.push_back(std::move(*c));
      }
    }
    evaluate(all, static_cast<size_t>(N));
    // Memetic step (nonlinear friction models): the best individual's friction, joint by joint,
    // replaced by friction_start's scan at its own inertial parameters where that lowers the joint's
    // term of the cost; one more child. Given the rigid body the cost is a sum of per-joint terms,
    // each depending on that joint's friction alone, and a joint whose Stribeck velocity sits in a
    // wrong decade is not moved out of it by crossover and mutation elsewhere (Eq. 4 without noise:
    // joint 5's qds 2.65 for the set 0.1, e_f 1.1, without this step). identify's problem (any
    // robot): its child is a short local gradient search from the best individual (without it the search ended 0.03 to
    // 57 chi-square units above the least-squares minimum on twelve synthetic 3-link problems).
    if ((g + 1) % kScanEvery == 0 && problem.memetic_child(problem.full(pop.front().u.data()), child)) {
      all.push_back(Individual{problem.unit(child)});
      evaluate(all, all.size() - 1);
    }
    // (mu + lambda): the best N of parents and children survive.
    std::stable_sort(all.begin(), all.end(), better);
    all.resize(static_cast<size_t>(N));
    pop.swap(all);
  }
  return problem.full(pop.front().u.data());
}

}  // namespace detail

}  // namespace dyncal::host
