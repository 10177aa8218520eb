#pragma once
// IDIM-IV (survey Eq. 17; Gautier, Janot and Vandanjon 2013): the instrumental-variable estimate
// phi = (Z^T K)^-1 Z^T tau, K the Eq. 7 regressor of the measured (differentiated) states and Z the
// same regressor of the states a closed-loop simulation of the drive's known control law produces
// with the previous estimate as the plant, iterated to convergence. Z does not see the noise of the
// measured positions, so the noise does not bias the estimate as it biases least squares.

#include <array>
#include <functional>

#include "dyncal_host/survey/methods/methods.hpp"
#include "dyncal_host/survey/methods/run_data.hpp"

namespace dyncal::host {

/// A closed-loop simulation of the drive's known control law (Gautier et al. 2013): the plant's
/// positions [rad] at the run's sample instants (S x 6) when its standard parameters are
/// phi_standard (60) and its friction Eq. 7 with Fc [Nm], beta [Nm s/rad] per joint. Throws
/// InputError when the simulation fails (for example the drive trips).
using ClosedLoopSimulation = std::function<Eigen::MatrixXd(
    const Eigen::VectorXd& phi_standard, const std::array<double, 6>& Fc, const std::array<double, 6>& beta)>;

struct IdimIvOptions {
  bool filter = true;       ///< low-pass the measured positions before differentiating (Table 10)
  double cutoff_hz = 20;    ///< survey Sec. 6.4: 20 Hz
  int filter_order = 4;     ///< fourth-order Butterworth (zero phase)
  int max_iterations = 20;  ///< closed-loop simulations at most
  /// Parallel decimation of the torque and the regressor (Gautier; survey Sec. 3.1): both low-passed
  /// by the same filter, then every decimation-th sample kept; 1: none (the study's default: at
  /// 100 Hz it changes nothing measurable, docs/survey.md Table 10).
  int decimation = 1;
  /// Stop when an iteration moves the estimate by at most this many of its standard errors (RMS
  /// over the parameters, in the estimate's covariance): the iterate then adds about tolerance^2
  /// (1 %) to the estimate's variance. A relative tolerance on |phi| was blind to the small
  /// parameters; and on most seeds the iteration keeps moving by 0.02-0.3 standard errors however
  /// long it runs (docs/survey.md, Table 10), so a tighter test only burns simulations.
  double tolerance = 0.1;
};

/// q, qd, qdd from the measured positions: optionally filtered (zero-phase Butterworth), then
/// central differences (S x 6 each).
void measured_states(const RunData& d, const IdimIvOptions& options, Eigen::MatrixXd& q, Eigen::MatrixXd& qd,
                     Eigen::MatrixXd& qdd);

/// The pseudo-inverse (Eq. 15) on the measured states: the least-squares reference of Table 10.
Estimate pseudo_inverse_measured(const RunData& d, const MethodSettings& settings, const IdimIvOptions& options);

/// IDIM-IV from the pseudo-inverse's estimate: identification's iterate_instruments
/// (instrumental_iteration.hpp, the same iteration as identify --method iv) on the study's system. Each iteration's
/// plant: the standard parameters most probable under the CAD prior given the base parameters (standard_from_base),
/// projected onto the physically consistent set, with Fc, beta >= 0. Converged when an iteration moves the estimate by
/// at most options.tolerance standard errors; once a step fails to halve the previous one, half steps (the map can
/// cycle between two plants). Estimate::iterations: closed-loop simulations run; Estimate::note says whether it
/// converged and the last step in standard errors. `simulate` runs the closed loop for each iterate's plant. Throws
/// InputError if a simulation fails (the drive tripped: it left the robot's limits).
Estimate idim_iv(const RunData& d, const MethodSettings& settings, const IdimIvOptions& options,
                 const ClosedLoopSimulation& simulate);

}  // namespace dyncal::host
