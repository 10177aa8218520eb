#pragma once
// The survey's simulation platform (Sec. 6.1, Fig. 3): the er20 arm on the simulated drive, driven
// along a Fourier excitation (Eq. 27) by the drive's control law with the set parameters as
// feed-forward, sampled at 100 Hz; measured torque with or without Table 7 noise.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/robot_description.hpp"

namespace dyncal::host::survey {

struct SurveyDataOptions {
  FrictionModel friction = FrictionModel::eq7;  ///< the set friction model (Eq. 7 linear, Eq. 4 nonlinear)
  bool torque_noise = false;                    ///< add Table 7 noise to the measured torque
  double sample_rate_hz = 100;                  ///< survey: 100 Hz
  int periods = 2;                              ///< excitation periods recorded (10 s each at f_f = 0.1 Hz)
  std::uint64_t seed = 1;                       ///< noise and excitation seed
  double position_noise_std = 0;                ///< Gaussian noise on the measured position q_meas [rad]
};

/// One recorded run. S samples; matrices are S x 6, joint j in column j - 1.
struct SurveyData {
  Eigen::VectorXd t;                            ///< [s]
  Eigen::MatrixXd q, qd, qdd;                   ///< exact plant state at the samples (q_m, qd_m, qdd_m of Fig. 3)
  Eigen::MatrixXd q_meas;                       ///< measured position: q plus position_noise_std noise
  Eigen::MatrixXd tau;                          ///< measured torque tau_jm [Nm] (with noise if chosen)
  Eigen::MatrixXd tau_cmd;                      ///< commanded torque tau_jc [Nm] (noise-free)
  Eigen::MatrixXd tau_load;                     ///< load torque of Eq. 9 [Nm] (load_torque) on an Eq. 9
                                                ///< run, zeros on the others (only Eq. 9 reads it)
  Scenario scenario;                            ///< friction, noise and seed the drive ran
  DriveTrajectory trajectory;                   ///< the excitation
  double trajectory_cond = 0;                   ///< cond(K) of the designed excitation for the run's
                                                ///< friction model (Eq. 26, unit-scaled columns)
  std::array<double, kDriveJoints> kp{}, kd{};  ///< the drive's PD gains (its known control law), set
                                                ///< from the lightest inertia along the trajectory
  std::vector<std::uint8_t> table;              ///< the drive's active table (feed-forward: set parameters)
  double sample_rate_hz = 0;
};

/// Simulates the survey's platform for `robot` (er20). Throws InputError.
SurveyData simulate_survey_data(const RobotDescription& robot, const SurveyDataOptions& options);

/// Rows [from, from + n) of every sampled signal of `d` (t, q, qd, qdd, q_meas, tau, tau_cmd,
/// tau_load); the rest copied. Throws InputError unless 0 <= from, 0 <= n, from + n <= S.
SurveyData sample_rows(const SurveyData& d, Eigen::Index from, Eigen::Index n);

/// Eq. 9's load torque as a user has it: the torque the joint holds against gravity and the
/// velocity-product terms, Y_b(q, qd, 0) phi_b (the simulated drive's load torque h(q, qd); with the
/// inertial term the friction would depend on the acceleration it causes), phi_b from an Eq. 9
/// least-squares fit of (q, qd, qdd, tau) with its own load torque, from tau_load = tau, repeated
/// until it changes by less than 1e-9 of max |tau| (at most 50 times). S x 6 [Nm].
Eigen::MatrixXd load_torque(const Eigen::MatrixXd& q, const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd,
                            const Eigen::MatrixXd& tau);

/// Runs the same drive (control law: `data`'s table and gains, trajectory and sampling) with a
/// different plant: standard parameters `phi_standard` (60), Eq. 7 friction Fc, beta per joint, no
/// noise. Returns the exact plant samples: the closed-loop simulation IDIM-IV builds its
/// instruments from (Gautier et al. 2013).
std::vector<SimulatedDrive::PlantSample> simulate_closed_loop(const RobotDescription& robot, const SurveyData& data,
                                                              const std::vector<double>& phi_standard,
                                                              const std::array<double, kDriveJoints>& Fc,
                                                              const std::array<double, kDriveJoints>& beta);

}  // namespace dyncal::host::survey
