#pragma once
// The residual a model that lacks nothing would leave (private to host_sim/diagnosis): the log's
// broadband noise after the identification's low-pass, the floor against which the diagnosis says
// how much of a joint's excess residual an effect removed and how much is left.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host::detail {

/// Per joint, the mean square [Nm^2] per fitted row that broadband noise alone leaves in the
/// residual (S N stacked, rows s N + j) of the stacked data d (filtered at io's cut-off and order
/// at the raw rate raw_rate_hz, decimated to d.rate_hz). From the residual's own high-frequency
/// content: the differences of consecutive kept samples inside each segment (`segments`), where
/// the model's low-frequency errors (the excitation's band) leave next to nothing and filtered white
/// noise leaves 2 (rho(0) - rho(D)) sigma^2, rho the autocorrelation of the zero-phase filter's
/// impulse response at the raw rate, D the decimation; the floor is rho(0) sigma^2. Robustly: the
/// median of the squared differences over the chi-square(1) median 0.4549. It holds every
/// broadband source (the torque's noise, the encoder's through the model's derivatives); a
/// narrowband error inside the filter's band counts as structure. lo, hi (when given): its 95 %
/// interval per row, from the order statistics of the squared differences at the quantiles
/// 0.5 -+ 1.96 sqrt(0.25 / n_eff) (the binomial interval of a median), n_eff the effective samples
/// of the differences (their autocorrelation, signal.hpp's effective_samples); the filter model's
/// own assumption (white noise before it) is not in it.
Eigen::VectorXd noise_floor_per_row(const StackedData& d, const Eigen::VectorXd& residual,
                                    const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments,
                                    const IdentifyOptions& io, double raw_rate_hz, Eigen::VectorXd* lo = nullptr,
                                    Eigen::VectorXd* hi = nullptr);

/// A diagnosis's noise floor: per joint, the validation RSS a model lacking nothing would leave
/// (noise_floor_per_row times the joint's fitted rows) with its interval, and the fitted rows per
/// cross-validation fold, for the jackknife of the shares measured against it.
struct NoiseFloor {
  Eigen::VectorXd per_row, per_row_lo, per_row_hi;  ///< N [Nm^2 per fitted row]
  Eigen::MatrixXd rows;                             ///< folds x N: fitted rows per fold
  /// The floor's RSS per joint [Nm^2] for the per-row floor `per` on every fold's rows but fold
  /// `without` (-1: all).
  Eigen::VectorXd rss(const Eigen::VectorXd& per, int without = -1) const;
};

/// noise_floor_per_row of `residual` (the declared model's) with its interval, and the fitted rows
/// of d per fold (`fold`: each sample's, 0..folds-1).
NoiseFloor noise_floor(const StackedData& d, const Eigen::VectorXd& residual,
                       const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments, const IdentifyOptions& io,
                       double raw_rate_hz, const std::vector<int>& fold, int folds);

/// The share of the excess validation RSS (above the floor's RSS `floor`) on `joints` (0-based)
/// that went from `before` to `after` (per joint [Nm^2]): the drop over the excess before, in [0, 1].
double excess_share(const std::vector<int>& joints, const Eigen::VectorXd& before, const Eigen::VectorXd& after,
                    const Eigen::VectorXd& floor);

/// excess_share's 95 % interval from the validation RSS per fold (folds x N, CrossValidator's
/// val_folds) before and after: the delete-a-group jackknife over the folds (jackknife.hpp; each
/// replicate without one fold's RSS and rows) around the shares the floor's interval gives (a higher
/// floor, a smaller excess, a larger share), clamped to [0, 1]. It holds the validation's
/// variation between folds and the floor's uncertainty, not the floor's model.
std::pair<double, double> excess_share_interval(const std::vector<int>& joints, const Eigen::MatrixXd& before_folds,
                                                const Eigen::MatrixXd& after_folds, const NoiseFloor& floor);

}  // namespace dyncal::host::detail
