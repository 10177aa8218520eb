#include "dyncal_host/excitation/excitation.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <nlopt.hpp>
#include <random>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {
namespace {

using Vec = TrajectoryVec;  // rows past the robot's joints unused
namespace mm = dyncal::modbus_map;

/// cond(K) and log det of `t`; Eq. 4: the Jacobian at the robot file's friction values.
void quality(const RobotDescription& robot, const ExcitationTrajectory& t, FrictionModel model, int grid, double* cond,
             double* logdet) {
  const std::vector<NominalFriction> friction =
      robot.friction.empty() ? std::vector<NominalFriction>(static_cast<size_t>(robot.num_joints)) : robot.friction;
  if (model != FrictionModel::eq7 && model != FrictionModel::eq4) throw InputError("excitation: model eq7 or eq4");
  const Eigen::MatrixXd W = compiled_robot_for(robot).excitation_regressor(t, model, friction, grid);
  // Eigenvalues of the (column-normalised) information matrix: cond(K) = sqrt(lambda_max / lambda_min).
  const Eigen::MatrixXd G = W.transpose() * W / static_cast<double>(W.rows());
  const Eigen::VectorXd ev = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(G, Eigen::EigenvaluesOnly).eigenvalues();
  const double lo = ev[0], hi = ev[ev.size() - 1];
  if (cond) *cond = lo > 0 ? std::sqrt(hi / lo) : std::numeric_limits<double>::infinity();
  if (logdet) *logdet = lo > 0 ? ev.array().log().sum() : -std::numeric_limits<double>::infinity();
}

struct Design {
  const RobotDescription* robot = nullptr;
  const ExciteOptions* options = nullptr;
  int evaluations = 0;
  double best = std::numeric_limits<double>::infinity();
  ExcitationTrajectory best_trajectory;

  ExcitationTrajectory trajectory(const double* x) const {
    ExcitationTrajectory t;
    t.f_f = options->f_f;
    t.harmonics = options->harmonics;
    const int L = options->harmonics;
    for (int j = 0; j < robot->num_joints; ++j) {
      for (int l = 0; l < L; ++l) {
        t.a(j, l) = x[2 * L * j + l];
        t.b(j, l) = x[2 * L * j + L + l];
      }
    }
    return t;
  }

  /// The criterion to minimise: log cond(K) or -log det(K^T K / rows), after fitting the limits.
  double value(const double* x) {
    ++evaluations;
    ExcitationTrajectory t = trajectory(x);
    for (int j = 0; j < robot->num_joints; ++j) {
      if (t.a.row(j).head(options->harmonics).squaredNorm() + t.b.row(j).head(options->harmonics).squaredNorm() == 0) {
        return 1e300;  // a joint that does not move: the regressor is singular
      }
    }
    fit_to_limits(*robot, t, options->margin, options->grid);
    double cond = 0, logdet = 0;
    quality(*robot, t, options->model, options->grid, &cond, &logdet);
    const double v = options->criterion == ExcitationCriterion::cond ? std::log(cond) : -logdet;
    const double f = std::isfinite(v) ? v : 1e300;
    if (f < best) {
      best = f;
      best_trajectory = t;
    }
    return f;
  }
};

double nlopt_value(const std::vector<double>& x, std::vector<double>& /*grad*/, void* data) {
  return static_cast<Design*>(data)->value(x.data());
}

}  // namespace

void fit_to_limits(const RobotDescription& robot, ExcitationTrajectory& t, double margin, int grid) {
  if (!(margin > 0 && margin <= 1) || grid < 8) throw InputError("excitation: margin in (0, 1], grid >= 8");
  t.q0.setZero();
  Vec qmin, qmax, vmax, amax;
  trajectory_extremes(t, grid, qmin, qmax, vmax, amax);
  for (int j = 0; j < robot.num_joints; ++j) {
    const double half_range = 0.5 * (robot.q_max[j] - robot.q_min[j]);
    const double s =
        margin * std::min({half_range / std::max(0.5 * (qmax[j] - qmin[j]), 1e-300),
                           robot.qd_max[j] / std::max(vmax[j], 1e-300), robot.qdd_max[j] / std::max(amax[j], 1e-300)});
    if (!(vmax[j] > 0) || !std::isfinite(s))
      throw InputError("excitation: joint " + std::to_string(j + 1) + " does not move");
    t.a.row(j) *= s;
    t.b.row(j) *= s;
    t.q0[j] = 0.5 * (robot.q_max[j] + robot.q_min[j]) - s * 0.5 * (qmax[j] + qmin[j]);
  }
}

