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

/// The optimisers' reduced objective on model m's run, its search ranges and their centre.
struct AtRangeCentre {
  explicit AtRangeCentre(FrictionModel m)
      : objective(data(m), m, settings().sigma),
        ranges(search_ranges(data(m), m, nearest_consistent(settings().prior.mean), 0.4)),
        x(0.5 * (ranges.lo + ranges.hi)) {}
  TorqueObjective objective;
  SearchRanges ranges;
  Eigen::VectorXd x;
};

void BM_ReducedEq25(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const AtRangeCentre c(m);
  for (auto _ : state) benchmark::DoNotOptimize(c.objective.eq25(c.x.data(), 1.0));
  state.SetLabel(model_key(m));
}
BENCHMARK(BM_ReducedEq25)->DenseRange(0, 5)->Unit(benchmark::kMicrosecond);

/// The genetic algorithm's and the particle filter's evaluation: the friction amplitudes fitted by
/// separable least squares at the box's centre, with the residual moments there.
void BM_FitAmplitudes(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const AtRangeCentre c(m);
  Eigen::VectorXd x = c.x;
  std::array<double, 6> mean{}, var{};
  for (auto _ : state) {
    x = c.x;
    c.objective.fit_amplitudes(x.data(), c.ranges.lo.data(), c.ranges.hi.data(), &mean, &var);
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
