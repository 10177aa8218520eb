#pragma once
// Payload identification with the arm's calibrated model fixed (docs/payload.md): the load rigidly
// attached to the last link changes only that link's 10 standard parameters, so the torque a log
// with the load has beyond the arm's model is Y_b(q, qd, qdd) K_N dphi (K_N: the base map's columns
// of link N, Gautier), linear in the payload's standard parameters dphi. Least squares on those 10
// columns (Gautier's per-joint weights), the parameters this log does not determine decided from
// the data and held at 0 (identifiability.hpp), then the payload's mass, centre of mass and inertia
// about it with standard deviations (delta method) and a verdict each.

#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "dyncal_host/identification/methods/identifiability.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"

namespace dyncal::host {

/// One payload quantity: mass [kg], a centre-of-mass coordinate [m] or an inertia entry about the
/// centre of mass [kg m^2], in the last link's frame (the generated model's link N frame).
struct PayloadQuantity {
  std::string name;  ///< mass, com_x, com_y, com_z, I11, I12, I13, I22, I23, I33
  std::string unit;
  double value = 0;  ///< NaN when not determined
  double std = 0;    ///< NaN when not determined (autocorrelation-inflated, as identify's)
  double scale = 0;  ///< the size the verdict compares 1.96 std with (docs/payload.md)
  Verdict verdict = Verdict::not_determined;
};

struct PayloadResult {
  std::string robot, model, params_source, log_source;
  int link = 0;      ///< the link the payload is attached to (1-based: the last)
  long samples = 0;  ///< kept samples of the log
  /// The payload's standard parameters [XX XY XZ YY YZ ZZ MX MY MZ M] (link frame, about its
  /// origin; Khalil-Kleinfinger), 0 where not determined, and their std (NaN there).
  Eigen::Matrix<double, 10, 1> standard = Eigen::Matrix<double, 10, 1>::Zero();
  Eigen::Matrix<double, 10, 1> standard_std = Eigen::Matrix<double, 10, 1>::Zero();
  std::vector<std::string> undetermined;    ///< standard parameters this log does not determine
  std::vector<PayloadQuantity> quantities;  ///< mass, centre of mass (3), inertia about it (6)
  bool inertia_determined = false;          ///< every inertia entry at least poorly determined
  double min_eigenvalue = 0;                ///< pseudo-inertia's smallest (inertia determined only)
  double inflation = 1;                     ///< the residual's autocorrelation factor S / n_eff
  /// The std includes the arm's calibration error (the parameter file's std propagated), not only
  /// this log's noise.
  bool arm_error_included = false;
  /// The std includes the torque constants' error (a log of currents, the arm set's Kt with std).
  bool torque_constant_error_included = false;
  std::vector<JointMetrics> unloaded;  ///< this log predicted by the arm's model alone
  std::vector<JointMetrics> loaded;    ///< out-of-fold (blocked folds): arm model plus the payload
  std::vector<std::string> notes;
};

/// The payload of `log` (a run with the load on the last link) with the arm's parameters `arm` (a
/// dyncal identify --params set for `robot`) fixed. The log is prepared as identify prepares it
/// (`options`: filter, cut-off, decimation, folds for the loaded model's validation; terms and effects
/// are the parameter set's). Throws InputError: parameters for another robot, a log the preparation
/// refuses, a log that determines no payload parameter, or a payload mass the log does not
/// determine (its 95 % interval holds 0: no load to speak of, or too little motion).
/// from_current: the log's torque is motor currents times torque constants (tau = N^T diag(Kt) i,
/// robot.transmission N): a relative error e_k of Kt_k scales motor k's share of the load's torque
/// (the arm's model, identified with the same Kt, scales with its data), moving the payload by
/// G_k e_k, G_k the weighted least-squares solution for the load torque's motor-k share N^T e_k
/// (N^-T C theta)_k; with the arm set's Kt std (ParameterSet::torque_constants_std, a fit from a
/// known load) sum_k (std_k / Kt_k)^2 G_k G_k^T is added to the covariance, without them a note says
/// the constants' error is not in the interval.
PayloadResult identify_payload(const RobotDescription& robot, const JointLog& log, const ParameterSet& arm,
                               const IdentifyOptions& options, bool from_current = false);

/// The arm's parameters with the payload's standard parameters (10, link N frame) added to link N:
/// the base parameters move by K_N dphi; terms, effects and friction are the arm's. Its source says
/// so; it carries no std (the arm's no longer describes the loaded base parameters). Throws InputError if the set's
/// robot is not compiled.
ParameterSet with_payload(const ParameterSet& arm, const RobotDescription& robot,
                          const Eigen::Matrix<double, 10, 1>& payload_standard);

/// The loaded arm's parameter file (identify --params format: predict, flash, table, diagnose and
/// payload read it), with the payload it carries recorded under "payload".
nlohmann::json loaded_parameter_file_json(const ParameterSet& loaded, const PayloadResult& r);

/// The payload report: the quantities with std, verdict and 95 % interval, what is not determined,
/// the prediction error before and after.
void print_payload_report(std::ostream& out, const PayloadResult& r);
nlohmann::json payload_report_json(const PayloadResult& r);

}  // namespace dyncal::host
