#pragma once

#include <Eigen/Core>

namespace dyncal::host {

/// Digital Butterworth low-pass filter of even order as a cascade of second-order sections
/// (bilinear transform with pre-warping), applied forward and backward (zero phase).
class ButterworthLowPass {
 public:
  /// order: even, >= 2; cutoff_hz in (0, sample_rate_hz / 2). Throws InputError otherwise.
  ButterworthLowPass(int order, double cutoff_hz, double sample_rate_hz);

  /// Zero-phase filtering of each column of x (rows = samples), in place. The signal is extended
  /// at both ends by odd reflection over about 3 time constants, and each pass starts from the
  /// steady state of its first sample, so that the ends carry no start-up transient.
  /// The magnitude response is the square of the single pass: -6 dB at the cutoff. Columns are
  /// filtered four at a time, interleaved (their recurrences overlap in the processor), each with the
  /// same operations as alone: the result does not depend on how many columns come together.
  void filtfilt(Eigen::Ref<Eigen::MatrixXd> x) const;

  double cutoff_hz() const { return cutoff_hz_; }

 private:
  /// Second-order sections, one per row: b0, b1, b2, a1, a2 (a0 = 1).
  Eigen::Matrix<double, Eigen::Dynamic, 5> sections_;
  double cutoff_hz_;
  int pad_;
};

}  // namespace dyncal::host
