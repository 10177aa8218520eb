#pragma once
// Cubic B-spline regression bases: a smooth function of one variable as a linear combination of
// columns, so that least squares fits it. The diagnosis's shapes beyond its catalogue and the shape
// effect term that identify fits and predict applies (model_effects.hpp) are these columns.

#include <Eigen/Core>
#include <vector>

namespace dyncal::host {

/// Knots of a cubic regression spline of `x` with `interior` interior knots at the quantiles
/// (k / (interior + 1)) of x, repeated values removed (a variable that rests at one value gets
/// fewer), boundaries at x's extremes: the full knot vector, the boundaries repeated four times.
/// Empty when x spans no interval.
std::vector<double> spline_knots(const Eigen::Ref<const Eigen::VectorXd>& x, int interior);

/// The B-spline basis of `knots` (spline_knots) at every x (clamped into the knots' span): x.size()
/// rows, knots.size() - 4 columns, each row summing to 1 (de Boor's recurrence).
Eigen::MatrixXd spline_basis(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<double>& knots);

/// The columns of a shape effect at x (x.size() rows; outside the knots' span x is clamped to it: the
/// shape is held at its end values):
/// - spline_basis(x, knots) without its first basis function (the rest stay identifiable next to a
///   model's offset or Coulomb column): knots.size() - 5 columns;
/// - without_linear: the basis times Z, Z an orthonormal basis (QR) of the coefficient vectors
///   orthogonal to the constant's and x's (all 1, and the Greville abscissae: the B-splines
///   reproduce both exactly), so that no combination of the columns but 0 is constant or linear in
///   x: knots.size() - 6 columns. For a shape of the model's own torque, whose linear part would
///   scale every parameter.
Eigen::MatrixXd shape_basis(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<double>& knots,
                            bool without_linear = false);

/// The number of shape_basis' columns.
inline int shape_basis_columns(const std::vector<double>& knots, bool without_linear) {
  const int m = static_cast<int>(knots.size()) - (without_linear ? 6 : 5);
  return m > 0 ? m : 0;
}

/// Points of a shape's curve in a report (diagnose's effects, identify's shapes).
inline constexpr int kShapeCurvePoints = 101;

/// A shape's curve for a plot or a report: `points` values x evenly over the knots' span and the
/// shape's torque there, shape_basis(x, knots, without_linear) times `coefficients` (its column
/// count of them; empty x and y otherwise), less its mean over those points. Centred as a generalised
/// additive model's smooth terms are: the data determine a shape's variation, while its level trades
/// with the model's other columns (a joint's gravity, a constant the basis nearly spans).
void shape_curve(const std::vector<double>& knots, const std::vector<double>& coefficients, bool without_linear,
                 int points, std::vector<double>& x, std::vector<double>& y);

}  // namespace dyncal::host
