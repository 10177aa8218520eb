#pragma once
// The options of identify() (identification/pipeline/identify.hpp), shared by every method, the
// prediction of other logs and the diagnosis.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// Options of `dyncal identify` (defaults follow the survey and Gautier's practice).
/// Highest Butterworth order identify accepts (even orders, cascaded second-order sections).
inline constexpr int kMaxFilterOrder = 8;

/// Options of identify(); each is range-checked against the log before any work (InputError naming
/// the option and its admissible range).
struct IdentifyOptions {
  /// wls (Gautier's per-joint weights) | ols (IDIM-OLS) | kf | rls | pcls (physically consistent WLS) |
  /// gd | ga | pf (the survey's optimisers on the weighted data: search_consistent) | iv (IDIM-IV:
  /// instrumental_variables.hpp, needs closed_loop)
  std::string method = "wls";
  unsigned terms = 0;                ///< dyncal::term bits (rigid body always included)
  std::vector<ModelEffect> effects;  ///< effect terms after the compiled ones (model_effects.hpp): not kf, rls
  std::vector<CoupledMotor> motors;  ///< coupled motors (model_effects.hpp): rows of the motor-velocity map
  /// Torque channels' delays undone on the log before anything else (logs/torque_delay.hpp)
  std::vector<TorqueDelay> torque_delays;
  int filter_order = 4;             ///< Butterworth order (zero-phase: twice the attenuation)
  double cutoff_hz = 20.0;          ///< low-pass cut-off for q, tau and the regressor columns
  int decimate = 0;                 ///< decimation factor; 0: floor(fs / (25 * cutoff)), at least 1
  int folds = 5;                    ///< blocked k-fold cross-validation
  double block_seconds = 0.5;       ///< length of the contiguous blocks dealt to the folds in turn
  double validate_last = 0.0;       ///< > 0: plain time split, this fraction at the end validates
  double rls_mu = 0.9999;           ///< forgetting factor of RLS (survey Eq. 23)
  double p0 = 1e6;                  ///< initial covariance diag of KF and RLS (prior ignorance)
  double min_speed_fraction = 0.0;  ///< fit only rows with |qd_j| >= this fraction of joint j's top speed
  bool load_regressor = false;      ///< also stack Y(q, qd, 0) (StackedData::W_load): the load torque's regressor
  double prior_std = 0.5;      ///< pcls: the prior's relative std (kPriorRelativeStd); 0: no prior, consistency alone
  double range_width = 3.0;    ///< gd, ga, pf: standard parameters within nominal +- this x their scale
  std::uint64_t seed = 1;      ///< ga, pf: random seed
  int search_evaluations = 0;  ///< gd: cost evaluations, ga: generations, pf: evaluations per particle; 0: default
  bool friction_per_joint = false;  ///< ignore robot.json's coupling: friction and rotor inertia per joint (the log's
                                    ///< conversion still uses the transmission); lets diagnose rediscover a coupling
  /// wls, ols: Coulomb and viscous friction and rotor inertia held >= 0 (sign_constrained.hpp:
  /// Lawson-Hanson on the weighted data's triangular factor), what a drive's table must hold
  /// (lib/ table_check.hpp); a parameter held at 0 is named in the notes, its std 0.
  bool sign_constraints = false;
  /// Refuse (InputError, exit 2) a log that leaves a parameter of the model not determined
  /// (identifiability.hpp) instead of dropping it with a note.
  bool strict = false;
  /// iv: the closed-loop simulation of the logged run under the drive's known control law (identify
  /// --law; drive_law.hpp): the log's grid (t, segments, period) with q the plant's positions at its
  /// samples (tau 0), the plant's standard parameters phi_standard (10 N, generated order) and
  /// Coulomb Fc [Nm] and viscous Fv [Nm s/rad] friction per joint (N). Throws InputError (a trip).
  std::function<JointLog(const JointLog& grid, const Eigen::VectorXd& phi_standard, const Eigen::VectorXd& Fc,
                         const Eigen::VectorXd& Fv)>
      closed_loop;
};

}  // namespace dyncal::host
