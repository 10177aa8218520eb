#include "dyncal_host/survey/survey_data.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>
#include <string>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/drive/closed_loop.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/identification/methods/friction_parameters.hpp"

namespace dyncal::host::survey {
namespace {

using Robot = dyncal::generated::er20::Robot;

/// The study's set friction of one joint for `model`, from robot.json's Eq. 4 values (Fc, Fs, qds,
/// beta), so that the six curves share Coulomb level, static peak, Stribeck velocity and viscous
/// slope: Eq. 5 f1 = Fc, f2 = Fc - Fs (the static peak: f1 - f2 = Fs at rest), f3 = qds, f4 =
/// 0.1 Fc (a 10 % drop at high speed), f5 = 1 s/rad; Eq. 6 f1 = Fc, f2 = Fs - Fc, f3 = 1 / qds,
/// f4 = 2 / qds; Eq. 8 fp = 0.1 Fc; Eq. 9 fl = 0.05 (5 % of the load torque).
void set_study_friction(JointFriction& f, FrictionModel model) {
  f.model = model;
  if (model == FrictionModel::eq5) {
    f.f1 = f.Fc;
    f.f2 = f.Fc - f.Fs;
    f.f3 = f.qds;
    f.f4 = 0.1 * f.Fc;
    f.f5 = 1.0;
  } else if (model == FrictionModel::eq6) {
    f.f1 = f.Fc;
    f.f2 = f.Fs - f.Fc;
    f.f3 = 1.0 / f.qds;
    f.f4 = 2.0 / f.qds;
  }
  f.fp = model == FrictionModel::eq8 ? 0.1 * f.Fc : 0.0;
  f.fl = model == FrictionModel::eq9 ? 0.05 : 0.0;
}

/// The control law's feed-forward table: the set base parameters and the set Fc, beta (Eq. 7 part
/// of the set friction), as Fig. 3 ("the inverse dynamic and friction model also takes phi_s").
std::vector<std::uint8_t> set_parameter_table(const Scenario& s) {
  JointArray Fc{}, beta{};
  for (int j = 0; j < kSurveyJoints; ++j) {
    Fc[static_cast<size_t>(j)] = s.friction[j].Fc;
    beta[static_cast<size_t>(j)] = s.friction[j].beta;
  }
  return encoded_table(nominal_table(s.robot, Fc, beta));
}

/// The drive's PD gains (natural frequency bandwidth_hz, damping) set from the smallest diagonal
/// inertia each joint sees along the trajectory instead of at its start pose: without rotor inertia
/// the arm's inertia about joint 1 changes several-fold as it folds, and a discrete PD loop tuned
/// at a heavy pose goes unstable at a light one.
void gains_along(const DriveTrajectory& trajectory, const Scenario& scenario, JointArray& kp, JointArray& kd) {
  using Vec = Eigen::Matrix<double, 6, 1>;
  Eigen::Matrix<double, Robot::kNumStandard, 1> phi;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = dyncal::generated::er20::kNominalStandard[i];
  Vec m_min = Vec::Constant(INFINITY);
  constexpr int kGrid = 400;
  for (int k = 0; k < kGrid; ++k) {
    Vec q, qd, qdd;
    trajectory.evaluate(trajectory.period() * k / kGrid, q, qd, qdd);
    Eigen::Matrix<double, 6, 6> mass;
    Robot::mass_matrix(q, phi, mass);
    m_min = m_min.cwiseMin(mass.diagonal());
  }
  const double w = 2.0 * M_PI * scenario.bandwidth_hz;
  for (int j = 0; j < kSurveyJoints; ++j) {
    const double m = m_min[j] + scenario.effects[j].rotor_inertia;
    kp[j] = m * w * w;
    kd[j] = 2.0 * scenario.damping * m * w;
  }
}

}  // namespace

ExciteResult study_excitation(const RobotDescription& robot, FrictionModel model, std::uint64_t seed) {
  // The survey designed for Eq. 7 and Eq. 4 only, so the other linear models (Eq. 8, 9) play Eq. 7's
  // design and the other nonlinear ones (Eq. 5, 6) Eq. 4's.
  ExciteOptions xo;
  xo.model = is_linear(model) ? FrictionModel::eq7 : FrictionModel::eq4;
  xo.seed = seed;
  return design_excitation(robot, xo);
}

SurveyData simulate_survey_data(const RobotDescription& robot, const SurveyDataOptions& o) {
  if (robot.name != Robot::kName) throw InputError("the survey study runs on the er20 arm");
  if (!(o.sample_rate_hz > 0) || o.periods < 1) throw InputError("survey data: sample rate > 0 and periods >= 1");
  SurveyData d;
  d.scenario = default_scenario(robot);
  d.scenario.seed = o.seed;
  d.scenario.sample_rate_hz = o.sample_rate_hz;
  d.scenario.encoder_counts = 0;  // exact q_m (Sec. 6.1 step 1); position noise is studied separately
  if (!o.torque_noise) d.scenario.tau_noise_std.fill(0.0);
  for (int j = 0; j < kSurveyJoints; ++j) {
    set_study_friction(d.scenario.friction[j], o.friction);
    d.scenario.effects[j].rotor_inertia = 0.0;  // the survey's model (Eq. 2) has none
  }
  d.table = set_parameter_table(d.scenario);
  const ExciteResult designed = o.design ? *o.design : study_excitation(robot, o.friction, o.seed);
  const auto& traj = designed.trajectory;
  d.trajectory_cond = designed.cond;
  d.trajectory.f_f = traj.f_f;
  d.trajectory.harmonics = traj.harmonics;
  for (int j = 0; j < kSurveyJoints; ++j) {
    d.trajectory.q0[j] = traj.q0[j];
    for (int l = 0; l < modbus_map::kMaxHarmonics; ++l) {
      d.trajectory.a(j, l) = traj.a(j, l);
      d.trajectory.b(j, l) = traj.b(j, l);
    }
  }
  d.sample_rate_hz = o.sample_rate_hz;
  gains_along(d.trajectory, d.scenario, d.kp, d.kd);
  const auto samples =
      play_closed_loop(robot, d.scenario, d.trajectory, o.periods, o.sample_rate_hz, d.table, {}, &d.kp, &d.kd);
  const Eigen::Index S = static_cast<Eigen::Index>(samples.size());
  d.t.resize(S);
  d.q.resize(S, kSurveyJoints);
  d.qd.resize(S, kSurveyJoints);
  d.qdd.resize(S, kSurveyJoints);
  d.tau.resize(S, kSurveyJoints);
  d.tau_cmd.resize(S, kSurveyJoints);
  d.q_meas.resize(S, kSurveyJoints);
  if (!(o.position_noise_std >= 0)) throw InputError("survey data: position noise >= 0");
  std::mt19937_64 rng(o.seed ^ 0x9e3779b97f4a7c15ULL);  // independent of the drive's torque noise
  std::normal_distribution<double> normal(0.0, 1.0);
  for (Eigen::Index s = 0; s < S; ++s) {
    const auto& p = samples[static_cast<size_t>(s)];
    d.t[s] = p.t;
    for (int j = 0; j < kSurveyJoints; ++j) {
      d.q(s, j) = p.q[j];
      d.qd(s, j) = p.qd[j];
      d.qdd(s, j) = p.qdd[j];
      d.tau(s, j) = p.tau_measured[j];
      d.tau_cmd(s, j) = p.tau_cmd[j];
      d.q_meas(s, j) = p.q[j] + (o.position_noise_std > 0 ? o.position_noise_std * normal(rng) : 0.0);
    }
  }
  // Only Eq. 9 reads the load torque (the Table 12 stand-in computes its own from its states).
  d.tau_load = o.friction == FrictionModel::eq9 ? load_torque(d.q, d.qd, d.qdd, d.tau)
                                                : Eigen::MatrixXd::Zero(S, kSurveyJoints).eval();
  return d;
}

std::vector<SimulatedDrive::PlantSample> simulate_closed_loop(const RobotDescription& robot, const SurveyData& data,
                                                              const std::vector<double>& phi_standard,
                                                              const JointArray& Fc, const JointArray& beta) {
  Scenario s = data.scenario;
  s.tau_noise_std.fill(0.0);
  for (int j = 0; j < kSurveyJoints; ++j) {
    s.friction[j] = JointFriction{};
    s.friction[j].model = FrictionModel::eq7;
    s.friction[j].Fc = Fc[j];
    s.friction[j].beta = beta[j];
  }
  const int periods = static_cast<int>(
      std::lround(static_cast<double>(data.t.size()) / (data.trajectory.period() * data.sample_rate_hz)));
  auto samples = play_closed_loop(robot, s, data.trajectory, std::max(periods, 1), data.sample_rate_hz, data.table,
                                  phi_standard, &data.kp, &data.kd);
  return samples;
}

SurveyData sample_rows(const SurveyData& d, Eigen::Index from, Eigen::Index n) {
  SurveyData r = d;
  static_cast<RunData&>(r) = sample_rows(static_cast<const RunData&>(d), from, n);
  r.tau_cmd = d.tau_cmd.middleRows(from, n);
  return r;
}

ClosedLoopSimulation closed_loop_of(const RobotDescription& robot, const SurveyData& data) {
  return [&robot, &data](const Eigen::VectorXd& phi_standard, const std::array<double, 6>& Fc,
                         const std::array<double, 6>& beta) {
    JointArray fc{}, b{};
    std::copy(Fc.begin(), Fc.end(), fc.begin());
    std::copy(beta.begin(), beta.end(), b.begin());
    const auto sim = simulate_closed_loop(
        robot, data, std::vector<double>(phi_standard.data(), phi_standard.data() + phi_standard.size()), fc, b);
    Eigen::MatrixXd q(static_cast<Eigen::Index>(sim.size()), kSurveyJoints);
    for (Eigen::Index s = 0; s < q.rows(); ++s)
      for (int j = 0; j < kSurveyJoints; ++j) q(s, j) = sim[static_cast<size_t>(s)].q[j];
    return q;
  };
}

std::vector<double> set_friction(const Scenario& s, FrictionModel model) {
  std::vector<double> out;
  for (int j = 0; j < kSurveyJoints; ++j) {
    const JointFriction& f = s.friction[j];
    switch (model) {
      case FrictionModel::eq7:
        out.insert(out.end(), {f.Fc, f.beta});
        break;
      case FrictionModel::eq8:
        out.insert(out.end(), {f.Fc, f.beta, f.fp});
        break;
      case FrictionModel::eq9:
        out.insert(out.end(), {f.Fc, f.beta, f.fl});
        break;
      case FrictionModel::eq4:
        out.insert(out.end(), {f.Fc, f.Fs, f.qds, f.beta});
        break;
      case FrictionModel::eq5:
        out.insert(out.end(), {f.f1, f.f2, f.f3, f.f4, f.f5, f.beta});
        break;
      case FrictionModel::eq6:
        out.insert(out.end(), {f.f1, f.f2, f.f3, f.f4, f.beta});
        break;
    }
  }
  return out;
}

}  // namespace dyncal::host::survey
