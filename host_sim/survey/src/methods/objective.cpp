#include "dyncal_host/survey/methods/objective.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Vec6 = Eigen::Matrix<double, 6, 1>;
/// exp(-(|qd| / qds)^2) < 1e-18 beyond |qd| = 6.5 qds: those rows carry no Stribeck term.
constexpr double kStribeckReach = 6.5;

double sgn(double v) {
  return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
}

/// Whether friction parameter k of `model` is an amplitude of the nonlinear part (its column there
/// depends on the scale parameters): Fc, Fs of Eq. 4 (through Fs - Fc), f2, f4 of Eq. 5, f1, f2 of Eq. 6.
bool has_nonlinear_column(FrictionModel model, int k) {
  switch (model) {
    case FrictionModel::eq4:
      return k == 0 || k == 1;
    case FrictionModel::eq5:
      return k == 1 || k == 3;
    case FrictionModel::eq6:
      return k == 0 || k == 1;
    default:
      return false;
  }
}

/// Standard regressor rows of every sample: Ys[s] is 6 x 60.
std::vector<Eigen::Matrix<double, 6, kStandard>> standard_rows(const RunData& d) {
  std::vector<Eigen::Matrix<double, 6, kStandard>> Y(static_cast<size_t>(d.q.rows()));
  for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
    Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                              Vec6(d.qdd.row(s).transpose()), Y[static_cast<size_t>(s)]);
  }
  return Y;
}

}  // namespace

TorqueObjective::TorqueObjective(const RunData& d, FrictionModel model, const std::array<double, 6>& sigma)
    : model_(model), kf_(friction_count(model)) {
  const Eigen::Index S = d.q.rows();
  if (S < 1) throw InputError("the optimisation objective needs samples");
  if (d.tau_load.rows() != S) throw InputError("the optimisation objective needs the run's load torque");
  n_ = static_cast<double>(S);
  for (int k = 0; k < kf_; ++k) {
    if (is_linear_parameter(model, k)) linear_.push_back(k);
  }
  for (int k = 0; k < kf_; ++k) {
    if (is_scale_parameter(model, k)) continue;
    amplitudes_.push_back(k);
    const auto it = std::find(linear_.begin(), linear_.end(), k);
    amplitude_column_.push_back(it == linear_.end() ? -1 : kStandard + static_cast<int>(it - linear_.begin()));
    if (has_nonlinear_column(model, k)) nonlinear_amplitudes_.push_back(static_cast<int>(amplitudes_.size()) - 1);
  }
  const int L = kStandard + static_cast<int>(linear_.size());
  const auto Y = standard_rows(d);
  for (int j = 0; j < 6; ++j) {
    Joint& J = joints_[j];
    J.w = 1.0 / sigma[j];
    Eigen::MatrixXd A(S, L);
    for (Eigen::Index s = 0; s < S; ++s) {
      A.row(s).head<kStandard>() = J.w * Y[static_cast<size_t>(s)].row(j);
      for (size_t i = 0; i < linear_.size(); ++i) {
        A(s, kStandard + static_cast<Eigen::Index>(i)) =
            J.w * linear_column(model, linear_[i], d.qd(s, j), d.tau_load(s, j));
      }
    }
    const Eigen::VectorXd tau = d.tau.col(j) * J.w;
    J.G = A.transpose() * A;
    J.h = A.transpose() * tau;
    J.a = A.colwise().sum().transpose();
    J.tt = tau.squaredNorm();
    J.ts = tau.sum();
    J.first = 0;
    while (J.first < kStandard && A.col(J.first).cwiseAbs().maxCoeff() == 0.0) ++J.first;
    if (is_linear(model)) continue;
    std::vector<Eigen::Index> order(static_cast<size_t>(S));
    std::iota(order.begin(), order.end(), Eigen::Index{0});
    std::stable_sort(order.begin(), order.end(),
                     [&](Eigen::Index a, Eigen::Index b) { return std::fabs(d.qd(a, j)) < std::fabs(d.qd(b, j)); });
    J.A_sorted.resize(S, L - J.first);
    J.tau_sorted.resize(S);
    J.qd_sorted.resize(S);
    for (Eigen::Index k = 0; k < S; ++k) {
      const Eigen::Index s = order[static_cast<size_t>(k)];
      J.A_sorted.row(k) = A.row(s).tail(L - J.first);
      J.tau_sorted[k] = tau[s];
      J.qd_sorted[k] = d.qd(s, j);
    }
    J.aq_sorted = J.qd_sorted.abs();
    J.sg_sorted = J.qd_sorted.unaryExpr([](double v) { return sgn(v); });
    J.inv_aq_sorted = J.aq_sorted.max(1e-300).inverse();
  }
}

