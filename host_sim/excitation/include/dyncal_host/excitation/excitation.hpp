#pragma once
// `dyncal excite`: excitation trajectory design (survey Sec. 4). A Fourier series per joint
// (Eq. 27) whose coefficients minimise cond(K) (Eq. 26) or maximise log det(K^T K) of the
// identification regressor over one period, every joint kept inside a margin of its position,
// velocity and acceleration limits (robots/<name>/robot.json); NLopt's Subplex does the search.
// Trajectory files are JSON, read back with every limit checked (common's trajectory_file.hpp).

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/friction_model.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/common/trajectory_file.hpp"

namespace dyncal::host {

enum class ExcitationCriterion { cond, logdet };

struct ExciteOptions {
  double f_f = 0.1;   ///< fundamental frequency [Hz] (survey: 0.1 Hz)
  int harmonics = 5;  ///< L (survey: 5)
  ExcitationCriterion criterion = ExcitationCriterion::cond;
  /// Identification model of K: Eq. 7 (base parameters, Fc and beta per joint) or Eq. 4 (base
  /// parameters and d tau_f / d(Fc, Fs, qds, beta) at the robot file's friction values).
  FrictionModel model = FrictionModel::eq7;
  double margin = 0.8;  ///< fraction of each limit the trajectory may use
  int grid = 200;       ///< samples per period for the criterion and the limits
  int candidates = 16;  ///< random starts (seeded); the best one is optimised
  std::uint64_t seed = 1;
  int max_evaluations = 3000;  ///< criterion evaluations of the optimiser
};

struct ExciteResult {
  ExcitationTrajectory trajectory;
  double cond = 0;        ///< cond(K), columns scaled to unit norm (Eq. 26)
  double logdet = 0;      ///< log det(K^T K / rows), same scaling
  double start_cond = 0;  ///< cond of the best random candidate (the optimiser's start)
  int evaluations = 0;
  JointFractions position_use{}, velocity_use{}, acceleration_use{};  ///< fraction of each limit
};

/// Scales each joint's coefficients so that the joint uses at most `margin` of its position
/// half-range, velocity and acceleration limits on a `grid`-point period, and centres it in its
/// range (q0). Throws InputError if a joint does not move.
void fit_to_limits(const RobotDescription& robot, ExcitationTrajectory& t, double margin, int grid);

/// cond(K) and log det(K^T K / rows) of `t` over one period (columns scaled to unit norm) for the
/// robot's compiled model (compiled_robot.hpp). Throws InputError for a robot not compiled in.
void excitation_quality(const RobotDescription& robot, const ExcitationTrajectory& t, FrictionModel model, int grid,
                        double* cond, double* logdet);

/// Designs the excitation. Throws InputError on bad options.
ExciteResult design_excitation(const RobotDescription& robot, const ExciteOptions& options);

/// A Fourier excitation (Eq. 27) inside the robot's position, velocity and acceleration limits
/// (80 % of each), the best of `candidates` seeded random ones by cond(K) of the base-parameter
/// regressor with Eq. 7 friction. Deterministic for a seed.
ExcitationTrajectory default_excitation(const RobotDescription& robot, double f_f, int harmonics, int candidates,
                                        std::uint64_t seed, double* cond);

}  // namespace dyncal::host
