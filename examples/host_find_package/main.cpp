// Identifies the simulated er20 with dyncal::lib found through find_package(dyncal) (double).
#include <cstdio>
#include <memory>

#include "er20_identification.hpp"

int main() {
  auto ls = std::make_unique<dyncal::StreamingLeastSquares<double, example::Model::kNumParams>>();
  const double error = example::identify_and_validate(*ls, 2000);
  std::printf("er20, %d parameters, relative RMS prediction error on an unseen trajectory: %.3g\n",
              example::Model::kNumParams, error);
  return error >= 0 && error < 1e-6 ? 0 : 1;
}
