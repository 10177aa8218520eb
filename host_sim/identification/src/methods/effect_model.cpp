#include "dyncal_host/identification/methods/effect_model.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "dyncal/effect_terms.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/identification/pipeline/compiled_robot.hpp"
#include "dyncal_host/identification/reports/prediction.hpp"

namespace dyncal::host {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

bool has_load_friction(const std::vector<ModelEffect>& effects) {
  for (const ModelEffect& e : effects)
    if (e.kind == EffectKind::load_friction) return true;
  return false;
}

/// Per validation group g (0: rows only ever trained on, f + 1: fold f) and joint j, the Gram
/// matrix, moment and sums of the fitted rows of the column-scaled design.
struct Grams {
  VectorXd scale;  ///< column scaling (1 / column norm)
  std::vector<std::vector<MatrixXd>> G;
  std::vector<std::vector<VectorXd>> g;
  std::vector<VectorXd> yy, n;
};

Grams accumulate(const MatrixXd& X, const StackedData& d, const std::vector<int>& fold, int folds) {
  const int N = static_cast<int>(d.q.cols());
  const Index p = X.cols(), S = d.t.size();
  Grams a;
  a.scale = X.colwise().norm().transpose();
  for (Index i = 0; i < p; ++i) a.scale[i] = a.scale[i] > 0 ? 1.0 / a.scale[i] : 1.0;
  const int groups = folds + 1;
  a.G.assign(groups, std::vector<MatrixXd>(N, MatrixXd::Zero(p, p)));
  a.g.assign(groups, std::vector<VectorXd>(N, VectorXd::Zero(p)));
  a.yy.assign(groups, VectorXd::Zero(N));
  a.n.assign(groups, VectorXd::Zero(N));
  for (Index s = 0; s < S; ++s) {
    const int grp = fold[static_cast<size_t>(s)] + 1;
    for (int j = 0; j < N; ++j) {
      const Index r = s * N + j;
      if (!d.fit_row[r]) continue;
      const VectorXd x = X.row(r).transpose().cwiseProduct(a.scale);
      a.G[grp][j].selfadjointView<Eigen::Lower>().rankUpdate(x);
      a.g[grp][j] += d.y[r] * x;
      a.yy[grp][j] += d.y[r] * d.y[r];
      a.n[grp][j] += 1;
    }
  }
  for (auto& v : a.G)
    for (auto& G : v) G = MatrixXd(G.selfadjointView<Eigen::Lower>());
  return a;
}

/// One least-squares fit on every group but `exclude` (-1: all): phi (unscaled), the per-joint
/// training RSS [Nm^2], the weighted Gram's inverse diagonal (for std) and the residual variance.
struct Fit {
  VectorXd phi, inv_diag;
  MatrixXd G;         ///< the weighted Gram of the column-scaled design (Grams::scale)
  VectorXd g;         ///< its moment
  VectorXd rss;       ///< per joint, unweighted
  double sigma2 = 1;  ///< weighted residual variance (1 for WLS up to the fit's own scale)
  double cond = 0;
};

Fit solve(const Grams& a, int exclude, const std::string& method) {
  const int N = static_cast<int>(a.yy[0].size());
  const Index p = a.scale.size();
  auto fit_with = [&](const VectorXd& w2, Fit& f) {
    MatrixXd G = MatrixXd::Zero(p, p);
    VectorXd g = VectorXd::Zero(p);
    double rows = 0;
    for (size_t grp = 0; grp < a.G.size(); ++grp) {
      if (static_cast<int>(grp) == exclude) continue;
      for (int j = 0; j < N; ++j) {
        G += w2[j] * a.G[grp][j];
        g += w2[j] * a.g[grp][j];
        rows += a.n[grp][j];
      }
    }
    // Rank: the scaled Gram's eigenvalues (its condition is cond([W E])^2).
    Eigen::SelfAdjointEigenSolver<MatrixXd> eig(G);
    const VectorXd ev = eig.eigenvalues();
    if (!(ev[0] > 1e-13 * ev[p - 1]))
      throw InputError(
          "the data do not excite every parameter of the model with its effect terms (regressor rank deficient): "
          "an effect collinear with the model, or too little excitation");
    // cond of the unscaled (weighted) design, as the compiled pipeline reports it.
    const VectorXd unscale = a.scale.cwiseInverse();
    const VectorXd ev_u =
        Eigen::SelfAdjointEigenSolver<MatrixXd>(unscale.asDiagonal() * G * unscale.asDiagonal(), Eigen::EigenvaluesOnly)
            .eigenvalues();
    f.cond = std::sqrt(ev_u[p - 1] / std::max(1e-300, ev_u[0]));
    const VectorXd beta = eig.eigenvectors() * (eig.eigenvectors().transpose() * g).cwiseQuotient(ev);
    f.rss = VectorXd::Zero(N);
    double wrss = 0;
    for (size_t grp = 0; grp < a.G.size(); ++grp) {
      if (static_cast<int>(grp) == exclude) continue;
      for (int j = 0; j < N; ++j) {
        const double r = std::max(0.0, a.yy[grp][j] - 2.0 * beta.dot(a.g[grp][j]) + beta.dot(a.G[grp][j] * beta));
        f.rss[j] += r;
        wrss += w2[j] * r;
      }
    }
    f.sigma2 = wrss / std::max(1.0, rows - static_cast<double>(p));
    f.inv_diag = (eig.eigenvectors() * ev.cwiseInverse().asDiagonal() * eig.eigenvectors().transpose())
                     .diagonal()
                     .cwiseProduct(a.scale.cwiseAbs2());
    f.phi = beta.cwiseProduct(a.scale);
    f.G = std::move(G);
    f.g = std::move(g);
  };
  Fit ols;
  fit_with(VectorXd::Ones(N), ols);
  if (method == "ols") return ols;
  // Gautier's weights from the OLS residual of the same rows (stacked_data.hpp: joint_noise_std).
  VectorXd n = VectorXd::Zero(N);
  for (size_t grp = 0; grp < a.n.size(); ++grp)
    if (static_cast<int>(grp) != exclude) n += a.n[grp];
  Fit wls;
  fit_with(joint_noise_std(ols.rss, n, p).cwiseAbs2().cwiseInverse(), wls);
  return wls;
}

/// pcls, gd, ga, pf on [W E]: the WLS fit `f` of the rows outside group `exclude` made physically
/// consistent (consistent_least_squares.hpp) on its weighted data: R from the Cholesky factor of the
/// scaled Gram (R_s D^-1, D the column scaling), z = R_s^-T g; K from the compiled robot's
/// standard_to_base; robot.json's inertials as prior (pcls) or search centre (gd, ga, pf). f's
/// parameters replaced; its inv_diag from pcls's Gauss-Newton std, the search keeps WLS's (the model
/// is linear), as the compiled pipeline.
ConsistentSolution make_consistent(const StackedData& d, const MatrixXd& X, const std::vector<int>& fold, int exclude,
                                   const Grams& a, const RobotDescription& robot, const IdentifyOptions& o, Fit& f) {
  const Eigen::LLT<MatrixXd> llt(f.G);
  if (llt.info() != Eigen::Success)
    throw InputError("--method " + o.method + ": the weighted design with its effect terms is not positive definite");
  const CompiledRobot& compiled = compiled_robot_for(robot);
  if (compiled.num_base != d.num_base) throw InputError("internal: the data's base parameters are not the robot's");
  ConsistentProblem p;
  p.R = MatrixXd(llt.matrixU()) * a.scale.cwiseInverse().asDiagonal();  // beta = D^-1 p
  p.z = llt.matrixL().solve(f.g);
  p.num_base = d.num_base;
  p.K = base_map(compiled);
  p.prior = Eigen::Map<const VectorXd>(compiled.nominal_standard.data(), compiled.num_standard);
  p.prior_relative_std = o.prior_std;
  p.start = f.phi;
  p.nonnegative = nonnegative_terms(d.names, d.num_base);
  p.sigma2 = f.sigma2;
  ConsistentSolution s;
  if (o.method == "pcls") {
    s = consistent_least_squares(p);
    f.inv_diag = s.params_std.cwiseAbs2() / f.sigma2;
  } else {
    // The particle filter's likelihood takes the residual's autocorrelation into account (S / n_eff).
    std::vector<char> train(static_cast<size_t>(d.t.size()));
    for (size_t s_ = 0; s_ < train.size(); ++s_) train[s_] = fold[s_] + 1 != exclude;
    p.sigma2 *= autocorrelation_inflation(d, train, d.y - X * f.phi);
    s = search_consistent(p, search_method(o.method), search_settings(o));
  }
  f.phi = s.params;
  return s;
}

/// The fit of the rows outside group `exclude`: load friction's rigid-body torque from a first fit
/// without the load terms on the same rows; made consistent for pcls, gd, ga, pf (into *consistent
/// if given). Returns the fit and its design.
Fit fit_rows(const StackedData& d, const std::vector<ModelEffect>& effects, const std::vector<int>& fold, int folds,
             int exclude, const RobotDescription& robot, const IdentifyOptions& o, MatrixXd& X,
             ConsistentSolution* consistent = nullptr) {
  const std::string method = o.method == "ols" ? "ols" : "wls";  // the consistent methods start from WLS
  VectorXd tau_rb = VectorXd::Zero(d.y.size());
  if (has_load_friction(effects)) {
    // The design without the load terms' columns.
    const MatrixXd E_all = effect_design(d, effects, tau_rb);
    std::vector<Index> keep;
    Index col = 0;
    for (const ModelEffect& e : effects) {
      const Index width = static_cast<Index>(effect_param_names(e).size());
      if (e.kind != EffectKind::load_friction)
        for (Index c = 0; c < width; ++c) keep.push_back(col + c);
      col += width;
    }
    MatrixXd X0(d.W.rows(), d.W.cols() + static_cast<Index>(keep.size()));
    X0.leftCols(d.W.cols()) = d.W;
    for (size_t c = 0; c < keep.size(); ++c) X0.col(d.W.cols() + static_cast<Index>(c)) = E_all.col(keep[c]);
    const Fit first = solve(accumulate(X0, d, fold, folds), exclude, method);
    tau_rb = rigid_body_torque(d, first.phi);
  }
  const MatrixXd E = effect_design(d, effects, tau_rb);
  X.resize(d.W.rows(), d.W.cols() + E.cols());
  X << d.W, E;
  const Grams a = accumulate(X, d, fold, folds);
  Fit f = solve(a, exclude, method);
  if (is_consistent_method(o.method)) {
    ConsistentSolution s = make_consistent(d, X, fold, exclude, a, robot, o, f);
    if (consistent) *consistent = std::move(s);
  }
  return f;
}

}  // namespace

