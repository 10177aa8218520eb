#pragma once
// Shared by the survey tests: one noise-free survey run per friction model (one excitation
// period, cached), the er20's maximum torques (robot.json), and method settings with the seed-1 CAD prior.
#include <array>
#include <cmath>
#include <map>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/survey/methods/methods.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"
#include "dyncal_host/survey/survey_data.hpp"

namespace dyncal::test {

/// The er20's maximum joint driving torques tau_max [Nm] from its robot.json (survey Sec. 5.1).
inline const std::array<double, 6> kEr20TauMax = [] {
  const host::RobotDescription robot = host::load_robot(host::default_robots_dir(), "er20");
  std::array<double, 6> t{};
  for (int j = 0; j < 6; ++j) t[static_cast<size_t>(j)] = robot.tau_max[j];
  return t;
}();

inline const host::survey::SurveyData& survey_data(host::FrictionModel model) {
  static std::map<host::FrictionModel, host::survey::SurveyData> cache;
  auto it = cache.find(model);
  if (it == cache.end()) {
    host::survey::SurveyDataOptions o;
    o.friction = model;
    o.periods = 1;
    it = cache.emplace(model, simulate_survey_data(host::load_robot(host::default_robots_dir(), "er20"), o)).first;
  }
  return it->second;
}

inline host::MethodSettings survey_settings() {
  host::MethodSettings s;
  s.prior = host::cad_prior(0.2, 1);
  return s;
}

/// RMS over the run's samples of joint j's (0-based) friction curve with parameters `est` minus the
/// one with `set` (friction_parameter_names order, joint-major), relative to the set curve's RMS:
/// what a fit recovers of the friction even where its parameters trade off.
inline double friction_curve_error(const host::survey::SurveyData& d, host::FrictionModel model,
                                   const std::vector<double>& est, const std::vector<double>& set, int j) {
  const int kf = host::friction_count(model);
  double diff = 0, ref = 0;
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    const double a = host::friction_torque(model, set.data() + kf * j, d.qd(s, j), d.tau_load(s, j));
    const double b = host::friction_torque(model, est.data() + kf * j, d.qd(s, j), d.tau_load(s, j));
    diff += (b - a) * (b - a);
    ref += a * a;
  }
  return std::sqrt(diff / ref);
}

}  // namespace dyncal::test
