#include "dyncal_host/identification/methods/instrumental_variables.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/autocorrelation.hpp"
#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/identification/methods/instrumental_iteration.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/torque_metrics.hpp"

namespace dyncal::host {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// The IV estimate of y = K phi on the rows with keep[row] (the others weigh 0): (Z^T K)^-1 Z^T y.
VectorXd iv_solve(const MatrixXd& K, const MatrixXd& Z, const VectorXd& y, const VectorXd& keep) {
  const MatrixXd Zk = Z.array().colwise() * keep.array();
  return (Zk.transpose() * K).colPivHouseholderQr().solve(Zk.transpose() * y);
}

int param_index(const StackedData& d, const std::string& name) {
  const auto it = std::find(d.names.begin(), d.names.end(), name);
  if (it == d.names.end())
    throw InputError("--method iv: no parameter " + name +
                     " (a coupled motor's friction: the closed loop simulates friction per joint, use "
                     "--friction-per-joint)");
  return static_cast<int>(it - d.names.begin());
}

}  // namespace

namespace {

/// Gautier's weights from the OLS residual and the weighted data: w (S N; 0 on rows left out of the
/// fit), K = diag(w) W, y = diag(w) tau and K's triangular factor R (R^T R = K^T K).
struct WeightedData {
  VectorXd w, y;
  MatrixXd K, R;
};

WeightedData weighted_data(const StackedData& d) {
  const int N = static_cast<int>(d.q.cols());
  const Index rows = d.t.size() * N, P = d.W.cols();
  VectorXd fit = VectorXd::Zero(rows);
  for (Index r = 0; r < rows; ++r) fit[r] = d.fit_row.empty() || d.fit_row[static_cast<size_t>(r)] ? 1.0 : 0.0;

  // Gautier's weights from the OLS residual, then the WLS start.
  const MatrixXd Kf = d.W.array().colwise() * fit.array();
  const VectorXd ols = Kf.colPivHouseholderQr().solve(d.y.cwiseProduct(fit));
  const VectorXd r_ols = (d.y - d.W * ols).cwiseProduct(fit);
  VectorXd rss = VectorXd::Zero(N), n = VectorXd::Zero(N);
  for (Index r = 0; r < rows; ++r) rss[r % N] += r_ols[r] * r_ols[r], n[r % N] += fit[r];
  const VectorXd sigma = joint_noise_std(rss, n, P);
  WeightedData out;
  VectorXd& w = out.w;
  w.resize(rows);
  for (Index r = 0; r < rows; ++r) w[r] = fit[r] / sigma[r % N];
  out.K = d.W.array().colwise() * w.array();
  out.y = d.y.cwiseProduct(w);
  // The weighted data's triangular factor R (R^T R = K^T K).
  const Eigen::HouseholderQR<MatrixXd> qr(out.K);
  out.R = qr.matrixQR().topRows(P).triangularView<Eigen::Upper>();
  return out;
}

/// The parameters an IV estimate reports (those the log determines) and the values the others are
/// held at.
struct KeptParameters {
  std::vector<Index> kept;  ///< ascending
  VectorXd held;            ///< P: the undetermined parameters' values (held_at), 0 elsewhere
  KeptParameters(const std::vector<int>& dropped, const VectorXd& held_at, Index P) : held(VectorXd::Zero(P)) {
    for (Index i = 0; i < P; ++i)
      if (std::find(dropped.begin(), dropped.end(), static_cast<int>(i)) == dropped.end()) kept.push_back(i);
    for (const int i : dropped) held[i] = held_at[i];
  }
  /// A's kept columns.
  MatrixXd columns(const MatrixXd& A) const {
    MatrixXd B(A.rows(), static_cast<Index>(kept.size()));
    for (size_t k = 0; k < kept.size(); ++k) B.col(static_cast<Index>(k)) = A.col(kept[k]);
    return B;
  }
  /// The full parameter vector (P) of the kept parameters' values x.
  VectorXd full(const VectorXd& x) const {
    VectorXd v = held;
    for (size_t k = 0; k < kept.size(); ++k) v[kept[k]] = x[static_cast<Index>(k)];
    return v;
  }
};

/// The torque each fold's IV estimate (from the other folds' rows) predicts on its own samples; NaN on
/// the rows --min-speed leaves out of the fit.
VectorXd fold_predictions(const StackedData& d, const MatrixXd& Kk, const MatrixXd& Z, const VectorXd& y_held,
                          const std::vector<int>& fold, int folds, const KeptParameters& kp) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size(), rows = S * N;
  VectorXd pred = VectorXd::Constant(rows, std::nan(""));
  for (int f = 0; f < folds; ++f) {
    VectorXd train(rows);
    for (Index r = 0; r < rows; ++r) train[r] = fold[static_cast<size_t>(r / N)] != f ? 1.0 : 0.0;
    const VectorXd phi_f = kp.full(iv_solve(Kk, Z, y_held, train));
    for (Index s = 0; s < S; ++s)
      if (fold[static_cast<size_t>(s)] == f) pred.segment(s * N, N) = d.W.middleRows(s * N, N) * phi_f;
  }
  for (Index r = 0; r < pred.size(); ++r)
    if (!d.fit_row.empty() && !d.fit_row[static_cast<size_t>(r)]) pred[r] = std::nan("");
  return pred;
}

