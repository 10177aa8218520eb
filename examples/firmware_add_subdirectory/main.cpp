// Identifies the simulated er20 on a Cortex-M (qemu) with dyncal::lib and dyncal::cortex_m, on the
// port's scalar (float on the M4F, double on the M7); prints through semihosting.
#include "dyncal_cortex_m/semihosting.hpp"
#include "er20_identification.hpp"

namespace {
using Scalar = DYNCAL_FW_SCALAR;
dyncal::StreamingLeastSquares<Scalar, example::Model::kNumParams> g_ls;  // static: no heap, small stack
}  // namespace

int main() {
  const Scalar error = example::identify_and_validate(g_ls, 500);
  dyncal::cortex_m::write("er20, relative RMS prediction error on an unseen trajectory: ");
  dyncal::cortex_m::write_float(static_cast<double>(error), 3);
  dyncal::cortex_m::write("\n");
  // float: rounding of a 48-parameter solve; double: near exact.
  const Scalar limit = sizeof(Scalar) == 4 ? Scalar(2e-2) : Scalar(1e-6);
  dyncal::cortex_m::exit(error >= Scalar(0) && error < limit ? 0 : 1);
}
