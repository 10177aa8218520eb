#pragma once

#include <Eigen/Core>
#include <cmath>

namespace dyncal {

/// True when every coefficient of `m` is finite (no NaN, no infinity). Allocation-free.
template <typename Derived>
bool all_finite(const Eigen::MatrixBase<Derived>& m) noexcept {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    for (Eigen::Index i = 0; i < m.rows(); ++i) {
      if (!std::isfinite(m(i, j))) return false;
    }
  }
  return true;
}

}  // namespace dyncal