/// res.params with the IV covariance's std, inflated by the residual's autocorrelation, and the
/// iteration's notes.
void report_instrumental(const StackedData& d, const MatrixXd& K, const MatrixXd& Kk, const MatrixXd& Z,
                         const VectorXd& y, const VectorXd& phi, const KeptParameters& kp, const IvIteration& it,
                         IdentifyResult& res) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size(), rows = S * N, P = d.W.cols(), Pk = static_cast<Index>(kp.kept.size());
  const VectorXd residual = y - K * phi;
  const double s2 = residual.squaredNorm() / (static_cast<double>(rows) - static_cast<double>(Pk));
  const MatrixXd ZK_inv = (Z.transpose() * Kk).inverse();
  const MatrixXd C = s2 * ZK_inv * (Z.transpose() * Z) * ZK_inv.transpose();
  const std::vector<char> all(static_cast<size_t>(S), 1);
  const double inflation = autocorrelation_inflation(d, all, d.y - d.W * phi);
  VectorXd stdev = VectorXd::Constant(P, std::nan(""));
  for (Index k = 0; k < Pk; ++k) stdev[kp.kept[static_cast<size_t>(k)]] = std::sqrt(std::max(0.0, C(k, k)) * inflation);
  for (Index i = 0; i < P; ++i) res.params.push_back({d.names[static_cast<size_t>(i)], phi[i], stdev[i]});
  char line[240];
  std::snprintf(line, sizeof line,
                "IDIM-IV: %s after %d closed-loop simulations of the law, last step %.2g standard errors (converged "
                "at %.2g); instruments from the plant of the last iterate",
                it.converged ? "converged" : "not converged", it.simulations, it.last_step_se, kIvTolerance);
  res.notes.push_back(line);
  if (it.tripped > 0)
    res.notes.push_back(
        "IDIM-IV: " + std::to_string(it.tripped) +
        " plant(s) tripped the simulated drive and were replaced by one half way back (last: " + it.trip + ")");
  std::snprintf(line, sizeof line,
                "parameter std: the IV covariance times %.3g for the residual's autocorrelation (S / n_eff)",
                std::sqrt(inflation));
  res.notes.push_back(line);
}

}  // namespace

