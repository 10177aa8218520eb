#include "dyncal_host/diagnose.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iomanip>
#include <optional>
#include <sstream>

#include "dyncal/friction.hpp"
#include "dyncal_host/input_error.hpp"
#include "dyncal_host/signal.hpp"
#include "dyncal_host/stacked_data.hpp"

namespace dyncal::host {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// RSS reduction of the least-squares fit of a sin(k q_j) + b cos(k q_j) to residual(s) over the
/// samples of `q` (S x N); nullopt when sin and cos are collinear on the data.
template <class Residual>
std::optional<double> harmonic_rss_reduction(const MatrixXd& q, int j, int k, Residual residual) {
  double ss = 0, cc = 0, sc = 0, sr = 0, cr = 0;
  for (Index s = 0; s < q.rows(); ++s) {
    const double a = std::sin(k * q(s, j)), b = std::cos(k * q(s, j)), r = residual(s);
    ss += a * a;
    cc += b * b;
    sc += a * b;
    sr += a * r;
    cr += b * r;
  }
  const double det = ss * cc - sc * sc;
  if (det <= 1e-12 * ss * cc) return std::nullopt;
  return (cc * sr * sr - 2 * sc * sr * cr + ss * cr * cr) / det;
}

/// A candidate effect: extra columns over the stacked rows (row s * N + j).
struct Candidate {
  std::string kind;
  std::vector<int> joints;  // 0-based
  std::vector<std::string> names;
  MatrixXd columns;    // (S N) x m
  std::string detail;  // e.g. "36 cycles per revolution"
  int searched = 1;    // alternatives the search chose among (frequencies, velocity scales, signs)
  double shape = 0;    // velocity scale (stribeck) or cycles per revolution (position_periodic)
  double sign = 1;     // coupling: q_i + sign q_j
};

/// Blocked cross-validation from per-fold, per-joint Gram matrices of the design [X C] and y. The
/// base design X is fixed for a greedy step (set_base), so each candidate C only costs its cross
/// products with X over the rows where C is not zero.
class CrossValidator {
 public:
  CrossValidator(const StackedData& d, int N, const std::vector<int>& fold, int folds)
      : d_(d), N_(N), fold_(fold), folds_(folds) {}

  void set_base(const MatrixXd& X) {
    X_ = &X;
    const Index p = X.cols(), S = d_.t.size();
    sx_ = X.colwise().norm().transpose();
    for (Index i = 0; i < p; ++i) sx_[i] = sx_[i] > 0 ? 1.0 / sx_[i] : 1.0;
    Gxx_fit_.assign(folds_, MatrixXd::Zero(p, p));
    gx_fit_.assign(folds_, VectorXd::Zero(p));
    Gxx_all_.assign(folds_, std::vector<MatrixXd>(N_, MatrixXd::Zero(p, p)));
    gx_all_.assign(folds_, std::vector<VectorXd>(N_, VectorXd::Zero(p)));
    yy_.assign(folds_, VectorXd::Zero(N_));
    for (Index s = 0; s < S; ++s) {
      const int f = fold_[s];
      for (int j = 0; j < N_; ++j) {
        const Index r = s * N_ + j;
        const VectorXd x = X.row(r).transpose().cwiseProduct(sx_);
        const double y = d_.y[r];
        if (!d_.fit_row[r]) continue;  // rows left out of the fit (stiction band) are not judged either
        Gxx_all_[f][j].selfadjointView<Eigen::Lower>().rankUpdate(x);
        gx_all_[f][j] += x * y;
        yy_[f][j] += y * y;
        Gxx_fit_[f].selfadjointView<Eigen::Lower>().rankUpdate(x);
        gx_fit_[f] += x * y;
      }
    }
    for (auto& G : Gxx_fit_) G = MatrixXd(G.selfadjointView<Eigen::Lower>());
    for (auto& v : Gxx_all_)
      for (auto& G : v) G = MatrixXd(G.selfadjointView<Eigen::Lower>());
  }

  /// Validation and training RSS per joint of [X C] (C may have no columns); phi_out: the
  /// coefficients of the fit on all rows, X's first.
  /// Out-of-fold predictions of the base design alone (each block predicted by the fit without its
  /// fold), for the per-sample indices e_T and e_T_Std.
  VectorXd predict_out_of_fold() const {
    const MatrixXd& X = *X_;
    const Index S = d_.t.size();
    std::vector<VectorXd> beta;
    fold_fits(Gxx_fit_, gx_fit_, beta);
    for (auto& b : beta) b = b.cwiseProduct(sx_);
    VectorXd pred(S * N_);
    for (Index s = 0; s < S; ++s)
      for (int j = 0; j < N_; ++j) pred[s * N_ + j] = X.row(s * N_ + j).dot(beta[fold_[s]]);
    return pred;
  }

