#include "dyncal_host/payload/torque_constants.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/autocorrelation.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// Rank threshold of the nuisance design (columns scaled to unit norm): directions below it carry
/// no information any data could give, not a statistical decision (Kt's std covers the rest).
constexpr double kRankThreshold = 1e-10;
constexpr int kMaxIterations = 50;
/// Gauss-Newton stops when no 1 / Kt moves by more than this fraction of itself.
constexpr double kStepTolerance = 1e-10;

/// One run in the current form: row s N + k is motor k at sample s.
struct CurrentRows {
  StackedData d;
  MatrixXd A;  ///< N^-T [Y, C_free] (the unloaded run's C_free columns are 0)
  VectorXd b;  ///< N^-T C_known pi_known [Nm]: the known load's torque per motor (0 unloaded)
  VectorXd i;  ///< the motor currents, filtered as the regressor [A]
};

CurrentRows current_rows(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options,
                         const KnownLoad* load, Index free_columns) {
  CurrentRows r;
  r.d = prepare_stacked(robot, log, options);
  const StackedData& d = r.d;
  const int N = robot.num_joints;
  const Index S = d.t.size(), P = d.W.cols() + d.E.cols();
  MatrixXd Y(d.W.rows(), P);
  Y << d.W, d.E;
  MatrixXd C = MatrixXd::Zero(Y.rows(), 10);
  if (load) C = d.W.leftCols(d.num_base) * base_map(compiled_robot_for(robot)).rightCols(10);
  Eigen::Matrix<double, 10, 1> known = Eigen::Matrix<double, 10, 1>::Zero();
  if (load) {
    known[9] = load->mass;
    if (load->com_known) known.segment<3>(6) = load->mass * load->com;
  }
  const MatrixXd T = robot.transmission.transpose().inverse();  // N^-T: joint torque to motor torque
  r.A.resize(Y.rows(), P + free_columns);
  r.b.resize(Y.rows());
  r.i.resize(Y.rows());
  for (Index s = 0; s < S; ++s) {
    const Index row = s * N;
    r.A.block(row, 0, N, P) = T * Y.middleRows(row, N);
    r.A.block(row, P, N, free_columns) = T * C.block(row, 0, N, free_columns);
    r.b.segment(row, N) = T * (C.middleRows(row, N) * known);
    r.i.segment(row, N) = T * d.y.segment(row, N);
  }
  return r;
}

/// Both runs' used rows compressed motor by motor: the fit's residual of motor k's rows is
/// w_k (i - s_k (A theta + b)) with w_k and s_k = 1 / Kt_k constant over them, so an orthogonal
/// transform of those rows (the QR of [A i b]) keeps every norm the fit takes: motor k's rows
/// become the p + 2 rows of R_k. The variable projection then works on N (p + 2) rows.
struct CompressedRows {
  MatrixXd A;
  VectorXd i, b;
  std::vector<int> motor;  ///< per compressed row
  VectorXd rows;           ///< per motor: the used rows it stands for
};

CompressedRows compress(const std::vector<const CurrentRows*>& runs, const std::vector<char>& use, int N) {
  const Index p = runs[0]->A.cols();
  CompressedRows out;
  out.rows = VectorXd::Zero(N);
  std::vector<MatrixXd> R(static_cast<size_t>(N));
  for (int m = 0; m < N; ++m) {
    Index n = 0, offset = 0;
    for (const CurrentRows* r : runs) {
      for (Index row = m; row < r->A.rows(); row += N) n += use[static_cast<size_t>(offset + row)];
      offset += r->A.rows();
    }
    MatrixXd M(n, p + 2);
    Index k = 0;
    offset = 0;
    for (const CurrentRows* r : runs) {
      for (Index row = m; row < r->A.rows(); row += N) {
        if (!use[static_cast<size_t>(offset + row)]) continue;
        M.row(k) << r->A.row(row), r->i[row], r->b[row];
        ++k;
      }
      offset += r->A.rows();
    }
    out.rows[m] = static_cast<double>(n);
    const Eigen::HouseholderQR<MatrixXd> qr(M);
    R[static_cast<size_t>(m)] = qr.matrixQR().topRows(std::min(n, p + 2)).triangularView<Eigen::Upper>();
  }
  Index total = 0;
  for (const auto& r : R) total += r.rows();
  out.A.resize(total, p);
  out.i.resize(total);
  out.b.resize(total);
  Index k = 0;
  for (int m = 0; m < N; ++m) {
    const MatrixXd& r = R[static_cast<size_t>(m)];
    out.A.middleRows(k, r.rows()) = r.leftCols(p);
    out.i.segment(k, r.rows()) = r.col(p);
    out.b.segment(k, r.rows()) = r.col(p + 1);
    for (Index q = 0; q < r.rows(); ++q) out.motor.push_back(m);
    k += r.rows();
  }
  return out;
}