int TorqueObjective::dimension() const {
  return kStandard + 6 * kf_;
}

Eigen::Index TorqueObjective::reach(const Joint& J, const double* theta) const {
  const Eigen::Index S = J.qd_sorted.size();
  if (model_ != FrictionModel::eq4) return S;
  const double v = kStribeckReach * std::max(theta[2], 1e-3);
  return std::lower_bound(J.aq_sorted.data(), J.aq_sorted.data() + S, v) - J.aq_sorted.data();
}

void TorqueObjective::nonlinear_part(const Joint& J, const double* th, Eigen::Index k, Eigen::ArrayXd& n,
                                     Eigen::ArrayXXd* dn) const {
  const auto aq = J.aq_sorted.head(k), sg = J.sg_sorted.head(k), qd = J.qd_sorted.head(k);
  const double w = J.w;
  if (dn) dn->setZero(k, kf_);
  switch (model_) {
    case FrictionModel::eq4: {  // (Fs - Fc) sgn exp(-(qd / qds)^2)
      const double c = th[1] - th[0], qds = std::max(th[2], 1e-3);
      const Eigen::ArrayXd u2 = (aq / qds).square();
      const Eigen::ArrayXd E = w * sg * (-u2).exp();
      n = c * E;
      if (dn) {
        dn->col(0) = -E;
        dn->col(1) = E;
        if (th[2] > 1e-3) dn->col(2) = c * E * 2 * u2 / qds;
      }
      break;
    }
    case FrictionModel::eq5: {  // -f2 sgn exp(-|qd| / f3) - f4 sgn exp(-1 / (f5 |qd|))
      const double f3 = std::max(th[2], 1e-3), f5 = std::max(th[4], 1e-3);
      const Eigen::ArrayXd e3 = w * sg * (-aq / f3).exp();
      const Eigen::ArrayXd inv = J.inv_aq_sorted.head(k);
      const Eigen::ArrayXd e5 = w * sg * (-inv / f5).exp();
      n = -th[1] * e3 - th[3] * e5;
      if (dn) {
        dn->col(1) = -e3;
        if (th[2] > 1e-3) dn->col(2) = -th[1] * e3 * aq / (f3 * f3);
        dn->col(3) = -e5;
        if (th[4] > 1e-3) dn->col(4) = -th[3] * e5 * inv / (f5 * f5);
      }
      break;
    }
    case FrictionModel::eq6: {  // (f1 + f2 sech(f3 qd)) tanh(f4 qd), by exponentials of -|x|
      const double f3 = std::max(th[2], 1e-3), f4 = std::max(th[3], 1e-3);
      const Eigen::ArrayXd E3 = (-f3 * aq).exp(), E4 = (-2 * f4 * aq).exp();
      const Eigen::ArrayXd sech = 2 * E3 / (1 + E3.square());
      const Eigen::ArrayXd t4 = sg * (1 - E4) / (1 + E4);
      const Eigen::ArrayXd a = th[0] + th[1] * sech;
      n = w * a * t4;
      if (dn) {
        dn->col(0) = w * t4;
        dn->col(1) = w * sech * t4;
        if (th[2] > 1e-3) dn->col(2) = -w * th[1] * sech * (1 - E3.square()) / (1 + E3.square()) * aq * t4;
        if (th[3] > 1e-3) dn->col(3) = w * a * (1 - t4.square()) * qd;
      }
      break;
    }
    default:
      n.setZero(k);
  }
}

