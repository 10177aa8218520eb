#pragma once
// The diagnosis's candidates beyond its catalogue (private to host_sim/diagnosis; issue 71,
// docs/diagnose.md "Beyond the catalogue"): what the greedy search weighs once no kind of the table
// qualifies. A delay of one joint's torque channel against its position channel, and a shape: a
// smooth function (cubic regression spline) of one variable a real arm's residual can follow.

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "candidate.hpp"
#include "candidate_context.hpp"

namespace dyncal::host::detail {

/// The delay of joint i's torque channel: tau_meas(t) = tau(t - delta) ~ tau(t) - delta dtau/dt, one
/// column -d/dt of the model's prediction of joint i (c.model_X c.model_phi, central differences in
/// each segment), coefficient delta [s] (positive: the torque lags the position). None on a joint
/// that has one ("delay<i>" among the model's names) or whose delay was refused (c.refused). The
/// chosen one is refined by delay_column.
void torque_delay(const CandidateContext& c, int i, int, std::vector<Candidate>& out);

/// The secant column of a delay delta0 [s] for a prediction p (S, at the kept samples t):
/// (p(t - delta0) - p(t)) / delta0, p(t - delta0) by cubic (Catmull-Rom) interpolation inside each
/// segment (held at its ends); -dp/dt when delta0 is 0. With it, tau_meas = p + delta column is exact
/// at delta = delta0: refitting delta with the column rebuilt at the last estimate (a fixed point)
/// removes the first-order expansion's bias at friction's filtered steps.
Eigen::VectorXd delay_column(const Eigen::VectorXd& t,
                             const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments,
                             const Eigen::VectorXd& p, double delta0);

/// The kept samples of joint j (S flags) around a step of its measured torque: where its unfiltered
/// torque d.tau_raw jumps between two samples by more than the model's filtered prediction p (S)
/// changes there, beyond kStandstillQuantile (0.1 % two-sided) times that difference's own scale
/// (1.4826 MAD over the joint's sample pairs, inside each segment), and one cut-off period
/// (rate / cutoff samples) either side of it, the filtered step's span; not where joint j's friction
/// sign goes from + to - or back within that span (a reversal's step falls at a phase of its own
/// each time: the sampling's misplacement averages out; a start or stop is kept). A sampled step
/// shows where it happened only to within a sample, at one sub-sample phase for every step of a
/// periodic motion's rests or a planned profile's corners on the controller's clock: a delay read
/// from those samples follows that phase (docs/diagnose.md "A delay read from sampled steps").
/// None without unfiltered torques (d.tau_raw empty).
std::vector<char> torque_step_samples(const StackedData& d,
                                      const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments, int j,
                                      const Eigen::VectorXd& p);

/// The shapes on joint i: for each variable of shape_variables, a cubic regression spline with
/// interior knots at its quantiles, the first basis function left out (the rest with the model's
/// columns stay identifiable); a variable times sgn(qd_i) filtered in time as the regressor's
/// friction columns were. The variables are screened by the local BIC of the joint's residual on
/// 8 knots' columns alone (n_eff of the residual left); the best one becomes three candidates, 4,
/// 8 and 16 interior knots, among which the cross-validated weighing chooses. Each counts the whole
/// family (variables x knot counts) as searched (the BIC's look-elsewhere term).
void shape(const CandidateContext& c, int i, int, std::vector<Candidate>& out);

/// The names of a shape's variables on joint i of an N-joint arm (model_effects.hpp's ShapeVariable):
/// t, q_i, qd_i, qdd_i, the model's torque tau_model_i, q and qd of the neighbour joints i - 1 and
/// i + 1, and sgn(qd_i) times t, q_i and tau_model_i.
std::vector<std::string> shape_variables(int i, int num_joints);

/// The 95 % interval of a delay (the last column of X, coefficient phi's last entry) on joint j,
/// the wider of two: (1) its standard error from the weighted fit (rows times `weights` per joint,
/// Frisch-Waugh against the other columns) with the residual's own scale on joint j, inflated for
/// the residual's correlation by sqrt(samples / n_eff_j), times 1.96; (2) the delete-a-group
/// jackknife of the estimates without each fold (`fold_delays`, K of them: variance (K - 1) / K
/// times their sum of squared deviations), times Student's t with K - 1 degrees of freedom, which
/// also holds what the model still lacks and the residual's uneven spread. Widened on both sides by
/// the share of the delay's information (its column's part orthogonal to the others, squared, on
/// joint j's rows) that comes from the samples around the torque's steps (`steps`:
/// torque_step_samples) times half the log's sample period `raw_period` [s]: each sampled step is
/// placed only to within a sample, and where the steps share one sub-sample phase that error does
/// not average out, so it is a bound added, not a variance. *step_share: that share.
std::pair<double, double> delay_interval(const StackedData& d, const Eigen::MatrixXd& X, const Eigen::VectorXd& phi,
                                         const Eigen::VectorXd& weights, int j, double n_eff_j,
                                         const std::vector<double>& fold_delays, const std::vector<char>& steps,
                                         double raw_period, double* step_share);

}  // namespace dyncal::host::detail
