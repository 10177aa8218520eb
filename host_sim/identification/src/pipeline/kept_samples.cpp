#include "dyncal_host/identification/pipeline/kept_samples.hpp"

namespace dyncal::host {

namespace {

// Moves the kept rows of each of `cols` columns of `rows` values (column-major at p) to the front,
// as a column-major (kept x cols) block. Returns the kept count.
Eigen::Index compact(double* p, Eigen::Index rows, Eigen::Index cols, const KeptSamples& kept) {
  const Eigen::Index n = kept.count();
  for (Eigen::Index c = 0; c < cols; ++c) {
    kept.for_each([&](Eigen::Index row, Eigen::Index k) { p[k + c * n] = p[row + c * rows]; });
  }
  return n;
}

}  // namespace

void keep_rows_in_place(Eigen::MatrixXd& m, const KeptSamples& kept) {
  const Eigen::Index rows = m.rows(), cols = m.cols();
  const Eigen::Index n = compact(m.data(), rows, cols, kept);
  // Eigen keeps the buffer and its values when the coefficient count is unchanged, and shortens a
  // row vector's buffer by realloc; a column-major matrix with fewer rows would be copied instead.
  m.resize(1, rows * cols);
  m.conservativeResize(1, n * cols);
  m.resize(n, cols);
}

void keep_rows_in_place(Eigen::VectorXd& v, const KeptSamples& kept) {
  const Eigen::Index n = compact(v.data(), v.size(), 1, kept);
  v.conservativeResize(n);
}

}  // namespace dyncal::host
