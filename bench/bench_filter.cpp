// The zero-phase Butterworth low-pass (identification/methods/butterworth.hpp) on a diagnosis-sized
// column (30 000 samples, fourth order, as diagnose's 7-joint minute): the time per column when
// 1, 2, 4 or 8 columns are filtered in one call (four at a time side by side).
#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include "dyncal_host/identification/methods/butterworth.hpp"

namespace {

void BM_FiltfiltColumns(benchmark::State& state) {
  const dyncal::host::ButterworthLowPass filter(4, 20.0, 500.0);
  const Eigen::MatrixXd input = Eigen::MatrixXd::Random(30000, state.range(0));
  Eigen::MatrixXd x = input;
  for (auto _ : state) {
    x = input;
    filter.filtfilt(x);
    benchmark::DoNotOptimize(x.data());
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));  // columns
}
BENCHMARK(BM_FiltfiltColumns)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
