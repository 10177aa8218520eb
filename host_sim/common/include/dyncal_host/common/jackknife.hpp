#pragma once
// The delete-a-group jackknife's 95 % half-width: the interval of a quantity estimated once on all
// data and once without each group (the blocked cross-validation's folds), for the diagnosis's
// delays and the shapes' bands of diagnose and identify.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "dyncal_host/common/normal_quantile.hpp"

namespace dyncal::host {

/// Student's t two-sided 95 % quantile for `dof` degrees of freedom: tabulated to 10, above by the
/// Cornish-Fisher expansion around the normal's (error below 1e-3 there).
inline double student_t975(int dof) {
  static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228};
  if (dof >= 1 && dof <= 10) return table[dof - 1];
  const double z = kZ95, n = std::max(1, dof);
  return z + (z * z * z + z) / (4 * n) + (5 * std::pow(z, 5) + 16 * z * z * z + 3 * z) / (96 * n * n);
}

/// The 95 % half-width of the delete-a-group jackknife over K >= 2 replicates replicate(0..K-1)
/// (the fits without each group): Student's t with K - 1 degrees of freedom times the square root
/// of (K - 1) / K times their sum of squared deviations from their mean (Efron and Tibshirani,
/// "An Introduction to the Bootstrap", ch. 11).
template <class Replicate>
double jackknife_half_width(size_t K, Replicate replicate) {
  double mean = 0, ss = 0;
  for (size_t k = 0; k < K; ++k) mean += replicate(k) / static_cast<double>(K);
  for (size_t k = 0; k < K; ++k) ss += (replicate(k) - mean) * (replicate(k) - mean);
  return student_t975(static_cast<int>(K) - 1) * std::sqrt(static_cast<double>(K - 1) / static_cast<double>(K) * ss);
}

}  // namespace dyncal::host