/// Column-pivoting QR of X with its columns scaled to unit norm (a zero column kept as it is), rank
/// by kRankThreshold; solve() gives the unscaled least-squares solution.
struct ScaledQr {
  VectorXd norm;
  Eigen::ColPivHouseholderQR<MatrixXd> qr;
  explicit ScaledQr(const MatrixXd& X) : norm(X.colwise().norm().transpose()) {
    for (Index col = 0; col < norm.size(); ++col)
      if (!(norm[col] > 0)) norm[col] = 1;
    qr.compute(X * norm.cwiseInverse().asDiagonal());
    qr.setThreshold(kRankThreshold);
  }
  VectorXd solve(const VectorXd& b) const { return qr.solve(b).cwiseQuotient(norm); }
};

/// The weighted nuisance design for 1 / Kt = s, its QR (columns scaled to unit norm, rank by
/// kRankThreshold), the fitted nuisance parameters and what Gauss-Newton needs.
struct Projection {
  VectorXd theta;  ///< the nuisance parameters (unscaled)
  VectorXd e;      ///< weighted residual of the compressed rows
  MatrixXd Jp;     ///< d(prediction)/d(s), projected off the nuisance columns: (rows - rank) x N
  VectorXd ep;     ///< the residual in the same basis
  int rank = 0;
};

Projection project(const CompressedRows& c, const VectorXd& s, const VectorXd& w, int N) {
  const Index n = c.A.rows(), p = c.A.cols();
  MatrixXd Aw(n, p);
  VectorXd rw(n);
  for (Index k = 0; k < n; ++k) {
    const int m = c.motor[static_cast<size_t>(k)];
    Aw.row(k) = (w[m] * s[m]) * c.A.row(k);
    rw[k] = w[m] * (c.i[k] - s[m] * c.b[k]);
  }
  const ScaledQr sq(Aw);
  Projection out;
  out.rank = static_cast<int>(sq.qr.rank());
  out.theta = sq.solve(rw);
  MatrixXd J = MatrixXd::Zero(n, N + 1);  // the N derivative columns and the residual
  for (Index k = 0; k < n; ++k) {
    const int m = c.motor[static_cast<size_t>(k)];
    J(k, m) = w[m] * (c.A.row(k).dot(out.theta) + c.b[k]);
  }
  out.e = rw - Aw * out.theta;
  J.col(N) = out.e;
  const MatrixXd QtJ = sq.qr.householderQ().adjoint() * J;
  out.Jp = QtJ.bottomRows(n - out.rank).leftCols(N);
  out.ep = QtJ.bottomRows(n - out.rank).col(N);
  return out;
}

/// The unweighted residual i - s (A theta + b) of every row of `r` [A], stacked as the run's rows.
VectorXd current_residual(const CurrentRows& r, const VectorXd& theta, const VectorXd& s, int N) {
  VectorXd e = r.A * theta + r.b;
  for (Index row = 0; row < e.size(); ++row) e[row] = r.i[row] - s[row % N] * e[row];
  return e;
}

std::string number(double v, int precision) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

}  // namespace

bool TorqueConstantFit::all_determined() const {
  for (Verdict v : verdicts)
    if (v == Verdict::not_determined) return false;
  return true;
}

