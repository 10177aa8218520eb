#include "dyncal_host/identification/methods/instrumental_iteration.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

double step_in_standard_errors(const Eigen::MatrixXd& K, const Eigen::MatrixXd& Z, const Eigen::VectorXd& y,
                               const Eigen::VectorXd& phi, const Eigen::VectorXd& step) {
  const double P = static_cast<double>(K.cols());
  const double s2 = (y - K * phi).squaredNorm() / (static_cast<double>(K.rows()) - P);
  const Eigen::VectorXd k_step = K * step;
  const Eigen::VectorXd projected = Z * Z.colPivHouseholderQr().solve(k_step);
  return std::sqrt(projected.squaredNorm() / s2 / P);
}

IvIteration iterate_instruments(const Eigen::MatrixXd& K, const Eigen::VectorXd& y, const Eigen::VectorXd& phi0,
                                const InstrumentsOf& instruments, const IvIterationOptions& o) {
  IvIteration it;
  it.phi = phi0;
  it.last_step_se = INFINITY;
  bool relax = false;
  double previous_step = INFINITY;
  Eigen::VectorXd simulated_from;  // the iterate whose plant gave Z
  while (it.simulations < o.max_simulations && !it.converged) {
    Eigen::MatrixXd Z;
    const bool first = it.Z.size() == 0;
    try {
      ++it.simulations;
      Z = instruments(it.phi, first);
    } catch (const InputError& e) {
      if (first || !o.retry_tripped) throw;
      it.trip = e.what();
      ++it.tripped;
      it.phi = 0.5 * (it.phi + simulated_from);
      continue;
    }
    if (Z.rows() != K.rows() || Z.cols() != K.cols())
      throw InputError("IDIM-IV: the instruments' shape differs from the regressor's");
    it.Z = std::move(Z);
    simulated_from = it.phi;
    it.estimate = (it.Z.transpose() * K).colPivHouseholderQr().solve(it.Z.transpose() * y);
    if (!it.estimate.allFinite()) throw InputError("IDIM-IV: the instrumental estimate is not finite");
    const double step = (it.estimate - it.phi).norm();
    it.last_step_se = step_in_standard_errors(K, it.Z, y, it.estimate, it.estimate - it.phi);
    it.converged = it.last_step_se <= o.tolerance;
    if (step > 0.5 * previous_step) relax = true;
    previous_step = step;
    it.phi = relax ? Eigen::VectorXd(0.5 * (it.phi + it.estimate)) : it.estimate;
  }
  return it;
}

}  // namespace dyncal::host
