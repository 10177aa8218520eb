#pragma once
// Calibration against a fixture drive compared with the scenario's true parameters.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/drive/ground_truth.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/logs/joint_log.hpp"
#include "support/drive_uri.hpp"

namespace dyncal::host {

/// Runs calibrate() on the fixture drive `env` (scenario file `scenario`) and compares with the
/// scenario's true parameters: friction within friction_tol, measurable parameters within
/// measurable_tol (relative), the rest within 1 % of the torque. Prints the comparison table.
/// `excitation`: a designed trajectory to play (dyncal excite); empty: calibrate's random choice.
inline void calibrate_and_compare(const char* env, const std::string& scenario_file, double friction_tol,
                                  double measurable_tol,
                                  const std::optional<dyncal::linux_port::Trajectory>& excitation = std::nullopt) {
  const std::string uri = fixture_drive_uri(env);
  ASSERT_FALSE(uri.empty()) << "run through ctest";
  const auto robot = load_robot(default_robots_dir(), "er20");
  const auto scenario = scenario_file.empty() ? default_scenario(robot) : load_scenario(scenario_file, robot);
  CalibrateOptions o;
  o.uri = uri;
  o.terms = parse_model("eq7,rotor_inertia,offset");
  o.progress = false;
  o.excitation = excitation;
  o.save_log =
      (std::filesystem::temp_directory_path() / ("dyncal_excitation_" + std::to_string(getpid()) + ".csv")).string();
  std::ostringstream progress;
  const CalibrateResult r = calibrate(robot, o, progress);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  EXPECT_EQ(r.lost, 0u);
  // The saved excitation log is the data the batch fit used: identify on it gives the same values.
  {
    const JointLog saved = read_csv_log(o.save_log, 6);
    std::filesystem::remove(o.save_log);
    EXPECT_EQ(saved.samples(), r.samples);
    IdentifyOptions io = o.identify;
    io.terms = o.terms;
    const IdentifyResult again = identify(robot, saved, io);
    ASSERT_EQ(again.params.size(), r.phi_batch.size());
    for (size_t i = 0; i < r.phi_batch.size(); ++i) EXPECT_EQ(again.params[i].value, r.phi_batch[i]) << i;
  }
  const auto truth = true_parameters(scenario, o.terms);
  ASSERT_EQ(truth.size(), r.phi_batch.size());
  // Torque share of each parameter on the excitation: share_i = max_j RMS(K_ji phi_i) / RMS(tau_j),
  // with K evaluated on the commanded trajectory. A parameter moving at least 5 % of some joint's
  // torque is measurable to 5 %; a smaller one is held to what it does to the torque instead: its
  // error may move no joint by more than 1 % of that joint's RMS torque.
  using Model = dyncal::IdentificationModel<dyncal::generated::er20::Robot,
                                            dyncal::kFrictionEq7 | dyncal::term::rotor_inertia | dyncal::term::offset>;
  ASSERT_EQ(Model::kNumParams, static_cast<int>(truth.size()));
  const auto traj =
      excitation ? *excitation : default_excitation(robot, o.f_f, o.harmonics, o.candidates, o.seed, nullptr);
  Model::ParamVector<double> phi_true;
  for (int i = 0; i < Model::kNumParams; ++i) phi_true[i] = truth[static_cast<size_t>(i)].value;
  Eigen::Matrix<double, 6, Model::kNumParams> col_ss = Eigen::Matrix<double, 6, Model::kNumParams>::Zero();
  Eigen::Matrix<double, 6, 1> tau_ss = Eigen::Matrix<double, 6, 1>::Zero();
  const int grid = 2000;
  for (int k = 0; k < grid; ++k) {
    Eigen::Matrix<double, 6, 1> q, qd, qdd;
    traj.evaluate(traj.period() * k / grid, q, qd, qdd);
    Model::Regressor<double> K;
    Model::regressor(q, qd, qdd, Eigen::Matrix<double, 6, 1>::Zero().eval(), K);
    col_ss += K.cwiseAbs2();
    tau_ss += (K * phi_true).cwiseAbs2();
  }
  const Eigen::Matrix<double, 6, Model::kNumParams> col_rms = (col_ss / grid).cwiseSqrt();
  const Eigen::Matrix<double, 6, 1> tau_rms = (tau_ss / grid).cwiseSqrt();
  int measurable = 0;
  std::printf("%-14s %12s %12s %10s\n", "parameter", "true", "identified", "error");
  for (size_t i = 0; i < truth.size(); ++i) {
    const double t = truth[i].value, e = r.phi_batch[i];
    const double share = (col_rms.col(static_cast<Eigen::Index>(i)) * std::abs(t)).cwiseQuotient(tau_rms).maxCoeff();
    const double error_share =
        (col_rms.col(static_cast<Eigen::Index>(i)) * std::abs(e - t)).cwiseQuotient(tau_rms).maxCoeff();
    SCOPED_TRACE(truth[i].name + ": true " + std::to_string(t) + ", identified " + std::to_string(e) +
                 ", torque share " + std::to_string(share));
    EXPECT_EQ(truth[i].name, r.names[i]);
    const bool friction = truth[i].name.rfind("Fc", 0) == 0 || truth[i].name.rfind("Fv", 0) == 0;
    std::printf("%-14s %12.5g %12.5g %9.2f%% %s\n", truth[i].name.c_str(), t, e, t != 0 ? 100 * (e - t) / t : 0.0,
                friction        ? "friction"
                : share >= 0.05 ? "measurable"
                                : "small share");
    if (friction) {
      EXPECT_LE(std::abs(e - t), friction_tol * std::abs(t));
    } else if (share >= 0.05) {
      ++measurable;
      EXPECT_LE(std::abs(e - t), measurable_tol * std::abs(t));
    } else {
      EXPECT_LE(error_share, 0.01);
    }
  }
  EXPECT_GE(measurable, 8);  // the criterion is not vacuous: 9 on this excitation (large inertial, Ia3)
  // The drive's own model error drops after the flash on every joint.
  for (int j = 0; j < 6; ++j) EXPECT_LT(r.drive_error_after[j], r.drive_error_before[j]) << "joint " << j + 1;
  print_calibrate_report(std::cout, r);
}

}  // namespace dyncal::host