  /// *novelty: the smallest fraction of a (unit-scaled) candidate column not explained by X (1 if C
  /// is empty); near 0 means the candidate is collinear with the model and not identifiable.
  void evaluate(const MatrixXd& C, VectorXd& val_rss, VectorXd& train_rss, VectorXd* phi_out = nullptr,
                double* novelty = nullptr) const {
    const MatrixXd& X = *X_;
    const Index p = X.cols(), m = C.cols(), q = p + m, S = d_.t.size();
    VectorXd sc = C.colwise().norm().transpose();
    for (Index i = 0; i < m; ++i) sc[i] = sc[i] > 0 ? 1.0 / sc[i] : 1.0;
    std::vector<MatrixXd> G_fit(folds_);
    std::vector<VectorXd> g_fit(folds_);
    std::vector<std::vector<MatrixXd>> G_all(folds_, std::vector<MatrixXd>(N_));
    std::vector<std::vector<VectorXd>> g_all(folds_, std::vector<VectorXd>(N_));
    for (int f = 0; f < folds_; ++f) {
      G_fit[f] = MatrixXd::Zero(q, q);
      G_fit[f].topLeftCorner(p, p) = Gxx_fit_[f];
      g_fit[f] = VectorXd::Zero(q);
      g_fit[f].head(p) = gx_fit_[f];
      for (int j = 0; j < N_; ++j) {
        G_all[f][j] = MatrixXd::Zero(q, q);
        G_all[f][j].topLeftCorner(p, p) = Gxx_all_[f][j];
        g_all[f][j] = VectorXd::Zero(q);
        g_all[f][j].head(p) = gx_all_[f][j];
      }
    }
    if (m > 0) {
      for (Index s = 0; s < S; ++s) {
        const int f = fold_[s];
        for (int j = 0; j < N_; ++j) {
          const Index r = s * N_ + j;
          if (!d_.fit_row[r]) continue;
          const VectorXd c = C.row(r).transpose().cwiseProduct(sc);
          if (c.isZero(0.0)) continue;
          const VectorXd x = X.row(r).transpose().cwiseProduct(sx_);
          const double y = d_.y[r];
          const MatrixXd xc = x * c.transpose();
          const MatrixXd cc = c * c.transpose();
          auto add = [&](MatrixXd& G, VectorXd& g) {
            G.topRightCorner(p, m) += xc;
            G.bottomLeftCorner(m, p) += xc.transpose();
            G.bottomRightCorner(m, m) += cc;
            g.tail(m) += c * y;
          };
          add(G_all[f][j], g_all[f][j]);
          add(G_fit[f], g_fit[f]);
        }
      }
    }
    std::vector<VectorXd> fold_beta;
    const VectorXd beta = fold_fits(G_fit, g_fit, fold_beta);
    if (novelty) {
      MatrixXd G_total = MatrixXd::Zero(q, q);
      for (const auto& G : G_fit) G_total += G;
      const double ridge = ridge_for(G_total);
      *novelty = 1.0;
      if (m > 0) {
        MatrixXd Gxx = G_total.topLeftCorner(p, p);
        Gxx.diagonal().array() += ridge;
        const MatrixXd Gxc = G_total.topRightCorner(p, m);
        const MatrixXd schur = G_total.bottomRightCorner(m, m) - Gxc.transpose() * Gxx.ldlt().solve(Gxc);
        for (Index i = 0; i < m; ++i)
          *novelty = std::min(*novelty, schur(i, i) / std::max(1e-300, G_total(p + i, p + i)));
      }
    }
    auto rss = [&](const VectorXd& b, int f, int j) {
      return std::max(0.0, yy_[f][j] - 2.0 * b.dot(g_all[f][j]) + b.dot(G_all[f][j] * b));
    };
    val_rss = VectorXd::Zero(N_);
    for (int f = 0; f < folds_; ++f)
      for (int j = 0; j < N_; ++j) val_rss[j] += rss(fold_beta[f], f, j);
    train_rss = VectorXd::Zero(N_);
    for (int f = 0; f < folds_; ++f)
      for (int j = 0; j < N_; ++j) train_rss[j] += rss(beta, f, j);
    if (phi_out) {
      phi_out->resize(q);
      phi_out->head(p) = beta.head(p).cwiseProduct(sx_);
      phi_out->tail(m) = beta.tail(m).cwiseProduct(sc);
    }
  }

 private:
  static double ridge_for(const MatrixXd& G) { return 1e-12 * std::max(1.0, G.diagonal().maxCoeff()); }

  /// Least-squares coefficients from per-fold Gram matrices: fold_beta[f] from every fold but f,
  /// and the return value from all folds (a tiny ridge keeps LDLT defined for collinear columns).
  VectorXd fold_fits(const std::vector<MatrixXd>& G_fit, const std::vector<VectorXd>& g_fit,
                     std::vector<VectorXd>& fold_beta) const {
    MatrixXd G_total = MatrixXd::Zero(G_fit[0].rows(), G_fit[0].cols());
    VectorXd g_total = VectorXd::Zero(g_fit[0].size());
    for (int f = 0; f < folds_; ++f) {
      G_total += G_fit[f];
      g_total += g_fit[f];
    }
    const double ridge = ridge_for(G_total);
    auto solve = [&](MatrixXd G, const VectorXd& g) {
      G.diagonal().array() += ridge;
      return VectorXd(G.ldlt().solve(g));
    };
    fold_beta.resize(folds_);
    for (int f = 0; f < folds_; ++f) fold_beta[f] = solve(G_total - G_fit[f], g_total - g_fit[f]);
    return solve(G_total, g_total);
  }

