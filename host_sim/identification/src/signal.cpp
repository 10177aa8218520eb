#include "dyncal_host/identification/signal.hpp"

namespace dyncal::host {

Eigen::MatrixXd central_difference(const Eigen::MatrixXd& x, double dt) {
  const Eigen::Index n = x.rows();
  Eigen::MatrixXd d(n, x.cols());
  if (n < 2) {
    d.setZero();
    return d;
  }
  d.row(0) = (x.row(1) - x.row(0)) / dt;
  d.row(n - 1) = (x.row(n - 1) - x.row(n - 2)) / dt;
  if (n > 2) d.middleRows(1, n - 2) = (x.bottomRows(n - 2) - x.topRows(n - 2)) / (2.0 * dt);
  return d;
}

double effective_samples(const Eigen::VectorXd& r) {
  const Eigen::Index S = r.size();
  const Eigen::VectorXd c = r.array() - r.mean();
  const double c0 = c.squaredNorm();
  double tau = 1.0;
  for (Eigen::Index k = 1; k < S / 4 && c0 > 0; ++k) {
    const double rho = c.head(S - k).dot(c.tail(S - k)) / c0;
    if (rho <= 0) break;
    tau += 2.0 * rho;
  }
  return static_cast<double>(S) / tau;
}

}  // namespace dyncal::host