void TorqueObjective::residual_moments(const double* x, std::array<double, 6>& mean, std::array<double, 6>& var,
                                       Eigen::MatrixXd* d_mean, Eigen::MatrixXd* d_var) const {
  const int D = dimension();
  const bool grad = d_mean != nullptr && d_var != nullptr;
  if (grad) {
    d_mean->setZero(6, D);
    d_var->setZero(6, D);
  }
  const int L = kStandard + static_cast<int>(linear_.size());
  Eigen::VectorXd z(L);
  z.head<kStandard>() = Eigen::Map<const Eigen::Matrix<double, kStandard, 1>>(x);
  Eigen::ArrayXd n;
  Eigen::ArrayXXd dn;
  for (int j = 0; j < 6; ++j) {
    const Joint& J = joints_[j];
    const double* f = x + kStandard + kf_ * j;
    for (size_t i = 0; i < linear_.size(); ++i) z[kStandard + static_cast<Eigen::Index>(i)] = f[linear_[i]];
    const Eigen::VectorXd Gz = J.G * z;
    // Sum and sum of squares of the residual r = tau - A z - n(theta).
    double sse = z.dot(Gz) - 2 * J.h.dot(z) + J.tt;
    double sum = J.ts - J.a.dot(z);
    Eigen::VectorXd d_sse_z = 2 * (Gz - J.h), d_sum_z = -J.a;
    Eigen::VectorXd d_sse_th = Eigen::VectorXd::Zero(kf_), d_sum_th = Eigen::VectorXd::Zero(kf_);
    if (!is_linear(model_)) {
      const Eigen::Index k = reach(J, f);
      nonlinear_part(J, f, k, n, grad ? &dn : nullptr);
      const auto Ak = J.A_sorted.topRows(k);
      const Eigen::ArrayXd r = J.tau_sorted.head(k) - (Ak * z.tail(L - J.first)).array();
      sse += -2 * (n * r).sum() + n.square().sum();
      sum -= n.sum();
      if (grad) {
        d_sse_z.tail(L - J.first) += 2 * Ak.transpose() * n.matrix();
        d_sse_th = 2 * dn.matrix().transpose() * (n - r).matrix();
        d_sum_th = -dn.colwise().sum().transpose().matrix();
      }
    }
    mean[j] = sum / n_;
    var[j] = std::max(0.0, sse / n_ - mean[j] * mean[j]);
    if (!grad) continue;
    // d var = d sse / n - 2 mean d mean; map local (z, theta) onto x.
    auto put = [&](int col, double dsum, double dsse) {
      (*d_mean)(j, col) += dsum / n_;
      (*d_var)(j, col) += dsse / n_ - 2 * mean[j] * dsum / n_;
    };
    for (int i = 0; i < kStandard; ++i) put(i, d_sum_z[i], d_sse_z[i]);
    const int base = kStandard + kf_ * j;
    for (size_t i = 0; i < linear_.size(); ++i) {
      const Eigen::Index c = kStandard + static_cast<Eigen::Index>(i);
      put(base + linear_[i], d_sum_z[c], d_sse_z[c]);
    }
    for (int k = 0; k < kf_; ++k) put(base + k, d_sum_th[k], d_sse_th[k]);
  }
}

double TorqueObjective::eq25(const double* x, double k_e, double* grad) const {
  std::array<double, 6> mean{}, var{};
  Eigen::MatrixXd dm, dv;
  residual_moments(x, mean, var, grad ? &dm : nullptr, grad ? &dv : nullptr);
  if (grad) {
    Eigen::Map<Eigen::VectorXd> g(grad, dimension());
    g.setZero();
    for (int j = 0; j < 6; ++j) {
      const double sd = std::sqrt(var[j]);
      g += sgn(mean[j]) * dm.row(j).transpose();
      if (sd > 0) g += k_e / (2 * sd) * dv.row(j).transpose();
    }
  }
  return eq25_of(mean, var, k_e);
}

