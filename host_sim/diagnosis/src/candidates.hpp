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

#include "candidate.hpp"
#include "candidate_context.hpp"
#include "dyncal/effect_terms.hpp"
#include "dyncal_host/diagnosis/diagnose_result.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host::detail {

/// One effect kind.
struct EffectSpec {
  Effect effect;
  const char* name;
  std::optional<EffectKind> table_kind;  ///< its model term (lib/ EffectKind; a shape: host only), if it has one
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