TorqueConstantFit identify_torque_constants(const RobotDescription& robot, const JointLog& unloaded,
                                            const JointLog& loaded, const KnownLoad& load,
                                            const IdentifyOptions& options) {
  if (!(load.mass > 0) || !std::isfinite(load.mass))
    throw InputError("torque constants: the load's mass must be a positive number of kg (--load-mass)");
  if (!load.com.allFinite()) throw InputError("torque constants: the load's centre of mass is not finite (--load-com)");
  const int N = robot.num_joints;
  const Index free_columns = load.com_known ? 6 : 9;  // inertia about the link origin (and first moments)
  const CurrentRows u = current_rows(robot, unloaded, options, nullptr, free_columns);
  const CurrentRows l = current_rows(robot, loaded, options, &load, free_columns);
  const std::vector<const CurrentRows*> runs = {&u, &l};
  TorqueConstantFit fit;
  fit.load = load;
  fit.declared = robot.torque_constants;
  fit.samples_unloaded = static_cast<long>(u.d.t.size());
  fit.samples_loaded = static_cast<long>(l.d.t.size());
  fit.notes = u.d.notes;
  for (const auto& n : l.d.notes) fit.notes.push_back("loaded run: " + n);
  std::vector<char> use;
  for (const CurrentRows* r : runs)
    for (Index row = 0; row < r->A.rows(); ++row)
      use.push_back(r->d.fit_row.empty() ? char(1) : r->d.fit_row[static_cast<size_t>(row)]);

  const CompressedRows c = compress(runs, use, N);
  const Index used = static_cast<Index>(c.rows.sum());

  // The start: the linear torque-form fit Kt_k i_k - A theta = b (unweighted); its noise sits in
  // the regressor (the currents), biasing Kt towards 0 by the noise's share: Gauss-Newton removes it.
  VectorXd s(N);
  {
    const Index p = c.A.cols(), n = c.A.rows();
    MatrixXd X = MatrixXd::Zero(n, N + p);
    for (Index k = 0; k < n; ++k) {
      X(k, c.motor[static_cast<size_t>(k)]) = c.i[k];
      X.row(k).tail(p) = -c.A.row(k);
    }
    const VectorXd x = ScaledQr(X).solve(c.b);
    std::string bad;
    for (int m = 0; m < N; ++m) {
      if (!(x[m] != 0) || !std::isfinite(x[m])) bad += (bad.empty() ? "" : ", ") + std::to_string(m + 1);
      s[m] = 1.0 / x[m];
    }
    if (!bad.empty())
      throw InputError("torque constants: the loaded and unloaded runs give no Kt for motor(s) " + bad +
                       ": the load's torque does not show in their currents (too light a load, or too little "
                       "motion with it)");
  }
  const VectorXd start = s;

  // Variable projection, Gautier's weights from the residual, refitted once with them.
  VectorXd w = VectorXd::Ones(N);
  Projection pr;
  for (int pass = 0; pass < 2; ++pass) {
    bool converged = false;
    for (int it = 0; it < kMaxIterations && !converged; ++it) {
      pr = project(c, s, w, N);
      const VectorXd step = pr.Jp.colPivHouseholderQr().solve(pr.ep);
      s += step;
      ++fit.iterations;
      converged = (step.cwiseQuotient(s).cwiseAbs().maxCoeff() < kStepTolerance);
      if (!s.allFinite() || (s.cwiseProduct(start).array() <= 0).any())
        throw InputError("torque constants: the fit diverged (a Kt went through 0): the pair does not determine them");
    }
    if (!converged)
      throw InputError("torque constants: the fit did not converge in " + std::to_string(kMaxIterations) + " steps");
    pr = project(c, s, w, N);
    // Per motor: the residual's std [A] (Gautier: RSS_k / (n_k - (rank + N) / N)).
    VectorXd rss = VectorXd::Zero(N);
    for (Index k = 0; k < pr.e.size(); ++k) {
      const int m = c.motor[static_cast<size_t>(k)];
      rss[m] += std::pow(pr.e[k] / w[m], 2);
    }
    fit.current_noise = joint_noise_std(rss, c.rows, pr.rank + N);
    w = fit.current_noise.cwiseInverse();
  }
  pr = project(c, s, w, N);
  fit.nuisance_rank = pr.rank;
  const double dof = static_cast<double>(used - pr.rank - N);
  const double sigma2 = pr.ep.squaredNorm() / std::max(1.0, dof);
  for (const CurrentRows* r : runs) {
    const VectorXd e = current_residual(*r, pr.theta, s, N);
    const std::vector<char> all(static_cast<size_t>(r->d.t.size()), 1);
    fit.inflation = std::max(fit.inflation, autocorrelation_inflation(r->d, all, e));
  }
  const MatrixXd cov_s = sigma2 * fit.inflation * (pr.Jp.transpose() * pr.Jp).ldlt().solve(MatrixXd::Identity(N, N));
  fit.kt.resize(N);
  fit.stdev.resize(N);
  constexpr double kNotShown = std::numeric_limits<double>::quiet_NaN();
  for (int m = 0; m < N; ++m) {
    const double kt = 1.0 / s[m], sd = std::sqrt(std::max(0.0, cov_s(m, m))) * kt * kt;
    fit.verdicts.push_back(verdict_of(sd, std::abs(kt)));
    const bool shown = fit.verdicts.back() != Verdict::not_determined;
    fit.kt[m] = shown ? kt : kNotShown;
    fit.stdev[m] = shown ? sd : kNotShown;
  }
  return fit;
}

