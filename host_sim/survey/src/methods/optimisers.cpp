// The survey study's optimisers (Sec. 3.4) on its er20 runs: the general searches of
// search_problem.hpp (gradient, genetic, particle) on the study's BoundedProblem.
#include "dyncal_host/survey/methods/optimisers.hpp"

#include <chrono>
#include <vector>

#include "bounded_problem.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host {

Estimate gradient_descent(const RunData& data, FrictionModel model, const MethodSettings& settings,
                          const OptimiserSettings& options) {
  const auto t0 = std::chrono::steady_clock::now();
  int evaluations = 0;
  // Eq. 7 from the CAD values, friction in the middle of its range.
  const detail::BoundedProblem linear(data, FrictionModel::eq7, settings, options);
  Eigen::VectorXd x0 = linear.full(std::vector<double>(static_cast<size_t>(linear.free_dimension()), 0.5).data());
  x0.head(kStandard) = linear.cad();
  const Eigen::VectorXd linear_solution =
      detail::gradient_search(linear, x0, options.max_evaluations, detail::GradientAlgorithm::slsqp, evaluations);
  if (model == FrictionModel::eq7) return linear.estimate(linear_solution, "gradient descent", t0, evaluations);
  // Another model from the Eq. 7 solution's inertial parameters and each joint's friction start.
  const detail::BoundedProblem problem(data, model, settings, options);
  const std::vector<double> f = friction_start(data, model, linear_solution.head(kStandard));
  Eigen::VectorXd x(kStandard + static_cast<Eigen::Index>(f.size()));
  x.head(kStandard) = linear_solution.head(kStandard);
  x.tail(static_cast<Eigen::Index>(f.size())) =
      Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
  x = detail::gradient_search(problem, x, options.max_evaluations, detail::GradientAlgorithm::slsqp, evaluations);
  return problem.estimate(x, "gradient descent", t0, evaluations);
}

Estimate genetic_algorithm(const RunData& data, FrictionModel model, const MethodSettings& settings,
                           const OptimiserSettings& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.population < 4 || options.generations < 1) throw InputError("genetic algorithm: population >= 4");
  const detail::BoundedProblem problem(data, model, settings, options);
  return problem.estimate(detail::genetic_search(problem, options), "genetic algorithm", t0, options.generations);
}

Estimate particle_filter(const RunData& data, FrictionModel model, const MethodSettings& settings,
                         const OptimiserSettings& options) {
  const auto t0 = std::chrono::steady_clock::now();
  if (options.population < 4 || options.generations < detail::kParticleMovesPerStep) {
    throw InputError("particle filter: >= 4 particles and >= 5 evaluations per particle");
  }
  const detail::BoundedProblem problem(data, model, settings, options);
  int steps = 0;
  const Eigen::VectorXd x = detail::particle_search(problem, options, steps);
  return problem.estimate(x, "particle filter", t0, steps);
}

}  // namespace dyncal::host
