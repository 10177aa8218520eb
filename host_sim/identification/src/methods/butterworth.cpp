#include "dyncal_host/identification/methods/butterworth.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

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

namespace {

/// Sections fused in one pass over the samples (a cascade of more runs as several passes, with the
/// same result): few enough that their states stay in registers.
constexpr int kFusedSections = 4;

// The section and signal loops unrolled, so that every state is a register (clang does not unroll
// at the host's -O1).
#if defined(__clang__)
#define DYNCAL_UNROLL _Pragma("clang loop unroll(full)")
#else
#define DYNCAL_UNROLL _Pragma("GCC unroll 16")
#endif

/// L doubles as one vector of the processor (the compiler's vector extension): each lane gets the
/// operations a double would, contracted into the same fused multiply-adds.
template <int L>
struct Lanes {
  typedef double type __attribute__((vector_size(8 * L)));
};
template <>
struct Lanes<1> {
  typedef double type;
};

/// One causal pass of the K sections from `from` over L interleaved signals y[i L + l] (i < n),
/// forward (from sample 0) or backward (from sample n - 1), in place: direct form II transposed,
/// each section's state at the steady state of its first input (unit DC gain). The sections run
/// fused in one loop over the samples and the L signals side by side in one vector, so their
/// recurrences overlap in the processor. Each signal gets the same operations as alone.
template <int L, int K>
void pass_interleaved(const Eigen::Matrix<double, Eigen::Dynamic, 5>& sections, int from, double* y, Eigen::Index n,
                      bool forward) {
  using V = typename Lanes<L>::type;
  double b0[K], b1[K], b2[K], a1[K], a2[K];
  V z1[K], z2[K];
  for (int k = 0; k < K; ++k) {
    b0[k] = sections(from + k, 0), b1[k] = sections(from + k, 1), b2[k] = sections(from + k, 2);
    a1[k] = sections(from + k, 3), a2[k] = sections(from + k, 4);
  }
  double* const first = forward ? y : y + (n - 1) * L;
  const Eigen::Index step = forward ? L : -L;
  V x;
  std::memcpy(&x, first, sizeof(V));
  DYNCAL_UNROLL
  for (int k = 0; k < K; ++k) {
    z2[k] = (b2[k] - a2[k]) * x;
    z1[k] = (b1[k] - a1[k]) * x + z2[k];
    const V out = b0[k] * x + z1[k];
    z1[k] = b1[k] * x - a1[k] * out + z2[k];
    z2[k] = b2[k] * x - a2[k] * out;
    x = out;
  }
  std::memcpy(first, &x, sizeof(V));
  for (Eigen::Index i = 1; i < n; ++i) {
    double* const at = first + i * step;
    std::memcpy(&x, at, sizeof(V));
    DYNCAL_UNROLL
    for (int k = 0; k < K; ++k) {
      const V out = b0[k] * x + z1[k];
      z1[k] = b1[k] * x - a1[k] * out + z2[k];
      z2[k] = b2[k] * x - a2[k] * out;
      x = out;
    }
    std::memcpy(at, &x, sizeof(V));
  }
}

/// pass_interleaved of sections [from, from + count), count <= kFusedSections.
template <int L>
void pass_sections(const Eigen::Matrix<double, Eigen::Dynamic, 5>& sections, int from, int count, double* y,
                   Eigen::Index n, bool forward) {
  switch (count) {
    case 1:
      return pass_interleaved<L, 1>(sections, from, y, n, forward);
    case 2:
      return pass_interleaved<L, 2>(sections, from, y, n, forward);
    case 3:
      return pass_interleaved<L, 3>(sections, from, y, n, forward);
    default:
      return pass_interleaved<L, kFusedSections>(sections, from, y, n, forward);
  }
}

/// filtfilt of L columns of x from column c0 (L <= 4), interleaved in `ext` ((n + 2 pad) L).
template <int L>
void filtfilt_columns(const Eigen::Matrix<double, Eigen::Dynamic, 5>& sections, Eigen::Ref<Eigen::MatrixXd>& x,
                      Eigen::Index c0, Eigen::Index pad, std::vector<double>& ext) {
  const Eigen::Index n = x.rows(), len = n + 2 * pad;
  ext.resize(static_cast<size_t>(len * L));
  for (int l = 0; l < L; ++l) {
    const auto col = x.col(c0 + l);
    for (Eigen::Index i = 0; i < pad; ++i) ext[static_cast<size_t>(i * L + l)] = 2.0 * col[0] - col[pad - i];
    for (Eigen::Index i = 0; i < n; ++i) ext[static_cast<size_t>((pad + i) * L + l)] = col[i];
    for (Eigen::Index i = 0; i < pad; ++i)
      ext[static_cast<size_t>((pad + n + i) * L + l)] = 2.0 * col[n - 1] - col[n - 2 - i];
  }
  const int K = static_cast<int>(sections.rows());
  for (bool forward : {true, false})
    for (int from = 0; from < K; from += kFusedSections)
      pass_sections<L>(sections, from, std::min(K - from, kFusedSections), ext.data(), len, forward);
  for (int l = 0; l < L; ++l) {
    auto col = x.col(c0 + l);
    for (Eigen::Index i = 0; i < n; ++i) col[i] = ext[static_cast<size_t>((pad + i) * L + l)];
  }
}

}  // namespace

void ButterworthLowPass::filtfilt(Eigen::Ref<Eigen::MatrixXd> x) const {
  const Eigen::Index n = x.rows();
  if (n < 2 || sections_.rows() == 0) return;
  const Eigen::Index pad = std::min<Eigen::Index>(pad_, n - 1);
  std::vector<double> ext;
  Eigen::Index c = 0;
  for (; c + 4 <= x.cols(); c += 4) filtfilt_columns<4>(sections_, x, c, pad, ext);
  if (x.cols() - c >= 2) filtfilt_columns<2>(sections_, x, c, pad, ext), c += 2;
  if (c < x.cols()) filtfilt_columns<1>(sections_, x, c, pad, ext);
}

}  // namespace dyncal::host
