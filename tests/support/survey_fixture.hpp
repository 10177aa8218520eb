#pragma once
// Shared by the survey tests: one noise-free survey run per friction model (one excitation
// period, cached), the er20's maximum torques, and method settings with the seed-1 CAD prior.
#include <array>
#include <map>

#include "dyncal_host/robot_description.hpp"
#include "dyncal_host/survey/methods.hpp"
#include "dyncal_host/survey/standard_parameters.hpp"

namespace dyncal::test {

inline const std::array<double, 6> kEr20TauMax{1200, 1300, 600, 110, 110, 60};

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

inline host::survey::MethodSettings survey_settings() {
  host::survey::MethodSettings s;
  s.prior = host::survey::cad_prior(0.2, 1);
  return s;
}

}  // namespace dyncal::test
