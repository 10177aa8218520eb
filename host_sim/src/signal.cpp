#include "dyncal_host/signal.hpp"

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

}  // namespace dyncal::host
