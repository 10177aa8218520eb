#pragma once
// The survey's optimisation methods (Sec. 3.4) on the standard parameters and the friction
// parameters within search ranges, with each link's pseudo-inertia kept positive definite
// (physical feasibility, Wensing et al. 2017): gradient-based (NLopt SLSQP, least-squares
// objective), a genetic algorithm (Eq. 25 objective) and a particle filter (the posterior under the
// assumed noise); the last two need no initial values, only the ranges. Deterministic for a seed;
// budgets are evaluation counts, not times.

#include "dyncal_host/identification/methods/optimiser_settings.hpp"
#include "dyncal_host/survey/methods/methods.hpp"
#include "dyncal_host/survey/methods/objective.hpp"

namespace dyncal::host {

/// Gradient-based: NLopt SLSQP from the CAD values on sum_j ||e_j / sigma_j||^2 / S (variables
/// scaled to their ranges), one inequality lambda_min(J_l) >= 0 per link with its analytic gradient.
Estimate gradient_descent(const RunData& data, FrictionModel model, const MethodSettings& settings,
                          const OptimiserSettings& options = {});

/// Real-coded genetic algorithm (Deb 2000 constraint handling: feasible beats infeasible, less
/// violation beats more): binary tournaments, simulated binary crossover (eta 15, p 0.9), polynomial
/// mutation (eta 20, p 1/D), (mu + lambda) survival; population uniform in the ranges.
Estimate genetic_algorithm(const RunData& data, FrictionModel model, const MethodSettings& settings,
                           const OptimiserSettings& options = {});

/// Particle filter for static parameters: a sequential Monte Carlo sampler (Del Moral, Doucet and
/// Jasra 2006) from the uniform distribution on the feasible ranges to the posterior of the torques
/// under the assumed noise (MethodSettings::sigma), with adaptive tempering, systematic resampling
/// and random-walk Metropolis moves (particles' covariance). `generations` counts evaluations per
/// particle (5 moves a step). Returns the posterior mean.
Estimate particle_filter(const RunData& data, FrictionModel model, const MethodSettings& settings,
                         const OptimiserSettings& options = {});

}  // namespace dyncal::host
