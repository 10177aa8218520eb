#pragma once
// The parameter vector and regressor types of an estimator whose number of parameters P is fixed at
// compile time, or run-time (P = Eigen::Dynamic) within a capacity MaxP: Eigen's fixed-capacity
// dynamic matrices, so no heap either way (PackedCovariance, KalmanFilter, RlsForgetting,
// StreamingLeastSquares).

#include <Eigen/Core>
#include <type_traits>

namespace dyncal {

/// The parameter vector (P entries) and the regressor (N x P) of an estimator with P parameters
/// fixed at compile time, or P = Eigen::Dynamic with capacity MaxP (no heap either way).
template <typename Scalar, int P, int MaxP>
using ParamVectorOf = std::conditional_t<P == Eigen::Dynamic, Eigen::Matrix<Scalar, Eigen::Dynamic, 1, 0, MaxP, 1>,
                                         Eigen::Matrix<Scalar, P, 1>>;
template <typename Scalar, int N, int P, int MaxP>
using RegressorOf =
    std::conditional_t<P == Eigen::Dynamic,
                       Eigen::Matrix<Scalar, N, Eigen::Dynamic, N == 1 ? Eigen::RowMajor : Eigen::ColMajor, N, MaxP>,
                       Eigen::Matrix<Scalar, N, P>>;

/// A parameter vector's initial value: zeros, or empty for the run-time size (reset() sizes it).
template <class Vector>
Vector initial_params() noexcept {
  if constexpr (Vector::SizeAtCompileTime == Eigen::Dynamic) {
    return Vector();
  } else {
    return Vector::Zero();
  }
}

}  // namespace dyncal
