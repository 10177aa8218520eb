// The survey study's host-side calculations on the default run's data size (2 000 samples, two
// excitation periods, Table 7 noise): one evaluation of the optimisers' reduced objective (Eq. 25)
// per friction model, one fit of the friction amplitudes (the samplers' evaluation), and one
// physically consistent least-squares solve per model.
#include <benchmark/benchmark.h>

#include <map>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/objective.hpp"
#include "dyncal_host/identification/physically_consistent.hpp"
#include "dyncal_host/identification/standard_parameters.hpp"
#include "dyncal_host/survey/survey_data.hpp"

namespace {

using dyncal::host::FrictionModel;
namespace survey = dyncal::host::survey;
using namespace dyncal::host;

const survey::SurveyData& data(FrictionModel model) {
  static std::map<FrictionModel, survey::SurveyData> cache;
  auto it = cache.find(model);
  if (it == cache.end()) {
    survey::SurveyDataOptions o;
    o.friction = model;
    o.torque_noise = true;
    o.periods = 2;
    it = cache
             .emplace(model, survey::simulate_survey_data(
                                 dyncal::host::load_robot(dyncal::host::default_robots_dir(), "er20"), o))
             .first;
  }
  return it->second;
}

MethodSettings settings() {
  MethodSettings s;
  s.prior = cad_prior(0.2, 1);
  return s;
}

constexpr FrictionModel kModels[] = {FrictionModel::eq7, FrictionModel::eq8, FrictionModel::eq9,
                                     FrictionModel::eq4, FrictionModel::eq5, FrictionModel::eq6};

void BM_ReducedEq25(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const survey::SurveyData& d = data(m);
  const TorqueObjective objective(d, m, settings().sigma);
  const SearchRanges r = search_ranges(d, m, nearest_consistent(settings().prior.mean), 0.4);
  const Eigen::VectorXd x = 0.5 * (r.lo + r.hi);
  for (auto _ : state) benchmark::DoNotOptimize(objective.eq25(x.data(), 1.0));
  state.SetLabel(model_key(m));
}
BENCHMARK(BM_ReducedEq25)->DenseRange(0, 5)->Unit(benchmark::kMicrosecond);

/// The genetic algorithm's and the particle filter's evaluation: the friction amplitudes fitted by
/// separable least squares at the box's centre, with the residual moments there.
void BM_FitAmplitudes(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const survey::SurveyData& d = data(m);
  const TorqueObjective objective(d, m, settings().sigma);
  const SearchRanges r = search_ranges(d, m, nearest_consistent(settings().prior.mean), 0.4);
  const Eigen::VectorXd x0 = 0.5 * (r.lo + r.hi);
  Eigen::VectorXd x = x0;
  std::array<double, 6> mean{}, var{};
  for (auto _ : state) {
    x = x0;
    objective.fit_amplitudes(x.data(), r.lo.data(), r.hi.data(), &mean, &var);
    benchmark::DoNotOptimize(x.data());
  }
  state.SetLabel(model_key(m));
}
BENCHMARK(BM_FitAmplitudes)->DenseRange(0, 5)->Unit(benchmark::kMicrosecond);

void BM_PhysicallyConsistentLs(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const survey::SurveyData& d = data(m);
  for (auto _ : state) benchmark::DoNotOptimize(physically_consistent_ls(d, m, settings()));
  state.SetLabel(model_key(m));
}
BENCHMARK(BM_PhysicallyConsistentLs)->DenseRange(0, 5)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
