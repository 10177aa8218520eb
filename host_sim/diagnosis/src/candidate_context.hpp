#pragma once
// What the candidate library and the shape search read at one greedy step of the diagnosis, and the
// time filtering their columns get (defined in candidates.cpp).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "dyncal/effect_terms.hpp"
#include "dyncal_host/identification/methods/butterworth.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host::detail {

/// What the library reads at one greedy step.
struct CandidateContext {
  const StackedData& data;
  int max_cycles = 64;  ///< position-periodic search: 1..max_cycles cycles per revolution
  /// Load torques for load friction (what it is, S N stacked torque [Nm]); the better one is taken.
  std::vector<std::pair<std::string, Eigen::VectorXd>> load_torques;
  std::vector<std::string> model_names;        ///< parameters of the model so far (no second Ia or offset)
  Eigen::VectorXd residual;                    ///< of the model so far (S N)
  Eigen::VectorXd joint_weights;               ///< the fit's per-joint weights (1 / sigma_j; ones for OLS)
  const Eigen::MatrixXd* model_X = nullptr;    ///< the model so far's design (S N) x p
  const Eigen::VectorXd* model_phi = nullptr;  ///< its fitted coefficients (p)
  std::vector<std::uint32_t> column_joints;    ///< per model column, the joints it is non-zero on (bit j)
  /// The identification's zero-phase low-pass at the data's (decimated) rate, and the sample ranges
  /// of the log's segments: candidate columns are filtered in time as the regressor's were
  /// (parallel filtering), so that a discontinuous column (a friction sign) meets the filtered
  /// torque as the model's own columns do. No filter: columns as computed.
  const ButterworthLowPass* filter = nullptr;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> segments;
  /// Parameters the search refused after choosing them (a torque delay whose interval holds 0): their
  /// candidates are not proposed again.
  std::vector<std::string> refused;
};

/// A motor turning with qd_i + r qd_j: its velocity with the filtered magnitude and the unfiltered
/// sign, 0 inside the band sqrt(band_i^2 + (r band_j)^2) (as identify's coupled motors).
double motor_velocity(const StackedData& d, Eigen::Index s, int i, int j, double r);

/// Filters in time, segment by segment, with c.filter (nothing without one), the columns of
/// `series` (S rows, one per kept sample; blocks of `kind`'s `width` columns) that step with the
/// velocity's sign (effect_column_steps): they are built from the unfiltered velocity's sign and
/// get the low-pass once, as tau did. The others are built from the filtered q, qd, qdd and have
/// had it (filtering them again would low-pass their qdd twice against tau's once).
void filter_in_time(const CandidateContext& c, Eigen::MatrixXd& series, EffectKind kind, int width);

}  // namespace dyncal::host::detail
