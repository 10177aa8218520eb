#pragma once
// The robots compiled into this build, by name: each robots/<name>/ folder (and tests/robots/<name>/)
// becomes generated code and a few translation units (host_sim/robots/) that register the
// robot's operations here when the program starts. Code that works on "any robot" looks the robot
// up by its robot.json name and calls through these function pointers; nothing names a robot.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/friction_model.hpp"
#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/identify_result.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "dyncal_host/model/term_set_model.hpp"

namespace dyncal::host {

/// One robot's generated model as run-time operations. Vectors are joint-ordered (N entries),
/// parameters in the generated StandardParam order (10 N).
struct CompiledRobot {
  std::string name;
  std::uint32_t robot_id = 0;  ///< the generated kRobotId
  int num_joints = 0, num_standard = 0, num_base = 0;
  std::vector<double> nominal_standard;  ///< kNominalStandard: the description's inertials
  std::vector<bool> prismatic;           ///< kJointPrismatic: per joint, prismatic (else revolute)

  /// Stacked, column-normalised regressor of one period of `t` on `grid` points (rows N x grid):
  /// Eq. 7 (base parameters, Fc and beta per joint), or Eq. 4 (base parameters and d tau_f /
  /// d(Fc, Fs, qds, beta) at `friction`).
  using ExcitationRegressorFn = Eigen::MatrixXd (*)(const ExcitationTrajectory& t, FrictionModel model,
                                                    const std::vector<NominalFriction>& friction, int grid);
  /// tau = ID(q, qd, qdd; phi) [Nm], N-vectors, phi the 10 N standard parameters.
  using InverseDynamicsFn = Eigen::VectorXd (*)(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                                const Eigen::VectorXd& qdd, const Eigen::VectorXd& phi);

  /// phi_b = the base parameters (BaseParam order, num_base) of the standard parameters phi (Gautier).
  using StandardToBaseFn = Eigen::VectorXd (*)(const Eigen::VectorXd& phi);

  /// Y_b(q, qd, qdd) (N x num_base): tau = Y_b phi_b [Nm].
  using BaseRegressorFn = Eigen::MatrixXd (*)(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                              const Eigen::VectorXd& qdd);

  /// The momentum observer (lib/ momentum_observer.hpp) with `table` as the model and gain K
  /// [1/s] on every joint, over rows [from, to) of a log sampled every dt [s]: q [rad], qd [rad/s],
  /// the friction terms' velocity qd_friction [rad/s] and tau [Nm] (S x N); started at row `from`;
  /// its residual [Nm] into the same rows of r (S x N, sized by the caller). Throws InputError: the
  /// observer refuses the table or the gain (its status named), or a sample (its row, 1-based).
  using MomentumResidualFn = void (*)(const ParameterTable& table, double gain, double dt, const Eigen::MatrixXd& q,
                                      const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qd_friction,
                                      const Eigen::MatrixXd& tau, Eigen::Index from, Eigen::Index to,
                                      Eigen::MatrixXd& r);
  /// The direct residual (lib/ direct_residual.hpp) over the same rows, with the acceleration qdd
  /// [rad/s^2] (S x N) besides; the same errors.
  using DirectResidualFn = void (*)(const ParameterTable& table, double gain, double dt, const Eigen::MatrixXd& q,
                                    const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qd_friction,
                                    const Eigen::MatrixXd& qdd, const Eigen::MatrixXd& tau, Eigen::Index from,
                                    Eigen::Index to, Eigen::MatrixXd& r);

  /// The identification model of each built term set (by built_term_set_index): what the
  /// identification pipeline, compiled once, needs of this robot. Its names are the identified
  /// parameters in table order (base parameters, then the terms'), as identify reports them and a
  /// parameter file lists them.
  std::array<TermSetModel, kBuiltTermSets> models{};
  ExcitationRegressorFn excitation_regressor = nullptr;
  InverseDynamicsFn inverse_dynamics = nullptr;
  StandardToBaseFn standard_to_base = nullptr;
  BaseRegressorFn base_regressor = nullptr;
  MomentumResidualFn momentum_residual = nullptr;
  DirectResidualFn direct_residual = nullptr;
};

/// Adds (or completes) the entry of `robot.name`: fields that are set in `robot` overwrite the
/// entry's. Called from static initialisers of the robots' translation units; returns true.
bool register_robot(const CompiledRobot& robot);

/// The compiled robot `name`. Throws InputError listing the compiled robots when it is not one.
const CompiledRobot& compiled_robot(const std::string& name);

/// Names of the compiled robots, sorted.
std::vector<std::string> compiled_robot_names();

/// The operations of `robot` checked against its description: the joint count, and an MDH robot's
/// links (robot.json's inertials) against the compiled kNominalStandard to 1e-9 relative (an edit
/// since the build is named with its field). Throws InputError.
const CompiledRobot& compiled_robot_for(const RobotDescription& robot);

/// The identification model of `robot` for the built term set `terms` (model_terms.hpp). Throws
/// InputError naming the model when it is not built.
const TermSetModel& term_set_model(const CompiledRobot& robot, unsigned terms);

/// The base map K (num_base x num_standard): phi_b = K phi (Gautier), from standard_to_base.
Eigen::MatrixXd base_map(const CompiledRobot& robot);

/// The robot `name` under `robots_dir` as every command loads it, and robot check checks it first
/// (docs/robots.md "Checks"): robot.json read and checked (load_robot), checked against its compiled
/// model (compiled_robot_for: joint count, an MDH robot's links), tau_max derived where absent.
/// Throws InputError: the first error, one line.
RobotDescription load_checked_robot(const std::string& robots_dir, const std::string& name);

/// Samples and seed of derive_tau_max.
inline constexpr int kDerivedTauMaxSamples = 4096;
inline constexpr unsigned kDerivedTauMaxSeed = 20;

/// Fills robot.tau_max when robot.json gives none (docs/robots.md): per joint, the largest |tau| of
/// the nominal model's inverse dynamics (robot.json's inertials, no friction) over
/// kDerivedTauMaxSamples seeded uniform samples of the rated envelope q in [q_min, q_max],
/// |qd| <= qd_max, |qdd| <= qdd_max; sets tau_max_derived. A scale for the e_T_abs indices and the
/// simulated drive, not a rating. No-op when tau_max is set. Throws InputError (robot not compiled,
/// a joint with no torque at all).
void derive_tau_max(RobotDescription& robot);

}  // namespace dyncal::host
