#include "dyncal_host/identification/pipeline/butterworth.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

ButterworthLowPass::ButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz) : cutoff_hz_(cutoff_hz) {
  if (order < 2 || order % 2 != 0) throw InputError("Butterworth order must be even and >= 2");
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < 0.5 * sample_rate_hz)) {
    throw InputError("filter cut-off " + std::to_string(cutoff_hz) + " Hz must lie in (0, " +
                     std::to_string(0.5 * sample_rate_hz) + ") Hz for a sample rate of " +
                     std::to_string(sample_rate_hz) + " Hz");
  }
  const double w0 = 2.0 * M_PI * cutoff_hz / sample_rate_hz;
  const double cw = std::cos(w0);
  const int n_sections = order / 2;
  sections_.resize(n_sections, 5);
  for (int k = 0; k < n_sections; ++k) {
    // Pole pair k of the analog prototype: Q = 1 / (2 cos((2k + 1) pi / (2 order))).
    const double q = 1.0 / (2.0 * std::cos((2.0 * k + 1.0) * M_PI / (2.0 * order)));
    const double alpha = std::sin(w0) / (2.0 * q);
    const double a0 = 1.0 + alpha;
    sections_(k, 0) = (1.0 - cw) / 2.0 / a0;
    sections_(k, 1) = (1.0 - cw) / a0;
    sections_(k, 2) = (1.0 - cw) / 2.0 / a0;
    sections_(k, 3) = -2.0 * cw / a0;
    sections_(k, 4) = (1.0 - alpha) / a0;
  }
  // Time constant of the slowest pole ~ 1 / (2 pi fc) seconds.
  pad_ = static_cast<int>(std::ceil(3.0 * sample_rate_hz / (2.0 * M_PI * cutoff_hz))) * order;
}

void ButterworthLowPass::pass(Eigen::VectorXd& y) const {
  for (int k = 0; k < sections_.rows(); ++k) {
    const double b0 = sections_(k, 0), b1 = sections_(k, 1), b2 = sections_(k, 2);
    const double a1 = sections_(k, 3), a2 = sections_(k, 4);
    // Direct form II transposed, state at the steady state of the first sample (unit DC gain).
    double z2 = (b2 - a2) * y[0];
    double z1 = (b1 - a1) * y[0] + z2;
    for (Eigen::Index i = 0; i < y.size(); ++i) {
      const double x = y[i];
      const double out = b0 * x + z1;
      z1 = b1 * x - a1 * out + z2;
      z2 = b2 * x - a2 * out;
      y[i] = out;
    }
  }
}

void ButterworthLowPass::filtfilt(Eigen::Ref<Eigen::MatrixXd> x) const {
  const Eigen::Index n = x.rows();
  if (n < 2) return;
  const Eigen::Index pad = std::min<Eigen::Index>(pad_, n - 1);
  Eigen::VectorXd ext(n + 2 * pad);
  for (Eigen::Index c = 0; c < x.cols(); ++c) {
    const auto col = x.col(c);
    for (Eigen::Index i = 0; i < pad; ++i) ext[i] = 2.0 * col[0] - col[pad - i];
    ext.segment(pad, n) = col;
    for (Eigen::Index i = 0; i < pad; ++i) ext[pad + n + i] = 2.0 * col[n - 1] - col[n - 2 - i];
    pass(ext);
    ext.reverseInPlace();
    pass(ext);
    ext.reverseInPlace();
    x.col(c) = ext.segment(pad, n);
  }
}

}  // namespace dyncal::host
