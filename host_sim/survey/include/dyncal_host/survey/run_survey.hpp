#pragma once
// `dyncal survey`: the survey's simulation study (Sec. 6) on the er20 through the simulated drive,
// every implemented method on the linear (Eq. 7) and nonlinear (Eq. 4) model, without and with
// Table 7 noise, printed side by side with the published numbers.

#include <cstdint>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host::survey {

/// The arm of the survey's study: its robot folder (robots/er20/, with survey_published.json), the
/// one the study's er20-typed methods are compiled for.
inline constexpr const char* kStudyRobot = "er20";

struct SurveyOptions {
  bool quick = false;                          ///< one excitation period (10 s, 1 000 samples) instead of two
  std::uint64_t seed = 1;                      ///< excitation, noise and CAD-prior seed
  double prior_error = 0.2;                    ///< CAD prior: set values times (1 + u), u uniform in +-prior_error
  PriorErrors prior_on = PriorErrors::table5;  ///< which set values the CAD prior's errors are on
  int jobs = 0;  ///< threads for the independent runs (0: one per hardware thread); results do not depend on it
};

struct SurveySeries;

/// Runs the study. The result (JSON) holds, per model and method, the Sec. 5 indices without and
/// with noise, each joint's RMS torque residual [Nm], the solution times, and joint 3's parameters
/// (Tables 5, 6). With `series`, also the time series the figures need (survey_plots.hpp). Throws
/// InputError.
nlohmann::json run_survey(const RobotDescription& robot, const SurveyOptions& options, SurveySeries* series = nullptr);

}  // namespace dyncal::host::survey