void excitation_quality(const RobotDescription& robot, const ExcitationTrajectory& t, FrictionModel model, int grid,
                        double* cond, double* logdet) {
  quality(robot, t, model, grid, cond, logdet);
}

ExciteResult design_excitation(const RobotDescription& robot, const ExciteOptions& o) {
  compiled_robot_for(robot);  // throws when the robot is not compiled in
  if (!(o.f_f > 0) || o.harmonics < 1 || o.harmonics > mm::kMaxHarmonics || o.candidates < 1 || o.max_evaluations < 1) {
    throw InputError("excitation: f_f > 0, harmonics 1..8, candidates >= 1, evaluations >= 1");
  }
  Design d;
  d.robot = &robot;
  d.options = &o;
  const int L = o.harmonics, N = robot.num_joints, D = 2 * L * N;
  // Random starts: coefficients uniform in +-1 / l (the spectrum of a smooth motion), seeded.
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> x0;
  double start = std::numeric_limits<double>::infinity();
  for (int c = 0; c < o.candidates; ++c) {
    std::vector<double> x(static_cast<size_t>(D));
    for (int j = 0; j < N; ++j)
      for (int k = 0; k < 2 * L; ++k) x[static_cast<size_t>(2 * L * j + k)] = u(rng) / (k % L + 1);
    const double v = d.value(x.data());
    if (v < start) {
      start = v;
      x0 = x;
    }
  }
  ExciteResult r;
  quality(robot, d.best_trajectory, o.model, o.grid, &r.start_cond, nullptr);
  // Subplex (Rowan 1990): derivative-free; the criterion is not smooth where eigenvalues cross.
  nlopt::opt opt(nlopt::LN_SBPLX, static_cast<unsigned>(D));
  opt.set_min_objective(nlopt_value, &d);
  opt.set_maxeval(std::max(1, o.max_evaluations - o.candidates));
  opt.set_xtol_rel(1e-6);
  std::vector<double> step(static_cast<size_t>(D));
  for (int i = 0; i < D; ++i) step[static_cast<size_t>(i)] = 0.2 / (i % L + 1);
  opt.set_initial_step(step);
  double f = 0;
  try {
    opt.optimize(x0, f);
  } catch (const nlopt::roundoff_limited&) {
    // the best point seen is kept in d.best_trajectory
  } catch (const std::exception& e) {
    throw InputError(std::string("excitation design (NLopt Subplex) failed: ") + e.what());
  }
  r.trajectory = d.best_trajectory;
  r.evaluations = d.evaluations;
  quality(robot, r.trajectory, o.model, o.grid, &r.cond, &r.logdet);
  limit_use(robot, r.trajectory, r.position_use, r.velocity_use, r.acceleration_use);
  return r;
}

ExcitationTrajectory default_excitation(const RobotDescription& robot, double f_f, int harmonics, int candidates,
                                        std::uint64_t seed, double* cond) {
  compiled_robot_for(robot);
  if (!(f_f > 0) || harmonics < 1 || harmonics > mm::kMaxHarmonics || candidates < 1) {
    throw InputError("excitation: f_f must be > 0, harmonics 1..8, candidates >= 1");
  }
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  ExcitationTrajectory best;
  double best_cond = std::numeric_limits<double>::infinity();
  const int grid = 400;  // samples per period for limits and cond(K)
  for (int c = 0; c < candidates; ++c) {
    ExcitationTrajectory t;
    t.f_f = f_f;
    t.harmonics = harmonics;
    for (int j = 0; j < robot.num_joints; ++j) {
      for (int l = 0; l < harmonics; ++l) {
        t.a(j, l) = u(rng) / (l + 1);
        t.b(j, l) = u(rng) / (l + 1);
      }
    }
    // Each joint within 80 % of its tightest limit (position half-range, velocity, acceleration).
    fit_to_limits(robot, t, 0.8, grid);
    double cnd = 0;
    excitation_quality(robot, t, FrictionModel::eq7, grid, &cnd, nullptr);
    if (cnd < best_cond) {
      best_cond = cnd;
      best = t;
    }
  }
  if (cond) *cond = best_cond;
  return best;
}

}  // namespace dyncal::host
