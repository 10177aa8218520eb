#pragma once
// Contact detection with the calibrated model (docs/monitor.md): lib/'s generalised-momentum
// observer run over a log, the residual's statistics on contact-free motion (the calibration's own
// log: identify writes them into the parameter file), per-joint thresholds for a stated false-alarm
// rate from those statistics (lib/ contact_threshold.hpp), and the contacts found in a log.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// The detection time the default gain is set for [s]: the observer's time constant 1 / K is a
/// quarter of it, so a step of external torque shows 98 % of its size after that time.
inline constexpr double kContactDetectionTime = 0.02;

/// The observer's default gain [1/s] for samples `period` [s] apart: 4 / kContactDetectionTime,
/// at most 1 / period (the discrete observer needs K dt <= 1).
double default_observer_gain(double period);

/// Which residual run_observer computes: lib/'s generalised-momentum observer (the monitor's), or
/// the direct residual (lib/ direct_residual.hpp: the model's torque error with the window's
/// acceleration, low-passed alike), for comparison (docs/monitor.md "Observer or direct residual").
enum class ResidualKind { momentum_observer, direct };

/// The observer's residual over a log.
struct ObserverRun {
  ResidualKind kind = ResidualKind::momentum_observer;
  double gain = 0;           ///< K [1/s], every joint
  double period = 0;         ///< sample period of the uniform grid [s]
  double delay = 0;          ///< how far an online observer runs behind the samples it reports on [s]
  std::vector<double> band;  ///< per joint, the friction terms' standstill band [rad/s]
  Eigen::VectorXd t;         ///< [s], S
  Eigen::MatrixXd r;         ///< residual [Nm], S x N
  /// S x N, 1 where the joint is at or near rest: its encoder did not count on a step of the
  /// velocity's window (a log with qd: |qd| inside the band). Friction there is static, any value
  /// up to its Coulomb level, which the model cannot know (friction_weight is 1 there).
  Eigen::MatrixXi still;
  std::vector<double> static_friction;  ///< per joint, the model's Coulomb level |Fc_j| [Nm] (0 without one)
  /// S x N in [0, 1]: the share of static_friction the residual may hold because the model cannot
  /// know the friction there (lib/ friction_uncertainty.hpp: 1 at rest, in the standstill band and
  /// at a velocity reversal, then decaying as the observer forgets); detection widens the threshold
  /// by friction_weight * static_friction.
  Eigen::MatrixXd friction_weight;
  std::vector<std::pair<Eigen::Index, Eigen::Index>> segments;  ///< [first, end) rows, each observed from its start
  std::vector<std::string> notes;                               ///< the log's sampling, the velocity's source
};

/// lib/'s momentum observer with `params` as the model (their drive-table form, drive_table.hpp)
/// over `log` put on a uniform grid (gaps up to pi / K bridged, half the period of the residual's
/// bandwidth K / 2 pi; longer ones split it), restarted at every segment. qd: the log's when it has
/// one, else the slope of the least-squares line through the 2D + 1 samples centred on each,
/// D = 1 / (K dt) (ObserverRun::delay = D dt; the first and last D samples of a segment are not
/// observed). gain 0: default_observer_gain. The friction terms' standstill band:
/// `band` when given (N), else identification's rule on this log: kStandstillQuantile times the
/// white-noise std (signal.hpp) of the velocity one sample resolves (a backward difference of q, or
/// the log's qd), where a joint at rest reads |qd| above it on 0.1 % of its samples. Throws
/// InputError: params of another robot, a model the observer cannot take, a gain with K dt > 1 or a
/// velocity window over 1025 samples, a non-finite sample, the log's sampling (uniform_grid.hpp).
/// kind direct: the direct residual instead, qdd twice the curvature of the least-squares parabola
/// through the same window (lib/ centred_slope.hpp); also throws for a log with qd (its
/// acceleration comes from q's window only).
/// lower_gain_within: a gain with K dt > 1 by at most this much (relative) is lowered to 1 / dt, the
/// log's grid period (a statistics' default gain, 1 / its own period, on a log a little slower);
/// ObserverRun::gain is the gain used.
ObserverRun run_observer(const RobotDescription& robot, JointLog log, const ParameterSet& params, double gain = 0,
                         const std::vector<double>& band = {}, ResidualKind kind = ResidualKind::momentum_observer,
                         double lower_gain_within = 0);