double TorqueObjective::least_squares(const double* x, double* grad) const {
  std::array<double, 6> mean{}, var{};
  Eigen::MatrixXd dm, dv;
  residual_moments(x, mean, var, grad ? &dm : nullptr, grad ? &dv : nullptr);
  if (grad) {
    Eigen::Map<Eigen::VectorXd> g(grad, dimension());
    g.setZero();
    for (int j = 0; j < 6; ++j) g += 2 * mean[j] * dm.row(j).transpose() + dv.row(j).transpose();
  }
  return least_squares_of(mean, var);
}

void TorqueObjective::amplitude_columns(const Joint& J, const double* th, Eigen::Index k, Eigen::ArrayXXd& D) const {
  const auto aq = J.aq_sorted.head(k), sg = J.sg_sorted.head(k);
  const double w = J.w;
  D.resize(k, kf_);
  switch (model_) {
    case FrictionModel::eq4: {  // (Fs - Fc) sgn exp(-(qd / qds)^2)
      const double qds = std::max(th[2], 1e-3);
      D.col(1) = w * sg * (-(aq / qds).square()).exp();
      D.col(0) = -D.col(1);
      break;
    }
    case FrictionModel::eq5: {  // -f2 sgn exp(-|qd| / f3) - f4 sgn exp(-1 / (f5 |qd|))
      const double f3 = std::max(th[2], 1e-3), f5 = std::max(th[4], 1e-3);
      D.col(1) = -(w * sg * (-aq / f3).exp());
      D.col(3) = -(w * sg * (-J.inv_aq_sorted.head(k) / f5).exp());
      break;
    }
    case FrictionModel::eq6: {  // (f1 + f2 sech(f3 qd)) tanh(f4 qd), by exponentials of -|x|
      const double f3 = std::max(th[2], 1e-3), f4 = std::max(th[3], 1e-3);
      const Eigen::ArrayXd E3 = (-f3 * aq).exp(), E4 = (-2 * f4 * aq).exp();
      D.col(0) = w * sg * (1 - E4) / (1 + E4);
      D.col(1) = D.col(0) * 2 * E3 / (1 + E3.square());
      break;
    }
    default:
      break;
  }
}

void TorqueObjective::fit_amplitudes(double* x, const double* lo, const double* hi, std::array<double, 6>* mean,
                                     std::array<double, 6>* var) const {
  AmplitudeScratch scratch;
  for (int j = 0; j < 6; ++j) {
    fit_joint_amplitudes(j, x, lo, hi, mean ? &(*mean)[j] : nullptr, var ? &(*var)[j] : nullptr, scratch);
  }
}

void TorqueObjective::fit_amplitudes(const std::vector<double*>& xs, const double* lo, const double* hi,
                                     std::vector<std::array<double, 6>>* mean,
                                     std::vector<std::array<double, 6>>* var) const {
  if (mean) mean->resize(xs.size());
  if (var) var->resize(xs.size());
  AmplitudeScratch scratch;
  // Joint-major: one joint's sorted rows (S x up to 60 doubles, about 1 MB at 2 000 samples) stay in
  // cache for every vector of the batch; each vector's arithmetic is the single call's.
  for (int j = 0; j < 6; ++j) {
    for (size_t i = 0; i < xs.size(); ++i) {
      fit_joint_amplitudes(j, xs[i], lo, hi, mean ? &(*mean)[i][j] : nullptr, var ? &(*var)[i][j] : nullptr, scratch);
    }
  }
}