Index effect_column_count(const std::vector<ModelEffect>& effects) {
  Index m = 0;
  for (const ModelEffect& e : effects) m += static_cast<Index>(effect_param_names(e).size());
  return m;
}

bool effect_column_steps(EffectKind kind, int column) {
  switch (kind) {
    case EffectKind::stribeck:
    case EffectKind::velocity_power:
    case EffectKind::load_friction:
      return true;
    case EffectKind::asymmetric_friction:
    case EffectKind::coupling:
      return column == 0;  // [qd > 0], sgn(v); qd [qd > 0], v and a are continuous
    default:
      return false;
  }
}

std::vector<bool> effect_columns_with_sign(const std::vector<ModelEffect>& effects) {
  std::vector<bool> out;
  for (const ModelEffect& e : effects) {
    const int width = static_cast<int>(effect_param_names(e).size());
    for (int c = 0; c < width; ++c) out.push_back(effect_column_steps(e.kind, c));
  }
  return out;
}

MatrixXd effect_columns_over_time(const std::vector<ModelEffect>& effects, const MatrixXd& q, const MatrixXd& qd,
                                  const MatrixXd& qdd, const MatrixXd& v_raw, const VectorXd& band) {
  const Index S = q.rows(), N = q.cols(), m = effect_column_count(effects);
  MatrixXd out = MatrixXd::Zero(S, N * m);
  const auto velocity = signed_velocity;
  double c[3];
  Index col = 0;
  for (const ModelEffect& e : effects) {
    const Index width = static_cast<Index>(effect_param_names(e).size());
    if (e.kind != EffectKind::load_friction) {
      const int i = e.joint, k = e.kind == EffectKind::coupling ? e.joint2 : e.joint;
      // A coupling's signed ratio r (lib/ effect_terms.hpp); 1 for the per-joint kinds.
      const double sign = e.kind == EffectKind::coupling ? e.sign * (e.shape > 0 ? e.shape : 1.0) : 1.0;
      for (Index s = 0; s < S; ++s) {
        double v, a;
        if (e.kind == EffectKind::coupling) {
          v = velocity(qd(s, i) + sign * qd(s, k), v_raw(s, i) + sign * v_raw(s, k),
                       std::hypot(band[i], sign * band[k]));
          a = qdd(s, i) + sign * qdd(s, k);
        } else {
          v = velocity(qd(s, i), v_raw(s, i), band[i]);
          a = qdd(s, i);
        }
        // The motor's v and a passed whole (second joint 0): effect_columns adds sign qd2.
        const int w = effect_columns(e.kind, e.shape, sign, q(s, i), v, a, 0.0, 0.0, 0.0, c);
        for (int x = 0; x < w; ++x) {
          out(s, i * m + col + x) = c[x];
          if (e.kind == EffectKind::coupling) out(s, k * m + col + x) = sign * c[x];
        }
      }
    }
    col += width;
  }
  return out;
}

