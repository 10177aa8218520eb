#pragma once
// The diagnosis's library of candidate effects (private to host_sim/diagnosis): one table entry per
// effect kind — how it builds its columns (lib/ effect_columns where the effect is a table term),
// which signs of its fitted parameters are physical, and how a found effect is explained.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "candidate_context.hpp"
#include "dyncal/effect_terms.hpp"
#include "dyncal_host/diagnosis/diagnose_result.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/model/stacked_data.hpp"

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
  /// Beyond the catalogue: the effective samples of its joint's residual after its own local fit
  /// (0: not computed). BIC weighs its joint with at least this many: the noise's correlation, not
  /// that of the structured residual it explains (beyond_catalogue.hpp).
  double n_eff_after = 0;

  /// Parameters it adds to the model: its columns less those it replaces.
  Eigen::Index added_parameters() const { return columns.cols() - static_cast<Eigen::Index>(replaces.size()); }
};

/// One effect kind.
struct EffectSpec {
  Effect effect;
  const char* name;
  std::optional<EffectKind> table_kind;  ///< its parameter-table term (lib/), if it has one
  bool per_pair;                         ///< candidates per joint pair i < j (else per joint i)
  /// Appends this kind's candidates for joint i (per_pair: joints i < j) to `out`.
  void (*generate)(const CandidateContext& c, int i, int j, std::vector<Candidate>& out);
  /// Whether the fitted parameters (the candidate's columns, in order) have physical signs.
  bool (*physical)(const Eigen::VectorXd& added);
  /// What a found effect means, with its fitted parameters.
  std::string (*explain)(const Candidate& c, const std::vector<double>& params);
  /// A kind of the catalogue (weighed first at every step), or one beyond it (torque_delay, shape:
  /// weighed only when no catalogue kind qualifies; beyond_catalogue.hpp).
  bool catalogue = true;
};

/// The candidate with its rotor-inertia column (c.inertia) dropped: the motor's inertia held at 0,
/// the optimum of the least-squares fit under the bound inertia >= 0 when the free fit is negative.
Candidate drop_inertia(Candidate c);

/// The table, in report order (stribeck, asymmetric_friction, velocity_power, load_friction,
/// rotor_inertia, offset, position_periodic, coupling, coupled_motor, drift).
const std::vector<EffectSpec>& effect_specs();
const EffectSpec& effect_spec(Effect e);

/// Every candidate of the current step among the catalogue's kinds (`catalogue`) or those beyond it:
/// per joint the per-joint kinds in table order, then every joint pair's per-pair kinds; only on
/// `joints` (0-based; empty: every joint).
/// Reported as progress of `progress_task` (progress.hpp), per joint and joint pair.
std::vector<Candidate> candidate_library(const CandidateContext& c, bool catalogue, const std::string& progress_task,
                                         const std::vector<int>& joints = {});

/// "joint 3: " or "joints 5 and 6: " followed by the kind's explanation.
std::string explain(const Candidate& c, const std::vector<double>& params);

}  // namespace dyncal::host::detail