void TorqueObjective::fit_joint_amplitudes(int j, double* x, const double* lo, const double* hi, double* mean,
                                           double* var, AmplitudeScratch& scratch) const {
  const Eigen::Map<const Eigen::Matrix<double, kStandard, 1>> phi(x);
  const int nl = static_cast<int>(linear_.size());
  const std::vector<int>& amp = amplitudes_;
  const std::vector<int>& col = amplitude_column_;
  const int na = static_cast<int>(amp.size());
  // At most 5 amplitudes per joint (friction_count): small fixed-capacity solves, no heap.
  using Small = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;
  using SmallVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, 6, 1>;
  Eigen::ArrayXXd& D = scratch.D;  // the amplitudes' nonlinear columns on the rows the nonlinear part reaches
  Eigen::VectorXd& r = scratch.r;  // there: the rigid-body residual
  const Joint& J = joints_[j];
  double* f = x + kStandard + kf_ * j;
  Small M = Small::Zero(na, na);
  SmallVector rhs = SmallVector::Zero(na);
  for (int a = 0; a < na; ++a) {
    const int ca = col[static_cast<size_t>(a)];
    if (ca < 0) continue;
    rhs[a] = J.h[ca] - J.G.row(ca).head<kStandard>().dot(phi);
    for (int b = 0; b < na; ++b) {
      if (col[static_cast<size_t>(b)] >= 0) M(a, b) = J.G(ca, col[static_cast<size_t>(b)]);
    }
  }
  Eigen::Index k = 0;
  if (!is_linear(model_)) {
    // The nonlinear columns d_a (independent of the amplitudes) add d_a . r to the right-hand side
    // and l_b . d_a + l_a . d_b + d_a . d_b to the normal matrix (l: the linear columns).
    k = reach(J, f);
    amplitude_columns(J, f, k, D);
    const auto Ak = J.A_sorted.topRows(k);
    r = J.tau_sorted.head(k).matrix() - Ak.leftCols(kStandard - J.first) * phi.tail(kStandard - J.first);
    for (const int a : nonlinear_amplitudes_) {
      const auto da = D.col(amp[static_cast<size_t>(a)]).matrix();
      rhs[a] += da.dot(r);
      for (int b = 0; b < na; ++b) {
        const int cb = col[static_cast<size_t>(b)];
        if (cb < 0) continue;
        const double lb_da = Ak.col(cb - J.first).dot(da);
        M(a, b) += lb_da;
        M(b, a) += lb_da;
      }
      for (const int b : nonlinear_amplitudes_) {
        if (b < a) continue;
        const double da_db = da.dot(D.col(amp[static_cast<size_t>(b)]).matrix());
        M(a, b) += da_db;
        if (b != a) M(b, a) += da_db;
      }
    }
  }
  SmallVector sol = M.completeOrthogonalDecomposition().solve(rhs);
  for (int a = 0; a < na; ++a) {
    const int i = kStandard + kf_ * j + amp[static_cast<size_t>(a)];
    if (lo) sol[a] = std::max(sol[a], lo[i]);
    if (hi) sol[a] = std::min(sol[a], hi[i]);
    f[amp[static_cast<size_t>(a)]] = sol[a];
  }
  if (!mean || !var) return;
  // The residual moments at the new amplitudes without another pass over the samples: the linear
  // columns from the reduced sums, the nonlinear part n = sum_a sol_a d_a (linear in the amplitudes).
  Eigen::VectorXd& z = scratch.z;
  z.resize(kStandard + nl);
  z.head<kStandard>() = phi;
  for (int i = 0; i < nl; ++i) z[kStandard + i] = f[linear_[static_cast<size_t>(i)]];
  double sse = z.dot(J.G * z) - 2 * J.h.dot(z) + J.tt, sum = J.ts - J.a.dot(z);
  if (!is_linear(model_)) {
    const auto Ak = J.A_sorted.topRows(k);
    Eigen::VectorXd& nk = scratch.n;
    Eigen::VectorXd& r_left = scratch.r_left;  // r less the linear columns' part
    nk.setZero(k);
    r_left = r;
    for (const int a : nonlinear_amplitudes_) nk += sol[a] * D.col(amp[static_cast<size_t>(a)]).matrix();
    for (int b = 0; b < na; ++b) {
      const int cb = col[static_cast<size_t>(b)];
      if (cb >= 0) r_left -= sol[b] * Ak.col(cb - J.first);
    }
    sse += -2 * nk.dot(r_left) + nk.squaredNorm();
    sum -= nk.sum();
  }
  *mean = sum / n_;
  *var = std::max(0.0, sse / n_ - *mean * *mean);
}

double TorqueObjective::eq25_of(const std::array<double, 6>& mean, const std::array<double, 6>& var, double k_e) {
  double J = 0;
  for (int j = 0; j < 6; ++j) J += std::fabs(mean[j]) + k_e * std::sqrt(var[j]);
  return J;
}