void print_torque_constants(std::ostream& out, const TorqueConstantFit& fit) {
  out << "Torque constants from a known load (" << number(fit.load.mass, 6) << " kg on the last link, centre of mass "
      << (fit.load.com_known ? "declared" : "fitted") << "): " << fit.samples_unloaded << " unloaded and "
      << fit.samples_loaded << " loaded samples, " << fit.iterations << " Gauss-Newton steps, std x"
      << number(std::sqrt(fit.inflation), 3) << " for autocorrelation\n";
  out << "  motor  Kt [Nm/A]      std        95 % interval           verdict            robot.json\n";
  for (Eigen::Index m = 0; m < fit.kt.size(); ++m) {
    out << "  " << std::setw(5) << m + 1 << "  ";
    if (fit.verdicts[static_cast<size_t>(m)] == Verdict::not_determined) {
      out << std::setw(13) << "-"
          << "  " << std::setw(9) << "-"
          << "  " << std::setw(21) << "-";
    } else {
      const double half = kVerdictZ * fit.stdev[m];
      out << std::setw(13) << number(fit.kt[m], 6) << "  " << std::setw(9) << number(fit.stdev[m], 2) << "  "
          << std::setw(21) << (number(fit.kt[m] - half, 5) + ".." + number(fit.kt[m] + half, 5));
    }
    out << "  " << std::setw(17) << std::left << to_string(fit.verdicts[static_cast<size_t>(m)]) << std::right << "  "
        << (fit.declared.size() > m ? number(fit.declared[m], 6) : std::string("-")) << "\n";
  }
  for (const auto& n : fit.notes) out << "note: " << n << "\n";
}

nlohmann::json torque_constants_json(const TorqueConstantFit& fit) {
  nlohmann::json load = {{"mass", fit.load.mass}};
  if (fit.load.com_known) load["com"] = {fit.load.com.x(), fit.load.com.y(), fit.load.com.z()};
  nlohmann::json motors = nlohmann::json::array();
  for (Eigen::Index m = 0; m < fit.kt.size(); ++m) {
    const bool shown = fit.verdicts[static_cast<size_t>(m)] != Verdict::not_determined;
    nlohmann::json j = {{"motor", m + 1},
                        {"verdict", to_string(fit.verdicts[static_cast<size_t>(m)])},
                        {"current_noise", fit.current_noise[m]}};
    j["kt"] = shown ? nlohmann::json(fit.kt[m]) : nlohmann::json(nullptr);
    j["std"] = shown ? nlohmann::json(fit.stdev[m]) : nlohmann::json(nullptr);
    if (fit.declared.size() > m) j["declared"] = fit.declared[m];
    motors.push_back(j);
  }
  return {{"load", load},
          {"motors", motors},
          {"samples_unloaded", fit.samples_unloaded},
          {"samples_loaded", fit.samples_loaded},
          {"autocorrelation_inflation", fit.inflation},
          {"iterations", fit.iterations},
          {"notes", fit.notes}};
}

}  // namespace dyncal::host
