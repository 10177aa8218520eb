#pragma once
// Motor torque constants from a known load (docs/robots.md, "Torque constants from a known load";
// Gautier & Briot 2014, Mamedov et al. 2020). A log of motor currents fixes the dynamics only up to
// each motor's torque constant Kt: an arm twice as heavy with half the Kt draws the same currents.
// A second run with a load of known mass on the last link breaks that scale: the load's torque is
// known in Nm, so every motor that feels it learns its Kt.
//
// The model, motor k at sample s (tau = N^T diag(Kt) i, N the transmission matrix):
//   i_k(s) = (1 / Kt_k) (N^-T (Y(s) phi + C_free(s) pi_free + C_known(s) pi_known))_k + noise,
// Y the identification model's regressor (base parameters, friction, rotor inertia, offsets, as
// identify's --model), phi the arm's parameters (shared by both runs), C the load's standard
// columns (the last link's 10, loaded run only): its mass and, when declared, its centre of mass
// known, the rest fitted. The noise is in the current, so the fit is output-error in the current:
// bilinear in (1 / Kt, phi), solved by variable projection (phi, pi_free by least squares for given
// Kt; Gauss-Newton on 1 / Kt, started from the linear torque-form fit) with Gautier's per-motor
// weights.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <ostream>
#include <string>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/methods/identifiability.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// The load of the loaded run, rigidly fixed to the last link.
struct KnownLoad {
  double mass = 0;                                ///< [kg], > 0
  bool com_known = false;                         ///< else its centre of mass is fitted
  Eigen::Vector3d com = Eigen::Vector3d::Zero();  ///< [m], the last link's frame (robot.json's)
};

struct TorqueConstantFit {
  Eigen::VectorXd kt;     ///< per motor [Nm/A]; NaN where not determined
  Eigen::VectorXd stdev;  ///< per motor [Nm/A] (autocorrelation-inflated); NaN where not determined
  std::vector<Verdict>
      verdicts;  ///< per motor: verdict_of(std, |Kt|): Kt is its own scale (signed: the current's sign)
  Eigen::VectorXd current_noise;  ///< per motor: the residual's std [A] (Gautier's weight's inverse)
  Eigen::VectorXd declared;       ///< robot.json's Kt (empty when it gives none), for comparison
  double inflation = 1;           ///< the residuals' autocorrelation factor S / n_eff (the larger run's)
  long samples_unloaded = 0, samples_loaded = 0;
  int nuisance_rank = 0;  ///< the arm's and the load's fitted parameters the pair determines together
  int iterations = 0;     ///< Gauss-Newton steps
  KnownLoad load;
  std::vector<std::string> notes;
  bool all_determined() const;
};

/// Kt per motor from `unloaded` and `loaded`, two logs of `robot` whose tau holds N^T i (the motor
/// currents [A] through the transmission: read_current_csv_log with every Kt 1), prepared as
/// identify prepares a log with `options` (filter, decimation, --min-speed; the model's terms and
/// effects are the arm's nuisance parameters). Throws InputError: a load mass not > 0, a log the
/// preparation refuses, a linear start with no finite nonzero Kt for a motor (the pair does not
/// show the load: name the motors), no convergence.
TorqueConstantFit identify_torque_constants(const RobotDescription& robot, const JointLog& unloaded,
                                            const JointLog& loaded, const KnownLoad& load,
                                            const IdentifyOptions& options);

/// The table: per motor Kt, std, 95 % interval, verdict, robot.json's value; what to do with it.
void print_torque_constants(std::ostream& out, const TorqueConstantFit& fit);
/// {"load": {...}, "motors": [{"motor", "kt", "std", "verdict", "current_noise", "declared"}], ...}.
nlohmann::json torque_constants_json(const TorqueConstantFit& fit);

}  // namespace dyncal::host
