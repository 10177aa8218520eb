#pragma once
// `dyncal survey --plots DIR`: the survey's figures from a run of the study, as SVG through gnuplot.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dyncal_host/survey/tracking.hpp"

namespace dyncal::host::survey {

/// The time series a run of the study keeps for its figures (the JSON result holds only indices).
struct SurveySeries {
  /// Fig. 2: the designed excitation as the drive played it (noise-free run), per design model.
  struct Trajectory {
    std::string model;  ///< "eq7" or "eq4"
    Eigen::VectorXd t;  ///< [s]
    Eigen::MatrixXd q;  ///< S x 6 [rad]
  };
  std::vector<Trajectory> trajectories;
  /// Fig. 4: beta of joint 3 and every tracking method's estimate, per run model and change profile.
  struct Tracking {
    std::string model;  ///< "eq7" or "eq4"
    std::vector<TrackingResult> runs;
  };
  std::vector<Tracking> tracking;
};

/// Writes into `dir` (created): fig2_trajectories_eqN.svg (Fig. 2: joint positions of the designed
/// excitation, Eq. 7 and Eq. 4), residual_rms_eqN.svg (the RMS torque residual [Nm] of every joint
/// for every method, without and with Table 7 noise, from `result`), fig4_tracking_eqN.svg (Fig. 4:
/// beta_3 [Nm s/rad] and its estimates over the samples N for the step, ramp and second-order
/// changes), with their .dat data and the gnuplot script plots.gp. Returns the SVG paths. Throws
/// InputError when the directory cannot be written or gnuplot fails.
std::vector<std::string> write_survey_plots(const nlohmann::json& result, const SurveySeries& series,
                                            const std::string& dir);

}  // namespace dyncal::host::survey