  const StackedData& d_;
  int N_;
  const std::vector<int>& fold_;
  int folds_;
  const MatrixXd* X_ = nullptr;
  VectorXd sx_;
  std::vector<MatrixXd> Gxx_fit_;
  std::vector<VectorXd> gx_fit_;
  std::vector<std::vector<MatrixXd>> Gxx_all_;
  std::vector<std::vector<VectorXd>> gx_all_;
  std::vector<VectorXd> yy_;
};

double sgn(double x) {
  return x > 0 ? 1.0 : (x < 0 ? -1.0 : 0.0);
}

std::string joint_list(const std::vector<int>& joints) {
  std::string s;
  for (size_t i = 0; i < joints.size(); ++i)
    s += (i ? (i + 1 == joints.size() ? " and " : ", ") : "") + std::to_string(joints[i] + 1);
  return s;
}

}  // namespace

DiagnoseResult diagnose(const RobotDescription& robot, const JointLog& log, const DiagnoseOptions& o) {
  IdentifyOptions io = o.identify;
  if (io.terms == 0) io.terms = kFrictionEq7;
  io.load_regressor = true;  // the load-friction candidate's load torque h(q, qd)
  const StackedData d = prepare_stacked(robot, log, io);
  const int N = robot.num_joints;
  const Index S = d.t.size(), R = S * N;
  DiagnoseResult res;
  res.robot = robot.name;
  res.declared_model = model_name(io.terms);
  res.samples = static_cast<long>(S);
  // Bad input: a joint that does not move, or moves at constant velocity, carries no information.
  for (int j = 0; j < N; ++j) {
    const double range = d.q.col(j).maxCoeff() - d.q.col(j).minCoeff();
    const double qd_var = (d.qd.col(j).array() - d.qd.col(j).mean()).square().mean();
    if (range < 1e-3)
      throw InputError("joint " + std::to_string(j + 1) + " does not move (range < 1 mrad): nothing to diagnose");
    if (std::sqrt(qd_var) < 1e-3 * std::max(1e-9, d.qd.col(j).cwiseAbs().maxCoeff()) || std::sqrt(qd_var) < 1e-4) {
      throw InputError("joint " + std::to_string(j + 1) +
                       " moves at constant velocity: inertia and friction cannot be told apart");
    }
  }
  // Folds as in identify (blocked).
  const Index block = std::max<Index>(1, std::lround(io.block_seconds * d.rate_hz));
  const int folds = io.folds;
  if (S < block * folds * 2) throw InputError("too few samples for a diagnosis (" + std::to_string(S) + ")");
  std::vector<int> fold(static_cast<size_t>(S));
  for (Index s = 0; s < S; ++s) fold[s] = static_cast<int>((s / block) % folds);
  res.validation = "blocked " + std::to_string(folds) + "-fold cross-validation";
  const double duration = static_cast<double>(S) / d.rate_hz;
  // Effective independent samples of each joint's residual (effective_samples): the residual is
  // low-passed and carries smooth model error, so counting every sample would make BIC overconfident.
  auto effective_samples_per_joint = [&](const VectorXd& residual) {
    VectorXd n(N);
    for (int j = 0; j < N; ++j) {
      VectorXd r(S);
      for (Index s = 0; s < S; ++s) r[s] = residual[s * N + j];
      n[j] = effective_samples(r);
    }
    return n;
  };

  CrossValidator cv(d, N, fold, folds);
  MatrixXd X = d.W;
  VectorXd val0, train0;
  VectorXd phi;
  const MatrixXd none(R, 0);
  cv.set_base(X);
  cv.evaluate(none, val0, train0, &phi);
  const VectorXd val_before = val0, train_before = train0;
  const VectorXd prediction_before = X * phi;
  const VectorXd oof_before = cv.predict_out_of_fold();
  std::vector<std::string> names = d.names;

  auto is_term = [](const std::string& n) {
    for (const char* p : {"Fc", "Fv", "Fp", "Ia", "offset"})
      if (n.rfind(p, 0) == 0 && n.size() > std::strlen(p) &&
          std::isdigit(static_cast<unsigned char>(n[std::strlen(p)])))
        return true;
    return false;
  };
  VectorXd phi_rb = phi;
  for (size_t i = 0; i < names.size(); ++i)
    if (is_term(names[i])) phi_rb[static_cast<Index>(i)] = 0;
  // Two load torques for load-dependent friction, from the fitted rigid-body parameters: the torque
  // the gear transmits, Y(q, qd, qdd) phi (a real gearbox's friction grows with it, inertial part
  // included), and the load the joint holds, h(q, qd) = Y(q, qd, 0) phi (gravity and velocity
  // products: what a model without an algebraic loop, such as the simulated drive, applies). The
  // candidate takes whichever explains the residual better (counted as a search of 2).
  const std::pair<const char*, VectorXd> load_torques[] = {
      {"load: transmitted rigid-body torque", d.W * phi_rb},
      {"load: gravity and velocity-product torque", d.W_load * phi_rb}};
  auto has = [&](const std::string& n) { return std::find(names.begin(), names.end(), n) != names.end(); };

  // The candidate library.
  auto make = [&](const std::string& kind, std::vector<int> joints, std::vector<std::string> nm,
                  const std::function<void(Index s, MatrixXd & cols)>& fill, std::string detail = "") {
    Candidate c{kind, std::move(joints), std::move(nm), MatrixXd::Zero(R, static_cast<Index>(nm.size())),
                std::move(detail)};
    c.columns = MatrixXd::Zero(R, static_cast<Index>(c.names.size()));
    for (Index s = 0; s < S; ++s) fill(s, c.columns);
    return c;
  };
  // Of one-column alternatives, the one whose column explains most of the residual (its projection),
  // counted as a search over all of them.
  auto best_of = [](std::vector<Candidate> alternatives, const VectorXd& residual) {
    size_t best = 0;
    double best_gain = -1;
    for (size_t i = 0; i < alternatives.size(); ++i) {
      const VectorXd col = alternatives[i].columns.col(0);
      const double gain = std::pow(col.dot(residual), 2) / std::max(1e-300, col.squaredNorm());
      if (gain > best_gain) {
        best_gain = gain;
        best = i;
      }
    }
    Candidate c = std::move(alternatives[best]);
    c.searched = static_cast<int>(alternatives.size());
    return c;
  };
  auto library = [&](const VectorXd& residual) {
    std::vector<Candidate> out;
    for (int j = 0; j < N; ++j) {
      const std::string J = std::to_string(j + 1);
      const double vmax = d.qd.col(j).cwiseAbs().maxCoeff();
      // Stribeck / static friction: best velocity scale of a small grid.
      std::vector<Candidate> stribeck;
      for (double frac : {0.02, 0.05, 0.1, 0.2}) {
        const double qds = frac * vmax;
        stribeck.push_back(make(
            "stribeck", {j}, {"Fs" + J},
            [&](Index s, MatrixXd& m) {
              const double v = d.qd(s, j);
              m(s * N + j, 0) = sgn(v) * std::exp(-(v / qds) * (v / qds));
            },
            "velocity scale " + std::to_string(qds).substr(0, 5) + " rad/s"));
        stribeck.back().shape = qds;
      }
      out.push_back(best_of(std::move(stribeck), residual));
      out.push_back(make("asymmetric_friction", {j}, {"Fc+" + J, "Fv+" + J}, [&](Index s, MatrixXd& m) {
        const double v = d.qd(s, j);
        m(s * N + j, 0) = v > 0 ? 1.0 : 0.0;
        m(s * N + j, 1) = v > 0 ? v : 0.0;
      }));
      out.push_back(make("velocity_power", {j}, {"Fp" + J},
                         [&](Index s, MatrixXd& m) { m(s * N + j, 0) = std::cbrt(d.qd(s, j)); }));
      std::vector<Candidate> load;
      for (const auto& [detail, tau_load] : load_torques) {
        load.push_back(make(
            "load_friction", {j}, {"Fl" + J},
            [&](Index s, MatrixXd& m) { m(s * N + j, 0) = std::abs(tau_load[s * N + j]) * sgn(d.qd(s, j)); }, detail));
      }
      out.push_back(best_of(std::move(load), residual));
      if (!has("Ia" + J))
        out.push_back(
            make("rotor_inertia", {j}, {"Ia" + J}, [&](Index s, MatrixXd& m) { m(s * N + j, 0) = d.qdd(s, j); }));
      if (!has("offset" + J))
        out.push_back(make("offset", {j}, {"offset" + J}, [&](Index s, MatrixXd& m) { m(s * N + j, 0) = 1.0; }));
      // Position-periodic torque: spectral search of the residual over q_j (integer cycles/rev).
      int best_k = 0;
      double best_power = -1;
      for (int k = 1; k <= o.max_cycles; ++k) {
        const std::optional<double> power =
            harmonic_rss_reduction(d.q, j, k, [&](Index s) { return residual[s * N + j]; });
        if (power && *power > best_power) {
          best_power = *power;
          best_k = k;
        }
      }
      if (best_k > 0) {
        out.push_back(make(
            "position_periodic", {j}, {"A" + J + "_sin", "A" + J + "_cos"},
            [&](Index s, MatrixXd& m) {
              m(s * N + j, 0) = std::sin(best_k * d.q(s, j));
              m(s * N + j, 1) = std::cos(best_k * d.q(s, j));
            },
            std::to_string(best_k) + " cycles per revolution"));
        out.back().searched = o.max_cycles;
        out.back().shape = best_k;
      }
      out.push_back(make("drift", {j}, {"dFv" + J, "doffset" + J}, [&](Index s, MatrixXd& m) {
        const double tau_t = (d.t[s] - d.t[0]) / duration;  // 0..1 over the log
        m(s * N + j, 0) = tau_t * d.qd(s, j);
        m(s * N + j, 1) = tau_t;
      }));
    }
    // Transmission coupling: a motor turning with q_i +/- q_j whose friction and inertia act on both.
    for (int i = 0; i < N; ++i) {
      for (int j = i + 1; j < N; ++j) {
        for (double sign : {1.0, -1.0}) {
          const std::string tag = std::to_string(i + 1) + (sign > 0 ? "+" : "-") + std::to_string(j + 1);
          out.push_back(make(
              "coupling", {i, j}, {"Fc" + tag, "Fv" + tag, "Ia" + tag},
              [&](Index s, MatrixXd& m) {
                const double v = d.qd(s, i) + sign * d.qd(s, j), a = d.qdd(s, i) + sign * d.qdd(s, j);
                const double row_i = 1.0, row_j = sign;  // torque on joint j carries the motor's sign
                m(s * N + i, 0) = row_i * sgn(v);
                m(s * N + i, 1) = row_i * v;
                m(s * N + i, 2) = row_i * a;
                m(s * N + j, 0) = row_j * sgn(v);
                m(s * N + j, 1) = row_j * v;
                m(s * N + j, 2) = row_j * a;
              },
              sign > 0 ? "motor turning with q" + std::to_string(i + 1) + " + q" + std::to_string(j + 1)
                       : "motor turning with q" + std::to_string(i + 1) + " - q" + std::to_string(j + 1)));
          out.back().searched = 2;
          out.back().sign = sign;
        }
      }
    }
    return out;
  };

  for (int step = 0; step < o.max_effects; ++step) {
    const VectorXd residual = d.y - X * phi;
    std::vector<Candidate> cands = library(residual);
    const VectorXd n_eff = effective_samples_per_joint(residual);
    if (step == 0) res.effective_samples_per_joint = n_eff.mean();
    int best = -1;
    double best_score = 0;
    std::vector<double> bic(cands.size()), gain(cands.size());
    std::vector<char> physical(cands.size(), 1), collinear(cands.size(), 0);
    std::vector<VectorXd> vals(cands.size()), trains(cands.size());
    for (size_t c = 0; c < cands.size(); ++c) {
      VectorXd phi_c;
      double novelty = 1;
      cv.evaluate(cands[c].columns, vals[c], trains[c], &phi_c, &novelty);
      collinear[c] = novelty < 1e-6;
      double dbic = 0, v0 = 0, v1 = 0, n_joints = 0;
      for (int j : cands[c].joints) {
        n_joints += n_eff[j];
        dbic += n_eff[j] * std::log(std::max(1e-300, trains[c][j]) / std::max(1e-300, train0[j]));
        v0 += val0[j] / std::max(1e-300, val_before[j]);  // joints weighted by their own scale
        v1 += vals[c][j] / std::max(1e-300, val_before[j]);
      }
      dbic += static_cast<double>(cands[c].columns.cols()) * std::log(n_joints);
      // A candidate picked among several alternatives (the best frequency of a spectral search, ...)
      // pays for the look-elsewhere effect: 2 ln(alternatives), a Bonferroni factor in BIC units.
      dbic += 2.0 * std::log(static_cast<double>(cands[c].searched));
      bic[c] = dbic;
      gain[c] = v0 > 0 ? (v0 - v1) / v0 : 0;
      // Physical signs: static friction exceeds Coulomb friction (Eq. 4), rotor inertia is positive,
      // load-dependent friction and a coupled motor's friction oppose motion (its inertia may be ~0).
      const VectorXd added = phi_c.tail(cands[c].columns.cols());
      const std::string& k = cands[c].kind;
      physical[c] = !((k == "stribeck" || k == "rotor_inertia" || k == "load_friction") && added[0] <= 0) &&
                    !(k == "coupling" && (added[0] < 0 || added[1] < 0));
      // Selection on validation error only: the largest relative validation gain among candidates
      // whose BIC evidence is very strong and whose parameters are physical.
      if (physical[c] && !collinear[c] && dbic < -o.bic_threshold && gain[c] >= o.min_gain && gain[c] > best_score) {
        best_score = gain[c];
        best = static_cast<int>(c);
      }
    }
    if (best < 0) {
      // Report the strongest rejected candidate of each kind.
      for (const char* kind : {"stribeck", "asymmetric_friction", "velocity_power", "load_friction", "rotor_inertia",
                               "offset", "position_periodic", "coupling", "drift"}) {
        int top = -1;
        for (size_t c = 0; c < cands.size(); ++c)
          if (cands[c].kind == kind && (top < 0 || bic[c] < bic[static_cast<size_t>(top)])) top = static_cast<int>(c);
        if (top < 0) continue;
        const auto& c = cands[static_cast<size_t>(top)];
        RejectedCandidate rc{c.kind, {}, bic[static_cast<size_t>(top)], gain[static_cast<size_t>(top)], ""};
        for (int j : c.joints) rc.joints.push_back(j + 1);
        std::ostringstream why;
        why << std::setprecision(3);
        if (!physical[static_cast<size_t>(top)])
          why << "unphysical sign of its parameter (BIC change " << rc.delta_bic << ")";
        else if (rc.delta_bic >= -o.bic_threshold)
          why << "BIC change " << rc.delta_bic << " (needs < " << -o.bic_threshold << ")";
        else
          why << "validation RSS does not drop (gain " << 100 * rc.validation_gain << " %)";
        rc.reason = why.str();
        res.rejected.push_back(rc);
      }
      break;
    }
    const Candidate& c = cands[static_cast<size_t>(best)];
    MatrixXd A(R, X.cols() + c.columns.cols());
    A << X, c.columns;
    X = A;
    for (const auto& n : c.names) names.push_back(n);
    cv.set_base(X);
    cv.evaluate(none, val0, train0, &phi);
    DiagnosedEffect e;
    e.kind = c.kind;
    for (int j : c.joints) e.joints.push_back(j + 1);
    e.param_names = c.names;
    for (Index k = 0; k < c.columns.cols(); ++k) e.params.push_back(phi[X.cols() - c.columns.cols() + k]);
    e.delta_bic = bic[static_cast<size_t>(best)];
    e.shape = c.shape;
    e.sign = c.sign;
    e.validation_gain = gain[static_cast<size_t>(best)];
    std::ostringstream ex;
    ex << std::setprecision(3) << "joint" << (c.joints.size() > 1 ? "s " : " ") << joint_list(c.joints) << ": ";
    if (c.kind == "position_periodic") {
      ex << "residual periodic in q" << c.joints[0] + 1 << " with " << c.detail << ", amplitude "
         << std::hypot(e.params[0], e.params[1]) << " Nm - cogging or gear ripple";
    } else if (c.kind == "coupling") {
      ex << "a " << c.detail << " adds friction Fc " << e.params[0] << " Nm, Fv " << e.params[1]
         << " Nm s/rad and inertia " << e.params[2] << " kg m^2 shared by both joints - transmission coupling";
    } else if (c.kind == "stribeck") {
      ex << "extra torque at low speed with the sign of q_dot (" << c.detail << "), Fs - Fc = " << e.params[0]
         << " Nm - static friction / Stribeck";
    } else if (c.kind == "asymmetric_friction") {
      ex << "friction differs with the direction of motion: +" << e.params[0] << " Nm, +" << e.params[1]
         << " Nm s/rad for q_dot > 0 - asymmetric friction";
    } else if (c.kind == "velocity_power") {
      ex << "friction grows with q_dot^(1/3), f1 = " << e.params[0] << " - velocity-power friction (Eq. 8)";
    } else if (c.kind == "load_friction") {
      ex << "friction grows with the load torque (" << c.detail << "), f1 = " << e.params[0]
         << " - load-dependent friction (Eq. 9)";
    } else if (c.kind == "rotor_inertia") {
      ex << "residual follows q_ddot, Ia = " << e.params[0] << " kg m^2 - rotor inertia";
    } else if (c.kind == "offset") {
      ex << "constant torque " << e.params[0] << " Nm - torque offset";
    } else if (c.kind == "drift") {
      ex << "viscous friction changes by " << e.params[0] << " Nm s/rad and the offset by " << e.params[1]
         << " Nm over the log - drift (temperature)";
    }
    e.explanation = ex.str();
    res.effects.push_back(e);
  }

  res.declared_names = d.names;
  res.declared_params.assign(phi.data(), phi.data() + d.W.cols());
  // Traces for the plots.
  {
    res.traces.t = d.t;
    res.traces.q = d.q;
    res.traces.qd = d.qd;
    res.traces.tau.resize(S, N);
    res.traces.tau_before.resize(S, N);
    res.traces.tau_after.resize(S, N);
    const VectorXd after = X * phi;
    for (Index s = 0; s < S; ++s)
      for (int j = 0; j < N; ++j) {
        res.traces.tau(s, j) = d.y[s * N + j];
        res.traces.tau_before(s, j) = prediction_before[s * N + j];
        res.traces.tau_after(s, j) = after[s * N + j];
      }
    res.traces.spectrum = MatrixXd::Zero(o.max_cycles, N);
    for (int j = 0; j < N; ++j)
      for (int k = 1; k <= o.max_cycles; ++k) {
        const std::optional<double> power =
            harmonic_rss_reduction(d.q, j, k, [&](Index s) { return d.y[s * N + j] - prediction_before[s * N + j]; });
        if (power) res.traces.spectrum(k - 1, j) = *power / static_cast<double>(S);
      }
  }
  // Metrics before/after.
  VectorXd val_after, train_after;
  cv.evaluate(none, val_after, train_after);
  const VectorXd oof_after = cv.predict_out_of_fold();
  for (int j = 0; j < N; ++j) {
    DiagnoseJoint m;
    m.joint = j + 1;
    double sy = 0, syy = 0;
    for (Index s = 0; s < S; ++s) {
      sy += d.y[s * N + j];
      syy += d.y[s * N + j] * d.y[s * N + j];
    }
    const double n = static_cast<double>(S), ss_tot = syy - sy * sy / n;
    m.rms_tau = std::sqrt(syy / n);
    m.rms_train_before = std::sqrt(train_before[j] / n);
    m.rms_train_after = std::sqrt(train_after[j] / n);
    m.rms_validation_before = std::sqrt(val_before[j] / n);
    m.rms_validation_after = std::sqrt(val_after[j] / n);
    m.r2_validation_before = 1 - val_before[j] / ss_tot;
    m.r2_validation_after = 1 - val_after[j] / ss_tot;
    // e_T and e_T_Std (survey Sec. 5.1): mean and standard deviation of |tau - tau_hat| / tau_max
    // over the out-of-fold predictions (rows in the fit only, as the validation RSS).
    auto indices = [&](const VectorXd& pred, double& mean, double& stdev) {
      double sa = 0, sa2 = 0, n_rows = 0;
      for (Index s = 0; s < S; ++s) {
        const Index r = s * N + j;
        if (!d.fit_row[r]) continue;
        const double a = std::abs(d.y[r] - pred[r]) / robot.tau_max[j];
        sa += a;
        sa2 += a * a;
        n_rows += 1;
      }
      mean = sa / std::max(1.0, n_rows);
      stdev = std::sqrt(std::max(0.0, sa2 / std::max(1.0, n_rows) - mean * mean));
    };
    indices(oof_before, m.e_T_before, m.e_T_std_before);
    indices(oof_after, m.e_T_after, m.e_T_std_after);
    res.joints.push_back(m);
  }
  return res;
}

