#pragma once
// The identification data of a log after filtering, differentiation, regressor evaluation,
// parallel filtering and decimation: what every batch method and the diagnosis work on.

#include <Eigen/Core>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace dyncal::host {

/// Stacked, filtered and decimated identification data: row s * N + j is joint j at sample s.
///
/// The regressor is kept as what it is computed from at the kept samples (q, qd, qdd, a coupled
/// motor's raw velocity and the parallel-filtered friction-sign columns), about 5 N numbers per
/// sample instead of its N P:
/// regressor(s, K) gives sample s's N rows. W and W_load hold it as one dense matrix when the
/// data were prepared for a consumer that needs it (prepare_stacked; identify without effect
/// terms streams the rows and leaves them empty).
struct StackedData {
  Eigen::MatrixXd W;               ///< (S N) x P regressor, dense (empty when only streamed, see above)
  Eigen::MatrixXd W_load;          ///< (S N) x P regressor at qdd = 0, filtered and stacked as W (only with
                                   ///< IdentifyOptions::load_regressor, else empty): its rigid-body columns times
                                   ///< phi give the load torque h(q, qd), gravity and velocity products [Nm]
  Eigen::MatrixXd filtered_terms;  ///< S x F: the friction-sign columns (Coulomb, power; per joint or coupled
                                   ///< motor) built at the log's rate and filtered in parallel, at the kept samples
  /// Writes sample s's N x P regressor rows into K (resized), as W's rows s N .. s N + N - 1;
  /// load: at qdd = 0, as W_load's. Set by the pipeline that prepared the data.
  std::function<void(const StackedData&, Eigen::Index s, bool load, Eigen::MatrixXd& K)> regressor_rows;
  Eigen::MatrixXd E;                ///< (S N) x m columns of IdentifyOptions::effects, computed at the log's rate
                                    ///< and filtered in parallel as W (effect_model.hpp); load friction's are 0
                                    ///< here (they need the fit's rigid-body torque: effect_design)
  Eigen::VectorXd y;                ///< (S N) torques [Nm]
  Eigen::VectorXd t;                ///< S sample times [s]
  double rate_hz = 0;               ///< after decimation
  std::vector<char> fit_row;        ///< (S N): 1 where row s * N + j enters the fit (see min_speed_fraction)
  Eigen::MatrixXd q, qd, qdd;       ///< S x N filtered joint signals at the kept samples (for extra columns)
  Eigen::MatrixXd qd_raw;           ///< S x N unfiltered velocity at the kept samples (friction signs); kept
                                    ///< with dense data, else 0 x N
  Eigen::MatrixXd tau_raw;          ///< S x N unfiltered torque at the kept samples [Nm] (the diagnosis' torque
                                    ///< steps); kept with dense data, else 0 x N
  Eigen::MatrixXd motor_qd_raw;     ///< S x C unfiltered velocity T.row(m) qd of each coupled motor m (in the
                                    ///< pipeline's order) at the kept samples: its friction sign [rad/s]
  Eigen::VectorXd standstill_band;  ///< N: |qd_raw| below it is rest [rad/s]
  std::vector<std::string> names;   ///< P parameter names
  int num_base = 0;                 ///< the first num_base columns are the base parameters (rigid body)
  double cutoff_hz = 0;
  int filter_order = 0;  ///< the zero-phase low-pass q, tau and the columns had (Butterworth order, cutoff_hz)
  std::vector<std::string> notes;  ///< what preparation did that the user should know (standstill band, segments)

  /// Sample s's regressor rows (N x P, rows s N .. s N + N - 1 of W) into K; load: W_load's.
  void regressor(Eigen::Index s, Eigen::MatrixXd& K, bool load = false) const { regressor_rows(*this, s, load, K); }
};

/// The friction sign of an unfiltered velocity `raw`: 0 inside the standstill band [rad/s] (at
/// rest), else +-1.
inline double friction_sign(double raw, double band) {
  return std::abs(raw) < band ? 0.0 : (raw > 0 ? 1.0 : -1.0);
}

/// The velocity every friction-sign column is built from: the filtered magnitude with the
/// unfiltered velocity's sign (a filtered velocity's sign switches up to a cut-off period after a
/// stop), 0 inside the standstill band [rad/s].
inline double signed_velocity(double filtered, double raw, double band) {
  return friction_sign(raw, band) * std::abs(filtered);
}

/// The data's segments [begin, end) of kept samples: a step in t longer than 1.5 periods (1 /
/// rate_hz) starts a new one (a gap or a rest cut out of the log).
inline std::vector<std::pair<Eigen::Index, Eigen::Index>> time_segments(const StackedData& d) {
  std::vector<std::pair<Eigen::Index, Eigen::Index>> segments;
  const Eigen::Index S = d.t.size();
  for (Eigen::Index s = 0, a = 0; s < S; ++s)
    if (s + 1 == S || d.t[s + 1] - d.t[s] > 1.5 / d.rate_hz) {
      segments.emplace_back(a, s + 1);
      a = s + 1;
    }
  return segments;
}

/// Gautier's per-joint residual standard deviation [Nm], the WLS weight's inverse: sigma_j^2 =
/// RSS_j / (n_j - p / N) for a fit of p parameters with n_j rows of joint j (N joints), at least
/// 1e-12 (a joint fitted exactly keeps a finite weight).
inline Eigen::VectorXd joint_noise_std(const Eigen::VectorXd& rss, const Eigen::VectorXd& rows, Eigen::Index p) {
  const double per_joint = static_cast<double>(p) / static_cast<double>(rss.size());
  return rss.cwiseQuotient((rows.array() - per_joint).max(1.0).matrix()).cwiseSqrt().cwiseMax(1e-12);
}

}  // namespace dyncal::host
