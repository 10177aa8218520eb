#pragma once
// Cubic B-spline regression bases for the diagnosis's search beyond its catalogue (private to
// host_sim/diagnosis): a smooth function of one variable as a linear combination of columns, so the
// cross-validated least squares that weighs the catalogue's effects weighs a shape too.

#include <Eigen/Core>
#include <vector>

namespace dyncal::host::detail {

/// Knots of a cubic regression spline of `x` with `interior` interior knots at the quantiles
/// (k / (interior + 1)) of x, repeated values removed (a variable that rests at one value gets
/// fewer), boundaries at x's extremes: the full knot vector, the boundaries repeated four times.
/// Empty when x spans no interval.
std::vector<double> spline_knots(const Eigen::Ref<const Eigen::VectorXd>& x, int interior);

/// The B-spline basis of `knots` (spline_knots) at every x (clamped into the knots' span): x.size()
/// rows, knots.size() - 4 columns, each row summing to 1 (de Boor's recurrence).
Eigen::MatrixXd spline_basis(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<double>& knots);

}  // namespace dyncal::host::detail