double TorqueObjective::least_squares_of(const std::array<double, 6>& mean, const std::array<double, 6>& var) {
  double J = 0;
  for (int j = 0; j < 6; ++j) J += mean[j] * mean[j] + var[j];
  return J;
}

std::array<double, 2> velocity_scale_range(const RunData& d, int j) {
  return velocity_scale_range(d.qd.col(j).cwiseAbs().maxCoeff());
}

SearchRanges search_ranges(const RunData& d, FrictionModel model, const Eigen::VectorXd& cad, double width) {
  if (cad.size() != kStandard || !(width >= 0)) throw InputError("search ranges: 60 CAD values and a width >= 0");
  const int kf = friction_count(model);
  const std::vector<std::string> names = friction_parameter_names(model);
  SearchRanges r;
  r.lo.resize(kStandard + 6 * kf);
  r.hi.resize(kStandard + 6 * kf);
  for (int i = 0; i < kStandard; ++i) {
    const double a = cad[i] * (1 - width), b = cad[i] * (1 + width);
    r.lo[i] = std::min(a, b);
    r.hi[i] = std::max(a, b);
  }
  for (int j = 0; j < 6; ++j) {
    const double tau = d.tau.col(j).cwiseAbs().maxCoeff(), qd = d.qd.col(j).cwiseAbs().maxCoeff();
    const auto v = velocity_scale_range(d, j);
    for (int k = 0; k < kf; ++k) {
      const int i = kStandard + kf * j + k;
      const std::string& n = names[static_cast<size_t>(k)];
      double lo = 0, hi = tau;  // Fc, Fs, f1
      if (n == "beta") {
        hi = qd > 0 ? tau / qd : 0.0;
      } else if (n == "fp") {
        hi = qd > 0 ? tau / std::cbrt(qd) : 0.0;
        lo = -hi;
      } else if (n == "fl") {
        hi = 1.0;
      } else if (is_scale_parameter(model, k)) {
        const auto range = scale_parameter_range(model, k, v);
        lo = range[0];
        hi = range[1];
      } else if (n != "Fc" && n != "Fs" && n != "f1") {
        lo = -tau;  // f2, f4 of Eq. 5; f2 of Eq. 6
      }
      r.lo[i] = lo;
      r.hi[i] = hi;
    }
  }
  return r;
}

std::vector<double> friction_start(const RunData& d, FrictionModel model, const Eigen::VectorXd& phi,
                                   std::vector<std::vector<ScaleInterval>>* intervals) {
  const Eigen::Index S = d.q.rows();
  const auto Y = standard_rows(d);
  Eigen::MatrixXd residual(S, 6);
  for (Eigen::Index s = 0; s < S; ++s) {
    residual.row(s) = d.tau.row(s) - (Y[static_cast<size_t>(s)] * phi.head(kStandard)).transpose();
  }
  const int kf = friction_count(model);
  const SearchRanges ranges = search_ranges(d, model, Eigen::VectorXd::Zero(kStandard), 0.0);
  std::vector<double> out(static_cast<size_t>(6 * kf), 0.0);
  if (intervals) intervals->resize(6);
  for (int j = 0; j < 6; ++j) {
    const std::vector<double> th =
        fit_joint_friction(model, d.qd.col(j), d.tau_load.col(j), residual.col(j), velocity_scale_range(d, j),
                           intervals ? &(*intervals)[static_cast<size_t>(j)] : nullptr);
    const int b = kStandard + kf * j;
    for (int k = 0; k < kf; ++k) {
      out[static_cast<size_t>(kf * j + k)] = std::clamp(th[static_cast<size_t>(k)], ranges.lo[b + k], ranges.hi[b + k]);
    }
  }
  return out;
}

double feasibility_violation(const double* x, const Eigen::VectorXd& cad, std::array<double, 6>* lambda_min) {
  double v = 0;
  for (int l = 0; l < kLinks; ++l) {
    const double lam = pseudo_inertia_min_eigenvalue(x + 10 * l, nullptr);
    if (lambda_min) (*lambda_min)[l] = lam;
    if (lam < 0) v += -lam / std::max(pseudo_inertia(cad.data() + 10 * l).norm(), 1e-12);
  }
  return v;
}

}  // namespace dyncal::host
