#include "dyncal_host/identification/methods/butterworth.hpp"

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

void ButterworthLowPass::pass(Eigen::VectorXd& y, bool forward) const {
  constexpr int kMaxSections = 16;
  const int K = static_cast<int>(sections_.rows());
  const Eigen::Index n = y.size();
  if (n == 0 || K == 0) return;
  double b0[kMaxSections], b1[kMaxSections], b2[kMaxSections], a1[kMaxSections], a2[kMaxSections];
  double z1[kMaxSections], z2[kMaxSections];
  double* const first = forward ? y.data() : y.data() + (n - 1);
  const Eigen::Index step = forward ? 1 : -1;
  for (int from = 0; from < K; from += kMaxSections) {  // more than 16 sections: in groups
    const int m = std::min(K - from, kMaxSections);
    for (int k = 0; k < m; ++k) {
      b0[k] = sections_(from + k, 0), b1[k] = sections_(from + k, 1), b2[k] = sections_(from + k, 2);
      a1[k] = sections_(from + k, 3), a2[k] = sections_(from + k, 4);
    }
    // Direct form II transposed, each section's state at the steady state of its first input
    // (unit DC gain): the first sample through the sections one after another.
    double x = first[0];
    for (int k = 0; k < m; ++k) {
      z2[k] = (b2[k] - a2[k]) * x;
      z1[k] = (b1[k] - a1[k]) * x + z2[k];
      const double out = b0[k] * x + z1[k];
      z1[k] = b1[k] * x - a1[k] * out + z2[k];
      z2[k] = b2[k] * x - a2[k] * out;
      x = out;
    }
    first[0] = x;
    for (Eigen::Index i = 1; i < n; ++i) {
      x = first[i * step];
      for (int k = 0; k < m; ++k) {
        const double out = b0[k] * x + z1[k];
        z1[k] = b1[k] * x - a1[k] * out + z2[k];
        z2[k] = b2[k] * x - a2[k] * out;
        x = out;
      }
      first[i * step] = x;
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
    pass(ext, true);
    pass(ext, false);
    x.col(c) = ext.segment(pad, n);
  }
}

}  // namespace dyncal::host