void print_diagnose_report(std::ostream& out, const DiagnoseResult& r) {
  out << "dyncal diagnose: robot " << r.robot << ", declared model " << r.declared_model << ", " << r.samples
      << " samples, " << r.validation << ", BIC with n_eff = " << std::lround(r.effective_samples_per_joint)
      << " per joint (mean, from the residual's autocorrelation)\n\n";
  out << "effects added (greedy, by validation gain, each with BIC evidence):\n";
  if (r.effects.empty()) out << "  none: nothing significant is left in the residual\n";
  for (const auto& e : r.effects) {
    out << "  " << std::left << std::setw(20) << e.kind << std::right << " dBIC " << std::setw(8)
        << std::setprecision(4) << e.delta_bic << ", validation RSS -" << std::setprecision(3)
        << 100 * e.validation_gain << " %\n    " << e.explanation << "\n";
  }
  out << "\nstrongest rejected candidates:\n";
  for (const auto& c : r.rejected) {
    out << "  " << std::left << std::setw(20) << c.kind << std::right << " joint";
    for (int j : c.joints) out << " " << j;
    out << ": " << c.reason << "\n";
  }
  out << "\njoint   RMS val before   after [Nm]   R2 before   after   rel. RMS after     e_T before  after   e_T_Std "
         "before  after\n"
      << std::fixed;
  for (const auto& j : r.joints) {
    out << std::setw(5) << j.joint << std::setprecision(4) << std::setw(17) << j.rms_validation_before << std::setw(12)
        << j.rms_validation_after << std::setw(12) << j.r2_validation_before << std::setw(8) << j.r2_validation_after
        << std::setw(17) << j.rms_validation_after / j.rms_tau << std::setw(15) << j.e_T_before << std::setw(7)
        << j.e_T_after << std::setw(15) << j.e_T_std_before << std::setw(7) << j.e_T_std_after << "\n";
  }
  out << "\njoint   RMS train before   after [Nm]   rel. RMS train before   after\n";
  for (const auto& j : r.joints) {
    out << std::setw(5) << j.joint << std::setprecision(4) << std::setw(19) << j.rms_train_before << std::setw(12)
        << j.rms_train_after << std::setw(24) << j.rms_train_before / j.rms_tau << std::setw(8)
        << j.rms_train_after / j.rms_tau << "\n";
  }
  out << std::defaultfloat;
}

