#pragma once
// Settings of the optimisation methods (survey Sec. 3.4): gradient-based, genetic algorithm,
// particle filter (optimisers.hpp for the survey study, consistent_least_squares.hpp's
// search_consistent for identify on any robot). Budgets are evaluation counts, not times.

#include <cstdint>

namespace dyncal::host {

/// The genetic algorithm's cost over the residuals e_j / sigma_j.
enum class Objective {
  least_squares,  ///< sum_j mean_j^2 + var_j: the Gaussian likelihood's, which its amplitude fit minimises
  eq25,           ///< survey Eq. 25: sum_j |mean_j| + k_e std_j
};

struct OptimiserSettings {
  /// Inertial ranges: in the survey, CAD value +- range_width x |CAD value| (search_ranges); in
  /// identify, nominal value +- range_width x its scale (search_consistent).
  double range_width = 0.4;
  double k_e = 1.0;                                ///< Eq. 25 weight of the residual standard deviation
  Objective objective = Objective::least_squares;  ///< the genetic algorithm's cost
  std::uint64_t seed = 1;                          ///< GA and particle filter
  int population = 120;                            ///< GA population / particle count
  int generations = 1500;                          ///< GA generations / particle-filter iterations
  int max_evaluations = 3000;                      ///< gradient-based: objective evaluations
};

}  // namespace dyncal::host
