#pragma once
// One candidate effect of the diagnosis (private to host_sim/diagnosis): the columns it adds and what
// its search found, whether it comes from the catalogue (candidates.hpp) or beyond it
// (beyond_catalogue.hpp).

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/diagnosis/diagnose_result.hpp"

namespace dyncal::host::detail {

/// A candidate effect: extra columns over the stacked rows (row s * N + j).
struct Candidate {
  Effect effect = Effect::offset;
  std::vector<int> joints;  ///< 0-based
  std::vector<std::string> names;
  Eigen::MatrixXd columns;  ///< (S N) x m
  std::string detail;       ///< e.g. "36 cycles per revolution"
  int searched = 1;         ///< alternatives the search chose among (frequencies, velocity scales, signs)
  double shape = 0;  ///< velocity scale (stribeck), cycles per revolution (position_periodic), ratio |r| (coupling)
  double sign = 1;   ///< coupling: the motor turns with q_i + sign shape q_j
  std::pair<double, double> shape_interval{0, 0};  ///< 95 % interval of shape where searched (coupling ratio)
  std::vector<std::string> replaces;  ///< the model's parameters (columns) it takes the place of (coupled_motor)
  /// A ratio the data do not bound (coupling, coupled_motor): its 95 % interval reaches the end of
  /// the searched range, or the estimate is an end of its own interval (the physical signs cut the
  /// profile there: the likelihood's maximum lies beyond). Never selected; reported as unbounded.
  bool unbounded = false;
  /// The column of a motor's rotor inertia (coupling, coupled_motor; -1: none). Held >= 0 in the
  /// selection: where the whole model's fit makes it negative the column is dropped (held at 0) and
  /// inertia_held set (drop_inertia). The ratio search fits it freely.
  int inertia = -1;
  bool inertia_held = false;
  std::string variable;       ///< shape: the variable its spline is of ("q3", "sgn(qd2) t", ...)
  std::vector<double> knots;  ///< shape: the spline's full knot vector (spline_basis.hpp)
  /// A penalised shape: the rows L of its roughness (shape_roughness_rows) on its columns and the
  /// penalties lambda its weighing chooses among by cross-validation (empty: not penalised); the
  /// last weighing's choice (ModelEffect::penalty) and its effective parameters (CandidatePenalty).
  Eigen::MatrixXd roughness;
  std::vector<double> penalty_grid;
  double penalty = 0;
  double edf = 0;
  /// Beyond the catalogue: the effective samples of its joint's residual after its own local fit
  /// (0: not computed). BIC weighs its joint with at least this many: the noise's correlation, not
  /// that of the structured residual it explains (beyond_catalogue.hpp).
  double n_eff_after = 0;

  /// Parameters it adds to the model: its columns less those it replaces.
  Eigen::Index added_parameters() const { return columns.cols() - static_cast<Eigen::Index>(replaces.size()); }
  /// Parameters it adds as the evidence counts them: a penalised shape's effective ones (edf).
  double weighed_parameters() const { return penalty_grid.empty() ? static_cast<double>(added_parameters()) : edf; }
};

}  // namespace dyncal::host::detail