std::vector<std::string> write_diagnose_plots(const DiagnoseResult& r, const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir);
  const auto& tr = r.traces;
  const Index S = tr.t.size(), N = tr.q.cols();
  {
    std::ofstream data(dir + "/samples.dat");
    if (!data) throw InputError("cannot write into '" + dir + "'");
    data << "# t, then per joint: q qd tau tau_before tau_after\n";
    for (Index s = 0; s < S; ++s) {
      data << tr.t[s];
      for (Index j = 0; j < N; ++j)
        data << " " << tr.q(s, j) << " " << tr.qd(s, j) << " " << tr.tau(s, j) << " " << tr.tau_before(s, j) << " "
             << tr.tau_after(s, j);
      data << "\n";
    }
    std::ofstream spec(dir + "/spectrum.dat");
    for (Index k = 0; k < tr.spectrum.rows(); ++k) {
      spec << k + 1;
      for (Index j = 0; j < N; ++j) spec << " " << std::sqrt(2.0 * tr.spectrum(k, j));  // amplitude [Nm]
      spec << "\n";
    }
  }
  std::vector<std::string> files;
  std::ofstream gp(dir + "/plots.gp");
  gp << "set terminal svg size 900,500 dynamic background rgb 'white' noenhanced\nset grid\nset key outside\n";
  for (Index j = 0; j < N; ++j) {
    const Index b = 2 + 5 * j;  // column of q_j
    const std::string J = std::to_string(j + 1);
    auto out = [&](const std::string& name) {
      files.push_back(dir + "/" + name);
      gp << "set output '" << dir << "/" << name << "'\n";
    };
    out("joint" + J + "_residual_vs_velocity.svg");
    gp << "set title 'joint " << J << ": residual of the declared model vs velocity'\nset xlabel 'qd" << J
       << " [rad/s]'\nset ylabel 'tau - tau_hat [Nm]'\nplot '" << dir << "/samples.dat' u " << b + 1 << ":($" << b + 2
       << "-$" << b + 3 << ") w p pt 7 ps 0.2 t 'declared model', '' u " << b + 1 << ":($" << b + 2 << "-$" << b + 4
       << ") w p pt 7 ps 0.2 t 'with the effects found'\n";
    out("joint" + J + "_residual_vs_position.svg");
    gp << "set title 'joint " << J << ": residual vs position'\nset xlabel 'q" << J << " [rad]'\nplot '" << dir
       << "/samples.dat' u " << b << ":($" << b + 2 << "-$" << b + 3 << ") w p pt 7 ps 0.2 t 'declared model', '' u "
       << b << ":($" << b + 2 << "-$" << b + 4 << ") w p pt 7 ps 0.2 t 'with the effects found'\n";
    out("joint" + J + "_residual_spectrum.svg");
    gp << "set title 'joint " << J << ": residual amplitude by cycles per revolution of q" << J
       << "'\nset xlabel 'cycles per revolution'\nset ylabel 'amplitude [Nm]'\nplot '" << dir
       << "/spectrum.dat' u 1:" << j + 2 << " w impulses lw 2 t 'declared model residual'\n";
    out("joint" + J + "_torque.svg");
    gp << "set title 'joint " << J
       << ": measured and predicted torque (fits on all data)'\nset xlabel 't [s]'\nset "
          "ylabel 'tau [Nm]'\nplot '"
       << dir << "/samples.dat' u 1:" << b + 2 << " w l lw 2 t 'measured', '' u 1:" << b + 3
       << " w l t 'declared model', '' u 1:" << b + 4 << " w l t 'with the effects found'\n";
  }
  gp.close();
  const std::string cmd = "gnuplot '" + dir + "/plots.gp' 2>'" + dir + "/gnuplot.log'";
  if (std::system(cmd.c_str()) != 0) {
    throw InputError("gnuplot failed or is missing (scripts/setup installs gnuplot-nox); see " + dir + "/gnuplot.log");
  }
  return files;
}

