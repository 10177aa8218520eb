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

/// A shape's roughness as rows L (2 (knots' distinct values - 1) x shape_basis_columns): for the
/// shape f = shape_basis(., knots, without_linear) c, |L c|^2 is the integral of f''(x)^2 over the
/// knots' span [Nm^2 / unit(x)^3], exactly (f'' is linear between knots: two Gauss-Legendre points
/// per interval). The penalty of a penalised regression spline (O'Sullivan's, as smoothing splines
/// have): its null space is f linear in x. Empty (0 x 0) when the shape has no columns.
Eigen::MatrixXd shape_roughness_rows(const std::vector<double>& knots, bool without_linear);

/// Points of a shape's curve in a report (diagnose's effects, identify's shapes).
inline constexpr int kShapeCurvePoints = 101;

/// A shape's curve for a plot or a report: `points` values x evenly over the knots' span and the
/// shape's torque there, shape_basis(x, knots, without_linear) times `coefficients` (its column
/// count of them; empty x and y otherwise), less its mean over those points. Centred as a generalised
/// additive model's smooth terms are: the data determine a shape's variation, while its level trades
/// with the model's other columns (a joint's gravity, a constant the basis nearly spans).
void shape_curve(const std::vector<double>& knots, const std::vector<double>& coefficients, bool without_linear,
                 int points, std::vector<double>& x, std::vector<double>& y);

/// A shape's pointwise 95 % band at shape_curve's points (`knots`, without_linear as its variable
/// has it; y: that curve, centred): the delete-a-group jackknife of the curve over the fits without
/// each fold (`fold_coefficients`: K >= 2 of them, the shape's shape_basis_columns coefficients
/// each; jackknife.hpp), around y: lo = y - half, hi = y + half [Nm]. It holds the coefficients'
/// correlation and what the model still lacks. lo = hi = y with fewer than two replicates or
/// replicates of another size.
void shape_band(const std::vector<double>& knots, bool without_linear,
                const std::vector<std::vector<double>>& fold_coefficients, const std::vector<double>& y,
                std::vector<double>& lo, std::vector<double>& hi);

}  // namespace dyncal::host
