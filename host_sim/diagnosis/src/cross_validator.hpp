#pragma once
// Blocked cross-validation of a growing linear design (private to host_sim/diagnosis).

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host::detail {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// A candidate's roughness penalty in CrossValidator::evaluate: its ShapePenalty (column counted within
/// the candidate's columns) and the penalties lambda to choose among (empty: shape.lambda alone). Out:
/// the chosen lambda and its effective parameters m - lambda tr(G^-1 P) (G the penalised Gram of all
/// rows, P the candidate's unit penalty in it: the part of the hat matrix's trace that is the
/// candidate's).
struct CandidatePenalty {
  ShapePenalty shape;
  std::vector<double> lambdas;
  double chosen = 0;
  double edf = 0;
};

/// Blocked cross-validation from per-fold, per-joint Gram matrices of the design [X C] and y. The
/// base design X is fixed for a greedy step (set_base), so each candidate C only costs its cross
/// products with X over the rows where C is not zero. The fit weighs joint j's rows by w_j
/// (set_joint_weights; 1 by default: OLS); the RSS it reports are per joint and unweighted [Nm^2].
/// A penalised shape (effect_model.hpp's ShapePenalty) adds w_j^2 n_j lambda |L c|^2 to the fit's
/// criterion, n_j the joint's fitted rows in that fit (all rows, or every fold's but one): each fold
/// carries its rows' share of it, so a fit without fold f has n_j less that fold's rows. The RSS
/// stay the data's alone.
class CrossValidator {
 public:
  CrossValidator(const StackedData& d, int N, const std::vector<int>& fold, int folds)
      : d_(d), N_(N), fold_(fold), folds_(folds), w2_(VectorXd::Ones(N)) {}

  /// Row weights per joint (weighted least squares: w_j = 1 / sigma_j, Gautier). Takes effect at
  /// the next set_base.
  void set_joint_weights(const VectorXd& w) { w2_ = w.cwiseAbs2(); }

  /// The base design X ((S N) x p) and the penalties of its penalised shapes (columns of X).
  void set_base(const MatrixXd& X, const std::vector<ShapePenalty>& penalties) {
    X_ = &X;
    const Index p = X.cols(), S = d_.t.size();
    sx_ = X.colwise().norm().transpose();
    for (Index i = 0; i < p; ++i) sx_[i] = sx_[i] > 0 ? 1.0 / sx_[i] : 1.0;
    Gxx_fit_.assign(folds_, MatrixXd::Zero(p, p));
    gx_fit_.assign(folds_, VectorXd::Zero(p));
    Gxx_all_.assign(folds_, std::vector<MatrixXd>(N_, MatrixXd::Zero(p, p)));
    gx_all_.assign(folds_, std::vector<VectorXd>(N_, VectorXd::Zero(p)));
    yy_.assign(folds_, VectorXd::Zero(N_));
    rows_.assign(folds_, VectorXd::Zero(N_));
    for (Index s = 0; s < S; ++s) {
      const int f = fold_[s];
      for (int j = 0; j < N_; ++j) {
        const Index r = s * N_ + j;
        const VectorXd x = X.row(r).transpose().cwiseProduct(sx_);
        const double y = d_.y[r];
        if (!d_.fit_row[r]) continue;  // rows left out of the fit (stiction band) are not judged either
        rows_[f][j] += 1;
        Gxx_all_[f][j].selfadjointView<Eigen::Lower>().rankUpdate(x);
        gx_all_[f][j] += x * y;
        yy_[f][j] += y * y;
        Gxx_fit_[f].selfadjointView<Eigen::Lower>().rankUpdate(x, w2_[j]);
        gx_fit_[f] += w2_[j] * y * x;
      }
    }
    for (auto& G : Gxx_fit_) G = MatrixXd(G.selfadjointView<Eigen::Lower>());
    for (auto& v : Gxx_all_)
      for (auto& G : v) G = MatrixXd(G.selfadjointView<Eigen::Lower>());
    for (const ShapePenalty& pen : penalties) add_penalty(pen, sx_.segment(pen.column, pen.rows.cols()), 0, Gxx_fit_);
  }

  /// Out-of-fold predictions of the base design alone (each block predicted by the fit without its
  /// fold), for the per-sample indices e_T_abs and e_T_abs_std.
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

  /// The base design's coefficients fitted without each fold in turn (folds entries of X.cols()):
  /// the replicates of a delete-a-group jackknife (the folds are interleaved blocks).
  std::vector<VectorXd> fold_coefficients() const {
    std::vector<VectorXd> beta;
    fold_fits(Gxx_fit_, gx_fit_, beta);
    for (auto& b : beta) b = b.cwiseProduct(sx_);
    return beta;
  }

  /// Validation and training RSS per joint of [X C] (C may have no columns); phi_out: the
  /// coefficients of the fit on all rows, X's first.
  /// *novelty: the smallest fraction of a (unit-scaled) candidate column not explained by X (1 if C
  /// is empty); near 0 means the candidate is collinear with the model and not identifiable.
  /// drop: columns of X left out of this fit (a candidate that replaces them); their coefficients 0.
  /// penalty: the candidate's roughness penalty (CandidatePenalty), chosen among its grid by the
  /// least validation RSS on its joint; the outputs are that fit's. val_folds: the validation RSS
  /// per fold (folds x N; val_rss its column sums), for a jackknife over the folds.
  void evaluate(const MatrixXd& C, VectorXd& val_rss, VectorXd& train_rss, VectorXd* phi_out = nullptr,
                double* novelty = nullptr, const std::vector<Index>& drop = {}, CandidatePenalty* penalty = nullptr,
                MatrixXd* val_folds = nullptr) const {
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
      // The fitted rows where C is not zero, by fold and joint; each group's cross products at once.
      std::vector<char> nonzero(static_cast<size_t>(C.rows()), 0);  // read column by column: C is column-major
      for (Index k = 0; k < m; ++k)
        for (Index r = 0; r < C.rows(); ++r) nonzero[static_cast<size_t>(r)] |= C(r, k) != 0.0;
      std::vector<std::vector<std::vector<Index>>> rows(folds_, std::vector<std::vector<Index>>(N_));
      for (Index s = 0; s < S; ++s)
        for (int j = 0; j < N_; ++j) {
          const Index r = s * N_ + j;
          if (d_.fit_row[r] && nonzero[static_cast<size_t>(r)]) rows[fold_[s]][j].push_back(r);
        }
      for (int f = 0; f < folds_; ++f)
        for (int j = 0; j < N_; ++j) {
          const std::vector<Index>& at = rows[f][j];
          if (at.empty()) continue;
          const MatrixXd Xb = X(at, Eigen::all) * sx_.asDiagonal(), Cb = C(at, Eigen::all) * sc.asDiagonal();
          const MatrixXd xc = Xb.transpose() * Cb, cc = Cb.transpose() * Cb;
          const VectorXd cy = Cb.transpose() * d_.y(at);
          auto add = [&](MatrixXd& G, VectorXd& g, double w2) {  // the lower-left block: at the end
            G.topRightCorner(p, m) += w2 * xc;
            G.bottomRightCorner(m, m) += w2 * cc;
            g.tail(m) += w2 * cy;
          };
          add(G_all[f][j], g_all[f][j], 1.0);
          add(G_fit[f], g_fit[f], w2_[j]);
        }
      auto mirror = [&](MatrixXd& G) { G.bottomLeftCorner(m, p) = G.topRightCorner(p, m).transpose(); };
      for (int f = 0; f < folds_; ++f) {
        mirror(G_fit[f]);
        for (int j = 0; j < N_; ++j) mirror(G_all[f][j]);
      }
    }
    // A dropped column's rows and columns leave the Grams.
    std::vector<Index> keep;
    for (Index i = 0; i < q; ++i)
      if (std::find(drop.begin(), drop.end(), i) == drop.end()) keep.push_back(i);
    if (!drop.empty()) {
      auto reduce = [&](MatrixXd& G, VectorXd& g) {
        G = MatrixXd(G(keep, keep));
        g = VectorXd(g(keep));
      };
      for (int f = 0; f < folds_; ++f) {
        reduce(G_fit[f], g_fit[f]);
        for (int j = 0; j < N_; ++j) reduce(G_all[f][j], g_all[f][j]);
      }
    }
    const Index kept = p - static_cast<Index>(drop.size());
    VectorXd beta;
    if (!penalty) {
      solve_and_score(G_fit, g_fit, G_all, g_all, kept, m, val_rss, train_rss, phi_out ? &beta : nullptr, novelty,
                      val_folds);
    } else {
      solve_penalised(G_fit, g_fit, G_all, g_all, kept, m, sc, *penalty, val_rss, train_rss, beta, novelty, val_folds);
    }
    if (phi_out) {
      // X's columns then C's, unscaled; the dropped ones 0.
      VectorXd scale(q);
      scale << sx_, sc;
      phi_out->setZero(q);
      for (size_t i = 0; i < keep.size(); ++i) (*phi_out)[keep[i]] = beta[static_cast<Index>(i)] * scale[keep[i]];
    }
  }

 private:
  /// Fits from the Grams (p base columns, m candidate columns): validation and training RSS per
  /// joint, the coefficients on the unit-scaled columns (*beta_out), the candidate's novelty.
  void solve_and_score(const std::vector<MatrixXd>& G_fit, const std::vector<VectorXd>& g_fit,
                       const std::vector<std::vector<MatrixXd>>& G_all, const std::vector<std::vector<VectorXd>>& g_all,
                       Index p, Index m, VectorXd& val_rss, VectorXd& train_rss, VectorXd* beta_out, double* novelty,
                       MatrixXd* val_folds = nullptr) const {
    const Index q = p + m;
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
    if (val_folds) val_folds->setZero(folds_, N_);
    for (int f = 0; f < folds_; ++f)
      for (int j = 0; j < N_; ++j) {
        const double v = rss(fold_beta[f], f, j);
        val_rss[j] += v;
        if (val_folds) (*val_folds)(f, j) = v;
      }
    train_rss = VectorXd::Zero(N_);
    for (int f = 0; f < folds_; ++f)
      for (int j = 0; j < N_; ++j) train_rss[j] += rss(beta, f, j);
    if (beta_out) *beta_out = beta;
  }

  /// solve_and_score for each penalty lambda of the candidate's grid on the same Grams (its unit
  /// penalty per fold added lambda times), the outputs those of the least validation RSS on its
  /// joint; penalty.chosen and penalty.edf set from it.
  void solve_penalised(const std::vector<MatrixXd>& G_fit, const std::vector<VectorXd>& g_fit,
                       const std::vector<std::vector<MatrixXd>>& G_all, const std::vector<std::vector<VectorXd>>& g_all,
                       Index kept, Index m, const VectorXd& sc, CandidatePenalty& penalty, VectorXd& val_rss,
                       VectorXd& train_rss, VectorXd& beta, double* novelty, MatrixXd* val_folds) const {
    // Each penalty of the grid on the same Grams; the least validation RSS on its joint is kept.
    const std::vector<double> grid =
        penalty.lambdas.empty() ? std::vector<double>{penalty.shape.lambda} : penalty.lambdas;
    const Index qk = kept + m;
    std::vector<MatrixXd> P(folds_, MatrixXd::Zero(qk, qk));
    ShapePenalty unit = penalty.shape;
    unit.lambda = 1.0;
    add_penalty(unit, sc.segment(unit.column, unit.rows.cols()), kept, P);
    MatrixXd P_total = MatrixXd::Zero(qk, qk);
    for (const auto& Pf : P) P_total += Pf;
    double best = INFINITY;
    std::vector<MatrixXd> G_pen(folds_);
    for (const double lambda : grid) {
      for (int f = 0; f < folds_; ++f) G_pen[f] = G_fit[f] + lambda * P[f];
      VectorXd val, train, b;
      MatrixXd by_fold;
      double nov = 1;
      solve_and_score(G_pen, g_fit, G_all, g_all, kept, m, val, train, &b, novelty ? &nov : nullptr, &by_fold);
      if (!(val[penalty.shape.joint] < best)) continue;
      best = val[penalty.shape.joint];
      val_rss = val, train_rss = train, beta = b;
      if (val_folds) *val_folds = by_fold;
      if (novelty) *novelty = nov;
      penalty.chosen = lambda;
      MatrixXd G_total = MatrixXd::Zero(qk, qk);
      for (const auto& G : G_pen) G_total += G;
      G_total.diagonal().array() += ridge_for(G_total);
      penalty.edf = static_cast<double>(m) - lambda * G_total.ldlt().solve(P_total).trace();
    }
  }

  /// Adds penalty `pen` (its columns from offset + pen.column, scaled by `scale` as the Grams' are)
  /// to each fold's fit Gram: w_j^2 lambda (the fold's fitted rows of joint j) L^T L.
  void add_penalty(const ShapePenalty& pen, const VectorXd& scale, Index offset, std::vector<MatrixXd>& G) const {
    const MatrixXd L = pen.rows * scale.asDiagonal();
    const MatrixXd LtL = L.transpose() * L;
    const Index m = pen.rows.cols(), at = offset + pen.column;
    for (int f = 0; f < folds_; ++f)
      G[f].block(at, at, m, m) += w2_[pen.joint] * pen.lambda * rows_[f][pen.joint] * LtL;
  }

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
  VectorXd w2_;  ///< squared joint weights of the fit
  const MatrixXd* X_ = nullptr;
  VectorXd sx_;
  std::vector<MatrixXd> Gxx_fit_;
  std::vector<VectorXd> gx_fit_;
  std::vector<std::vector<MatrixXd>> Gxx_all_;
  std::vector<std::vector<VectorXd>> gx_all_;
  std::vector<VectorXd> yy_;
  std::vector<VectorXd> rows_;  ///< fitted rows per fold and joint
};

}  // namespace dyncal::host::detail
