#pragma once
// The iteration of IDIM-IV (survey Eq. 17; Gautier, Janot and Vandanjon 2013), for any robot and
// any caller: identify's --method iv (instrumental_variables.hpp) and the survey study's Table 10.
// Each iterate's plant is simulated in closed loop under the drive's known law; the simulated
// states' regressor is the instruments Z; the next iterate is the IV estimate (Z^T K)^-1 Z^T y. The
// callers differ only in how a plant is made from an iterate and how its states are prepared,
// which `instruments` does.

#include <Eigen/Core>
#include <functional>
#include <string>

namespace dyncal::host {

/// The instruments of the plant made from iterate phi (P): Z, rows and columns as K, weighted as K.
/// `first` is true for the first plant (the callers take the nominal inertials there: least
/// squares on noisy positions underestimates the inertias, and a plant lighter than the arm can
/// make the law's fixed-gain loop unstable). Throws InputError when the simulation fails (the plant
/// trips the drive).
using InstrumentsOf = std::function<Eigen::MatrixXd(const Eigen::VectorXd& phi, bool first)>;

struct IvIterationOptions {
  int max_simulations = 20;
  /// Converged when an iteration moves the estimate by at most this many of its standard errors
  /// (RMS over the parameters, in the IV covariance): such a step adds about tolerance^2 to the
  /// estimate's variance.
  double tolerance = 0.1;
  /// A plant after the first that trips the drive: back half way towards the iterate whose plant
  /// last simulated, and go on (true); or let the InputError through (false).
  bool retry_tripped = false;
};

struct IvIteration {
  Eigen::VectorXd phi;       ///< the last iterate (a half step of the last IV estimate once relaxed)
  Eigen::VectorXd estimate;  ///< the IV estimate of the last instruments
  Eigen::MatrixXd Z;         ///< the last instruments
  int simulations = 0;       ///< closed-loop simulations run (tripped ones included)
  int tripped = 0;           ///< of them, plants that tripped the drive (retry_tripped)
  std::string trip;          ///< the last trip's message
  bool converged = false;
  double last_step_se = 0;  ///< the last step in standard errors
};

/// Iterates IDIM-IV on the weighted system y = K phi (rows x P) from phi0 (the least-squares
/// estimate). Once a step fails to halve the previous one it takes half steps (Mann iteration): the
/// map from plant to estimate need not contract, and can cycle between two plants. Throws
/// InputError: the first simulation fails (or any, without retry_tripped), an estimate is not
/// finite, the instruments' shape is not K's.
IvIteration iterate_instruments(const Eigen::MatrixXd& K, const Eigen::VectorXd& y, const Eigen::VectorXd& phi0,
                                const InstrumentsOf& instruments, const IvIterationOptions& options);

/// The length of `step` in standard errors of the IV estimate phi of the weighted system y = K phi
/// with instruments Z: sqrt(step^T C^-1 step / P), C = s^2 (Z^T K)^-1 Z^T Z (K^T Z)^-1, s^2 the
/// residual variance |y - K phi|^2 / (rows - P); step^T C^-1 step = |P_Z K step|^2 / s^2 (P_Z the
/// projection onto Z's columns). The rows' errors are taken independent: filtered, differentiated
/// positions make them correlated, so the step is if anything overstated (a stricter test).
double step_in_standard_errors(const Eigen::MatrixXd& K, const Eigen::MatrixXd& Z, const Eigen::VectorXd& y,
                               const Eigen::VectorXd& phi, const Eigen::VectorXd& step);

}  // namespace dyncal::host