std::vector<EffectTerm> effect_terms(const DiagnoseResult& r, std::vector<std::string>* skipped) {
  std::vector<EffectTerm> out;
  for (const auto& e : r.effects) {
    EffectTerm t;
    t.joint = static_cast<std::uint8_t>(e.joints.front() - 1);
    for (size_t k = 0; k < e.params.size() && k < 3; ++k) t.c[k] = static_cast<float>(e.params[k]);
    t.shape = static_cast<float>(e.shape);
    if (e.kind == "stribeck")
      t.kind = EffectKind::stribeck;
    else if (e.kind == "asymmetric_friction")
      t.kind = EffectKind::asymmetric_friction;
    else if (e.kind == "velocity_power")
      t.kind = EffectKind::velocity_power;
    else if (e.kind == "load_friction")
      t.kind = EffectKind::load_friction;
    else if (e.kind == "rotor_inertia")
      t.kind = EffectKind::rotor_inertia;
    else if (e.kind == "offset")
      t.kind = EffectKind::offset;
    else if (e.kind == "position_periodic")
      t.kind = EffectKind::position_periodic;
    else if (e.kind == "coupling") {
      t.kind = EffectKind::coupling;
      t.joint2 = static_cast<std::uint8_t>(e.joints.back() - 1);
      t.sign = static_cast<std::int8_t>(e.sign > 0 ? 1 : -1);
    } else {
      if (skipped) skipped->push_back(e.kind + " on joint " + std::to_string(e.joints.front()));
      continue;
    }
    out.push_back(t);
  }
  return out;
}

