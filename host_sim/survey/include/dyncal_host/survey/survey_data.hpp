#pragma once
// The survey's simulation platform (Sec. 6.1, Fig. 3): the er20 arm on the simulated drive, driven
// along a Fourier excitation (Eq. 27) by the drive's control law with the set parameters as
// feed-forward, sampled at 100 Hz; measured torque with or without Table 7 noise.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/survey/methods/idim_iv.hpp"
#include "dyncal_host/survey/methods/run_data.hpp"

namespace dyncal::host::survey {

struct SurveyDataOptions {
  FrictionModel friction = FrictionModel::eq7;  ///< the set friction model (Eq. 7 linear, Eq. 4 nonlinear)
  bool torque_noise = false;                    ///< add Table 7 noise to the measured torque
  double sample_rate_hz = 100;                  ///< survey: 100 Hz
  int periods = 2;                              ///< excitation periods recorded (10 s each at f_f = 0.1 Hz)
  std::uint64_t seed = 1;                       ///< noise and excitation seed
  double position_noise_std = 0;                ///< Gaussian noise on the measured position q_meas [rad]
  /// The excitation designed for this run (study_excitation of its friction model and seed), when
  /// the caller has it: the design is deterministic, so a study designs each one once; null: designed here.
  const ExciteResult* design = nullptr;
};

/// The survey's optimal trajectory for a run of friction model `model` (Sec. 6.1, Fig. 2): Eq. 27
/// with L = 5, f_f = 0.1 Hz, cond(K) minimised for Eq. 7 (linear models) or Eq. 4 (nonlinear ones)
/// by dyncal excite's design from `seed`.
ExciteResult study_excitation(const RobotDescription& robot, FrictionModel model, std::uint64_t seed);

/// One recorded run of the study: the RunData the methods take (q, qd, qdd the exact plant state at
/// the samples: q_m, qd_m, qdd_m of Fig. 3; q_meas with position_noise_std noise; tau the measured
/// torque tau_jm, with noise if chosen; tau_load Eq. 9's on an Eq. 9 run, zeros on the others), and
/// what the study knows beside them. Matrices S x 6.
/// Joints of the study's arm (er20; the study stays er20-specific).
inline constexpr int kSurveyJoints = 6;

struct SurveyData : RunData {
  Eigen::MatrixXd tau_cmd;          ///< commanded torque tau_jc [Nm] (noise-free)
  Scenario scenario;                ///< friction, noise and seed the drive ran
  DriveTrajectory trajectory;       ///< the excitation
  double trajectory_cond = 0;       ///< cond(K) of the designed excitation for the run's
                                    ///< friction model (Eq. 26, unit-scaled columns)
  JointArray kp{}, kd{};            ///< the drive's PD gains (its known control law), set
                                    ///< from the lightest inertia along the trajectory
  std::vector<std::uint8_t> table;  ///< the drive's active table (feed-forward: set parameters)
};

/// Simulates the survey's platform for `robot` (er20). Throws InputError.
SurveyData simulate_survey_data(const RobotDescription& robot, const SurveyDataOptions& options);

/// Rows [from, from + n) of every sampled signal of `d` (the RunData's and tau_cmd); the rest copied.
/// Throws InputError unless 0 <= from, 0 <= n, from + n <= S.
SurveyData sample_rows(const SurveyData& d, Eigen::Index from, Eigen::Index n);

/// Runs the same drive (control law: `data`'s table and gains, trajectory and sampling) with a
/// different plant: standard parameters `phi_standard` (60), Eq. 7 friction Fc, beta per joint, no
/// noise. Returns the exact plant samples: the closed-loop simulation IDIM-IV builds its
/// instruments from (Gautier et al. 2013).
std::vector<SimulatedDrive::PlantSample> simulate_closed_loop(const RobotDescription& robot, const SurveyData& data,
                                                              const std::vector<double>& phi_standard,
                                                              const JointArray& Fc, const JointArray& beta);

/// simulate_closed_loop as IDIM-IV takes it: the plant's positions at the run's samples (S x 6).
ClosedLoopSimulation closed_loop_of(const RobotDescription& robot, const SurveyData& data);

/// Set friction parameters of every joint of `scenario` (its JointFriction fields), joint-major in
/// friction_parameter_names order. Eq. 5 and 6 read f1..f5; Eq. 8 fp; Eq. 9 fl.
std::vector<double> set_friction(const Scenario& scenario, FrictionModel model);

}  // namespace dyncal::host::survey