MatrixXd effect_design(const StackedData& d, const std::vector<ModelEffect>& effects, const VectorXd& tau_rb) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  if (d.E.cols() != effect_column_count(effects) || d.E.rows() != S * N)
    throw InputError("internal: the data were not prepared with these effect terms");
  MatrixXd E = d.E;
  Index col = 0;
  for (const ModelEffect& e : effects) {
    if (e.kind == EffectKind::load_friction) {
      const int i = e.joint;
      for (Index s = 0; s < S; ++s) {
        const double v = d.qd(s, i);
        E(s * N + i, col) = std::abs(tau_rb[s * N + i]) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0));
      }
    }
    col += static_cast<Index>(effect_param_names(e).size());
  }
  return E;
}

VectorXd rigid_body_torque(const StackedData& d, const VectorXd& phi) {
  return d.W.leftCols(d.num_base) * phi.head(d.num_base);
}

MatrixXd model_design(const StackedData& d, const std::vector<ModelEffect>& effects, const VectorXd& phi) {
  const MatrixXd E = effect_design(d, effects, rigid_body_torque(d, phi));
  MatrixXd X(d.W.rows(), d.W.cols() + E.cols());
  X << d.W, E;
  return X;
}

void fit_effect_model(const StackedData& d, const std::vector<ModelEffect>& effects, const std::vector<int>& fold,
                      int folds, const RobotDescription& robot, const IdentifyOptions& options, IdentifyResult& res) {
  const std::string& method = options.method;
  if (method != "ols" && method != "wls" && !is_consistent_method(method))
    throw InputError("--method " + method + ": a model with effect terms is fitted by wls, ols, pcls, gd, ga or pf");
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  VectorXd pred = VectorXd::Constant(S * N, std::nan(""));
  MatrixXd X;
  for (int f = 0; f < folds; ++f) {
    const Fit fit = fit_rows(d, effects, fold, folds, f + 1, robot, options, X);
    for (Index s = 0; s < S; ++s)
      if (fold[static_cast<size_t>(s)] == f) pred.segment(s * N, N) = X.middleRows(s * N, N) * fit.phi;
  }
  // Rows --min-speed leaves out of the fit are left out of the scores too.
  for (Index r = 0; r < pred.size(); ++r)
    if (!d.fit_row.empty() && !d.fit_row[static_cast<size_t>(r)]) pred[r] = std::nan("");
  res.joints = torque_metrics(d.y, pred, N, robot.tau_max);
  const auto t0 = std::chrono::steady_clock::now();
  ConsistentSolution consistent;
  const Fit fit = fit_rows(d, effects, fold, folds, -1, robot, options, X, &consistent);
  res.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  res.condition_number = fit.cond;
  // White-noise standard deviations inflated by the residual's autocorrelation (stacked_data.hpp).
  const std::vector<char> all(static_cast<size_t>(S), 1);
  const double inflation = autocorrelation_inflation(d, all, d.y - X * fit.phi);
  std::vector<std::string> names = d.names;
  for (const ModelEffect& e : effects)
    for (const std::string& n : effect_param_names(e)) names.push_back(n);
  res.params.clear();
  for (Index i = 0; i < fit.phi.size(); ++i)
    res.params.push_back({names[static_cast<size_t>(i)], fit.phi[i],
                          std::sqrt(std::max(0.0, fit.sigma2 * fit.inv_diag[i]) * inflation)});
  char line[200];
  std::snprintf(line, sizeof line,
                "parameter std: the white-noise figures times %.3g for the residual's autocorrelation (S / n_eff)",
                std::sqrt(inflation));
  res.notes.push_back(line);
  if (has_load_friction(effects))
    res.notes.push_back(
        "load friction: its rigid-body torque from a first fit without the load terms on the same rows (the "
        "transmitted torque, as a drive's feed-forward computes it)");
  report_consistent(consistent, options, res);
}

}  // namespace dyncal::host