nlohmann::json diagnose_report_json(const DiagnoseResult& r) {
  nlohmann::json j;
  j["robot"] = r.robot;
  j["declared_model"] = r.declared_model;
  j["samples"] = r.samples;
  j["validation"] = r.validation;
  j["effective_samples_per_joint"] = r.effective_samples_per_joint;
  j["effects"] = nlohmann::json::array();
  for (const auto& e : r.effects) {
    nlohmann::json p = nlohmann::json::object();
    for (size_t i = 0; i < e.params.size(); ++i) p[e.param_names[i]] = e.params[i];
    j["effects"].push_back({{"kind", e.kind},
                            {"joint", e.joints.front()},
                            {"joints", e.joints},
                            {"parameters", p},
                            {"evidence", {{"delta_bic", e.delta_bic}, {"validation_gain", e.validation_gain}}},
                            {"explanation", e.explanation}});
  }
  j["rejected"] = nlohmann::json::array();
  for (const auto& c : r.rejected)
    j["rejected"].push_back({{"kind", c.kind}, {"joints", c.joints}, {"delta_bic", c.delta_bic}, {"reason", c.reason}});
  j["joints"] = nlohmann::json::array();
  for (const auto& m : r.joints) {
    j["joints"].push_back({{"joint", m.joint},
                           {"rms_train_before", m.rms_train_before},
                           {"rms_train_after", m.rms_train_after},
                           {"rms_validation_before", m.rms_validation_before},
                           {"rms_validation_after", m.rms_validation_after},
                           {"relative_rms_validation_before", m.rms_validation_before / m.rms_tau},
                           {"relative_rms_validation_after", m.rms_validation_after / m.rms_tau},
                           {"r2_validation_before", m.r2_validation_before},
                           {"r2_validation_after", m.r2_validation_after},
                           {"e_T_before", m.e_T_before},
                           {"e_T_after", m.e_T_after},
                           {"e_T_std_before", m.e_T_std_before},
                           {"e_T_std_after", m.e_T_std_after}});
  }
  return j;
}

}  // namespace dyncal::host