/// The residual's statistics on contact-free motion, per joint: mean, standard deviation and the
/// standard deviation of its sample-to-sample difference [Nm] (differences within segments), from
/// the samples after each segment's first 5 / K (the observer's start-up: e^-5 < 1 %) where the
/// model knows the friction (friction_weight below e^-5: 5 time constants after a rest or reversal).
struct ResidualStatistics {
  std::string source;  ///< the log they come from
  double gain = 0;     ///< K [1/s]
  double period = 0;   ///< [s]
  Eigen::Index samples = 0;
  std::vector<double> band;                       ///< the observer's standstill band [rad/s] (N)
  std::vector<double> mean, std, difference_std;  ///< N each [Nm]
  /// N: the largest |r - mean| on that motion [Nm], less the friction the model cannot know there
  /// (friction_weight * static_friction: what the threshold, widened by it, would have to clear)
  std::vector<double> peak;
};

/// Throws InputError when no segment is longer than the start-up.
ResidualStatistics residual_statistics(const ObserverRun& run, const std::string& source);

/// The parameter file's "monitor" object: {source, gain, period, samples, joints: [{joint, band,
/// mean, std, difference_std, peak}]}.
nlohmann::json residual_statistics_json(const ResidualStatistics& s);
/// Reads it back; throws InputError naming `where` and what is missing or not a positive number.
ResidualStatistics read_residual_statistics(const nlohmann::json& j, const std::string& where);

/// Per-joint thresholds [Nm] for `alarms_per_hour` false alarms of the whole arm on motion like the
/// statistics': an alarm when |r_j - mean_j| > threshold_j. gaussian: lib/ contact_threshold (the
/// rate shared equally by the joints), what the rate holds for if the residual is Gaussian. A
/// residual whose tails are heavier (a model error at velocity reversals, say) can exceed it on
/// the calibration's own motion: then the threshold is that motion's peak |r - mean| (peak_bound
/// true) and the rate is not established for that joint: the log shows only that its own motion
/// stays below it. Throws InputError for a rate not > 0 or a joint without statistics.
struct ContactThreshold {
  double value = 0, gaussian = 0;
  bool peak_bound = false;
};
std::vector<ContactThreshold> contact_thresholds(const ResidualStatistics& s, double alarms_per_hour);

/// How far a monitored log's rate may be from the statistics' (docs/monitor.md "Another rate"): the
/// relative difference of sample period, and of the gain it forces, within which the statistics
/// are used as taken. The observer's white-noise residual has variance ~ K dt / (2 - K dt) per unit
/// noise, so a relative change e of dt or K moves its std by at most e (K dt <= 1); a threshold z
/// stds out then passes Gaussian noise exp(z^2 e) times as often. The tolerance is the e at which
/// the stated false-alarm rate at most doubles, ln 2 / z^2, z the largest gaussian threshold over
/// its std among the joints.
double statistics_rate_tolerance(const ResidualStatistics& s, const std::vector<ContactThreshold>& thresholds);

/// One contact: from the first sample where a joint's |r - mean| exceeds its threshold to the first
/// where every joint is back within it, alarms closer than the observer's time constant 1 / K
/// merged (its memory: one push seen twice).
struct Contact {
  double start = 0, end = 0;  ///< [s], the samples' time
  double detected = 0;        ///< when an online observer raises it: start + ObserverRun::delay [s]
  std::vector<int> joints;    ///< 1-based joints that crossed their threshold
  std::vector<double> peak;   ///< per joint (N), the residual's largest |r - mean| during it [Nm]
  int first_joint = 0;        ///< 1-based: the joint that crossed first
};

/// The bound |r - mean| of joint j (0-based) is compared with at row k [Nm]: the joint's threshold
/// widened by the friction the model cannot know there (friction_weight * static_friction).
double contact_limit(const ObserverRun& run, const std::vector<ContactThreshold>& thresholds, Eigen::Index k, int j);

std::vector<Contact> detect_contacts(const ObserverRun& run, const ResidualStatistics& s,
                                     const std::vector<ContactThreshold>& thresholds);

/// dyncal monitor --plots: per joint an SVG of r - mean over time with its threshold (widened where
/// the joint rests) and the contacts shaded, into `dir` (created), through gnuplot; returns the
/// files. Throws InputError when the directory cannot be written or gnuplot fails.
std::vector<std::string> write_contact_plots(const ObserverRun& run, const ResidualStatistics& s,
                                             const std::vector<ContactThreshold>& thresholds,
                                             const std::vector<Contact>& contacts, const std::string& dir);

}  // namespace dyncal::host
