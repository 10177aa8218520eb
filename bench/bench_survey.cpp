// The survey study's host-side calculations on the default run's data size (2 000 samples, two
// excitation periods, Table 7 noise): one evaluation of the optimisers' reduced objective (Eq. 25)
// per friction model, one fit of the friction amplitudes (the samplers' evaluation), and one
// physically consistent least-squares solve per model.
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/survey/methods/objective.hpp"
#include "dyncal_host/survey/methods/physically_consistent.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"
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

/// A sampler's population of 120 (the study's) evaluated one vector after another (state.range(1)
/// 0) or joint by joint over the population (1: fit_amplitudes' batch form, what the genetic
/// algorithm and the particle filter run; same results).
void BM_FitAmplitudesPopulation(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const AtRangeCentre c(m);
  std::vector<Eigen::VectorXd> population;
  for (int i = 0; i < 120; ++i) {
    Eigen::VectorXd x = c.ranges.lo;
    for (Eigen::Index k = 0; k < x.size(); ++k) {  // spread over the box, deterministic
      x[k] += (0.5 + 0.45 * std::sin(1.7 * i + 0.3 * static_cast<double>(k))) * (c.ranges.hi[k] - c.ranges.lo[k]);
    }
    population.push_back(x);
  }
  std::vector<Eigen::VectorXd> xs = population;
  std::vector<double*> ptrs;
  for (Eigen::VectorXd& x : xs) ptrs.push_back(x.data());
  std::vector<std::array<double, 6>> means, vars;
  std::array<double, 6> mean{}, var{};
  for (auto _ : state) {
    for (size_t i = 0; i < xs.size(); ++i) xs[i] = population[i];
    if (state.range(1) == 1) {
      c.objective.fit_amplitudes(ptrs, c.ranges.lo.data(), c.ranges.hi.data(), &means, &vars);
    } else {
      for (double* x : ptrs) c.objective.fit_amplitudes(x, c.ranges.lo.data(), c.ranges.hi.data(), &mean, &var);
    }
    benchmark::DoNotOptimize(xs.front().data());
  }
  state.SetLabel(std::string(model_key(m)) + (state.range(1) == 1 ? " joint by joint" : " one by one"));
}
BENCHMARK(BM_FitAmplitudesPopulation)->ArgsProduct({{3, 4, 5}, {0, 1}})->Unit(benchmark::kMillisecond);

void BM_PhysicallyConsistentLs(benchmark::State& state) {
  const FrictionModel m = kModels[state.range(0)];
  const survey::SurveyData& d = data(m);
  for (auto _ : state) benchmark::DoNotOptimize(physically_consistent_ls(d, m, settings()));
  state.SetLabel(model_key(m));
}
BENCHMARK(BM_PhysicallyConsistentLs)->DenseRange(0, 5)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