void fit_instrumental(const StackedData& d, const JointLog& grid, const std::vector<int>& fold, int folds,
                      const RobotDescription& robot, const IdentifyOptions& o, const PrepareLog& prepare,
                      const std::vector<int>& dropped, const VectorXd& held_at, IdentifyResult& res) {
  if (!o.closed_loop)
    throw InputError("--method iv needs --law FILE: the drive's control law the run was recorded under");
  const auto t0 = std::chrono::steady_clock::now();
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size(), rows = S * N, P = d.W.cols();
  if (d.W.rows() != rows) throw InputError("internal: --method iv needs the dense regressor");
  std::vector<int> fc(static_cast<size_t>(N)), fv(static_cast<size_t>(N));
  for (int j = 0; j < N; ++j) {
    fc[static_cast<size_t>(j)] = param_index(d, "Fc" + std::to_string(j + 1));
    fv[static_cast<size_t>(j)] = param_index(d, "Fv" + std::to_string(j + 1));
  }
  const WeightedData wd = weighted_data(d);
  const VectorXd& w = wd.w;
  const MatrixXd& K = wd.K;
  const VectorXd& y = wd.y;
  const MatrixXd& R = wd.R;
  res.condition_number = [&] {
    const VectorXd sv = Eigen::JacobiSVD<MatrixXd>(R).singularValues();
    return sv[0] / sv[sv.size() - 1];
  }();
  // The iteration runs on the whole model (its plants need every parameter: one held at 0 would
  // pull the plant away from what the data say at the white-noise level); the reported IV estimate
  // holds the parameters the log does not determine at held_at (the prior's mean), with the final
  // instruments.
  const KeptParameters kp(dropped, held_at, P);
  const MatrixXd Kk = kp.columns(K);

  // Each iterate's plant: consistent inertials nearest it in the data's metric, the prior deciding
  // what the data do not see; friction at least 0.
  const CompiledRobot& compiled = compiled_robot_for(robot);
  ConsistentProblem plant_problem;
  plant_problem.R = R;
  plant_problem.num_base = d.num_base;
  plant_problem.K = base_map(compiled);
  plant_problem.prior = Eigen::Map<const VectorXd>(compiled.nominal_standard.data(), compiled.num_standard);
  plant_problem.prior_relative_std = o.prior_std > 0 ? o.prior_std : kPriorRelativeStd;
  const VectorXd nominal = plant_problem.prior;
  // Each plant simulated under the law and prepared as the log was: the instruments, weighted as K.
  const InstrumentsOf instruments = [&](const VectorXd& phi, bool first) -> MatrixXd {
    VectorXd standard = nominal, model = phi;
    if (!first) {
      plant_problem.z = R * phi;
      plant_problem.start = phi;
      const ConsistentSolution plant = consistent_least_squares(plant_problem);
      standard = plant.standard;
      model = plant.params;
    }
    VectorXd Fc(N), Fv(N);
    for (int j = 0; j < N; ++j) {
      Fc[j] = std::max(0.0, model[fc[static_cast<size_t>(j)]]);
      Fv[j] = std::max(0.0, model[fv[static_cast<size_t>(j)]]);
    }
    StackedData sim;
    try {
      sim = prepare(o.closed_loop(grid, standard, Fc, Fv));
    } catch (const InputError& e) {
      if (first) throw InputError(std::string("--method iv: the first closed-loop simulation failed: ") + e.what());
      throw;
    }
    if (sim.W.rows() != rows || sim.W.cols() != P || !sim.t.isApprox(d.t))
      throw InputError("--method iv: the closed-loop simulation's samples are not the log's");
    return sim.W.array().colwise() * w.array();
  };
  IvIterationOptions iteration;
  iteration.max_simulations = kIvMaxSimulations;
  iteration.tolerance = kIvTolerance;
  iteration.retry_tripped = true;
  const IvIteration it = iterate_instruments(K, y, K.colPivHouseholderQr().solve(y), instruments, iteration);
  // The IV estimate of the last instruments (the iterate may be a half step), of the parameters the
  // log determines.
  const MatrixXd Z = kp.columns(it.Z);
  const VectorXd y_held = y - K * kp.held;  // the held parameters' torque moved to the left-hand side
  const VectorXd phi = kp.full(iv_solve(Kk, Z, y_held, VectorXd::Ones(rows)));
  if (!phi.allFinite()) throw InputError("--method iv: the instrumental estimate is not finite");
  res.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // Cross-validation with the final instruments: each fold's IV estimate from the others' rows.
  res.joints = torque_metrics(d.y, fold_predictions(d, Kk, Z, y_held, fold, folds, kp), N, robot.tau_max);

  // Standard deviations: the IV covariance, inflated by the residual's autocorrelation.
  report_instrumental(d, K, Kk, Z, y, phi, kp, it, res);
}

}  // namespace dyncal::host
