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

using Vec = Eigen::Matrix<double, modbus_map::kMaxJoints, 1>;  // rows past the robot's joints unused
namespace mm = dyncal::modbus_map;

/// Extremes of q, qd, qdd over one period on `grid` points.
void extremes(const ExcitationTrajectory& t, int grid, Vec& qmin, Vec& qmax, Vec& vmax, Vec& amax) {
  qmin.setConstant(std::numeric_limits<double>::infinity());
  qmax = -qmin;
  vmax.setZero();
  amax.setZero();
  for (int k = 0; k < grid; ++k) {
    Vec q, qd, qdd;
    t.evaluate(t.period() * k / grid, q, qd, qdd);
    qmin = qmin.cwiseMin(q);
    qmax = qmax.cwiseMax(q);
    vmax = vmax.cwiseMax(qd.cwiseAbs());
    amax = amax.cwiseMax(qdd.cwiseAbs());
  }
}

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
  extremes(t, grid, qmin, qmax, vmax, amax);
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

void limit_use(const RobotDescription& robot, const ExcitationTrajectory& t, JointFractions& position,
               JointFractions& velocity, JointFractions& acceleration) {
  Vec qmin, qmax, vmax, amax;
  extremes(t, 2000, qmin, qmax, vmax, amax);
  position.fill(0);
  velocity.fill(0);
  acceleration.fill(0);
  for (int j = 0; j < robot.num_joints; ++j) {
    const double centre = 0.5 * (robot.q_max[j] + robot.q_min[j]), half = 0.5 * (robot.q_max[j] - robot.q_min[j]);
    position[j] = std::max(std::fabs(qmax[j] - centre), std::fabs(qmin[j] - centre)) / half;
    velocity[j] = vmax[j] / robot.qd_max[j];
    acceleration[j] = amax[j] / robot.qdd_max[j];
  }
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

nlohmann::json trajectory_to_json(const RobotDescription& robot, const ExcitationTrajectory& t) {
  nlohmann::json j;
  j["robot"] = robot.name;
  j["f_f"] = t.f_f;
  j["harmonics"] = t.harmonics;
  for (int i = 0; i < robot.num_joints; ++i) {
    j["q0"].push_back(t.q0[i]);
    nlohmann::json a = nlohmann::json::array(), b = nlohmann::json::array();
    for (int l = 0; l < t.harmonics; ++l) {
      a.push_back(t.a(i, l));
      b.push_back(t.b(i, l));
    }
    j["a"].push_back(a);
    j["b"].push_back(b);
  }
  return j;
}

ExcitationTrajectory trajectory_from_json(const RobotDescription& robot, const nlohmann::json& j) {
  auto need = [&](const char* key) -> const nlohmann::json& {
    if (!j.is_object() || !j.contains(key)) throw InputError(std::string("trajectory file: missing '") + key + "'");
    return j[key];
  };
  auto number = [](const nlohmann::json& v, const std::string& what) {
    if (!v.is_number() || !std::isfinite(v.get<double>()))
      throw InputError("trajectory file: " + what + " is not a number");
    return v.get<double>();
  };
  if (need("robot").get<std::string>() != robot.name) {
    throw InputError("trajectory file is for robot '" + j["robot"].get<std::string>() + "', not '" + robot.name + "'");
  }
  ExcitationTrajectory t;
  t.f_f = number(need("f_f"), "f_f");
  if (!need("harmonics").is_number_integer()) throw InputError("trajectory file: harmonics is not an integer");
  t.harmonics = j["harmonics"].get<int>();
  if (!(t.f_f > 0) || t.harmonics < 1 || t.harmonics > mm::kMaxHarmonics) {
    throw InputError("trajectory file: f_f must be > 0 and harmonics 1..8");
  }
  const auto& q0 = need("q0");
  const auto& a = need("a");
  const auto& b = need("b");
  const size_t n = static_cast<size_t>(robot.num_joints);
  if (!q0.is_array() || q0.size() != n || !a.is_array() || a.size() != n || !b.is_array() || b.size() != n) {
    throw InputError("trajectory file: q0, a and b need one entry per joint (" + std::to_string(n) + ")");
  }
  for (size_t i = 0; i < n; ++i) {
    const std::string joint = " of joint " + std::to_string(i + 1);
    t.q0[static_cast<Eigen::Index>(i)] = number(q0[i], "q0" + joint);
    if (!a[i].is_array() || a[i].size() != static_cast<size_t>(t.harmonics) || !b[i].is_array() ||
        b[i].size() != static_cast<size_t>(t.harmonics)) {
      throw InputError("trajectory file: a and b" + joint + " need " + std::to_string(t.harmonics) + " coefficients");
    }
    for (int l = 0; l < t.harmonics; ++l) {
      t.a(static_cast<Eigen::Index>(i), l) = number(a[i][static_cast<size_t>(l)], "a" + joint);
      t.b(static_cast<Eigen::Index>(i), l) = number(b[i][static_cast<size_t>(l)], "b" + joint);
    }
  }
  JointFractions pos{}, vel{}, acc{};
  limit_use(robot, t, pos, vel, acc);
  for (int i = 0; i < robot.num_joints; ++i) {
    for (const auto& [use, what] : {std::pair{pos[i], "position range"}, std::pair{vel[i], "velocity limit"},
                                    std::pair{acc[i], "acceleration limit"}}) {
      if (use > 1.0) {
        throw InputError("trajectory file: joint " + std::to_string(i + 1) + " exceeds its " + what + " (" +
                         std::to_string(static_cast<int>(std::lround(100 * use))) + " % of it)");
      }
    }
  }
  return t;
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
