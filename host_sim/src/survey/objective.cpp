#include "dyncal_host/survey/objective.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "dyncal_host/input_error.hpp"
#include "dyncal_host/survey/standard_parameters.hpp"
#include "er20/robot.hpp"

namespace dyncal::host::survey {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Vec6 = Eigen::Matrix<double, 6, 1>;
constexpr int kLocal = kStandard + 2;  // [phi | Fc_j | beta_j]
/// exp(-(|qd| / qds)^2) < 1e-18 beyond |qd| = 6.5 qds: those rows carry no Stribeck term.
constexpr double kStribeckReach = 6.5;

double sgn(double v) {
  return v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0);
}

}  // namespace

TorqueObjective::TorqueObjective(const SurveyData& d, FrictionModel model, const std::array<double, 6>& sigma)
    : model_(model) {
  if (model != FrictionModel::eq7 && model != FrictionModel::eq4) {
    throw InputError("the optimisation objective takes Eq. 7 or Eq. 4 friction");
  }
  kf_ = model == FrictionModel::eq4 ? 4 : 2;
  const Eigen::Index S = d.q.rows();
  if (S < 1) throw InputError("the optimisation objective needs samples");
  n_ = static_cast<double>(S);
  std::array<Eigen::MatrixXd, 6> A;
  for (auto& a : A) a.resize(S, kLocal);
  Eigen::Matrix<double, 6, kStandard> Ys;
  for (Eigen::Index s = 0; s < S; ++s) {
    Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                              Vec6(d.qdd.row(s).transpose()), Ys);
    for (int j = 0; j < 6; ++j) {
      const double w = 1.0 / sigma[j];
      A[j].row(s).head<kStandard>() = w * Ys.row(j);
      A[j](s, kStandard) = w * sgn(d.qd(s, j));
      A[j](s, kStandard + 1) = w * d.qd(s, j);
    }
  }
  for (int j = 0; j < 6; ++j) {
    Joint& J = joints_[j];
    const Eigen::VectorXd tau = d.tau.col(j) / sigma[j];
    J.G = A[j].transpose() * A[j];
    J.h = A[j].transpose() * tau;
    J.a = A[j].colwise().sum().transpose();
    J.w = 1.0 / sigma[j];
    J.tt = tau.squaredNorm();
    J.ts = tau.sum();
    if (model == FrictionModel::eq4) {
      std::vector<Eigen::Index> order(static_cast<size_t>(S));
      std::iota(order.begin(), order.end(), Eigen::Index{0});
      std::stable_sort(order.begin(), order.end(),
                       [&](Eigen::Index a, Eigen::Index b) { return std::fabs(d.qd(a, j)) < std::fabs(d.qd(b, j)); });
      J.A_sorted.resize(S, kLocal);
      J.tau_sorted.resize(S);
      J.qd_sorted.resize(S);
      for (Eigen::Index k = 0; k < S; ++k) {
        const Eigen::Index s = order[static_cast<size_t>(k)];
        J.A_sorted.row(k) = A[j].row(s);
        J.tau_sorted[k] = tau[s];
        J.qd_sorted[k] = d.qd(s, j);
      }
    }
  }
}

int TorqueObjective::dimension() const {
  return kStandard + 6 * kf_;
}

void TorqueObjective::residual_moments(const double* x, std::array<double, 6>& mean, std::array<double, 6>& var,
                                       Eigen::MatrixXd* d_mean, Eigen::MatrixXd* d_var) const {
  const int D = dimension();
  const bool grad = d_mean != nullptr && d_var != nullptr;
  if (grad) {
    d_mean->setZero(6, D);
    d_var->setZero(6, D);
  }
  Eigen::Matrix<double, kLocal, 1> z;
  z.head<kStandard>() = Eigen::Map<const Eigen::Matrix<double, kStandard, 1>>(x);
  for (int j = 0; j < 6; ++j) {
    const Joint& J = joints_[j];
    const double* f = x + kStandard + kf_ * j;
    z[kStandard] = f[0];
    z[kStandard + 1] = f[kf_ - 1];  // beta is last in both models
    const Eigen::Matrix<double, kLocal, 1> Gz = J.G * z;
    // Sum and sum of squares of the residual r = tau - A z - c s(qds).
    double sse = z.dot(Gz) - 2 * J.h.dot(z) + J.tt;
    double sum = J.ts - J.a.dot(z);
    Eigen::Matrix<double, kLocal, 1> d_sse_z = 2 * (Gz - J.h), d_sum_z = -J.a;
    double d_sse_c = 0, d_sse_qds = 0, d_sum_c = 0, d_sum_qds = 0;
    if (model_ == FrictionModel::eq4) {
      const double c = f[1] - f[0], qds = std::max(f[2], 1e-3);
      // Only rows with |qd| < 6.5 qds carry the Stribeck term (rows sorted by |qd|).
      Eigen::Index k = 0;
      const Eigen::Index S = J.qd_sorted.size();
      while (k < S && std::fabs(J.qd_sorted[k]) < kStribeckReach * qds) ++k;
      Eigen::VectorXd s(k), sp(k);  // s = sgn exp(-(qd/qds)^2) / sigma_j, sp = ds/dqds
      for (Eigen::Index i = 0; i < k; ++i) {
        const double v = J.qd_sorted[i], u = v / qds;
        s[i] = J.w * sgn(v) * std::exp(-u * u);
        sp[i] = s[i] * 2 * u * u / qds;
      }
      const auto Ak = J.A_sorted.topRows(k);
      const auto tk = J.tau_sorted.head(k);
      const Eigen::Matrix<double, kLocal, 1> As = Ak.transpose() * s;
      const double st = s.dot(tk), ss = s.squaredNorm(), s_sum = s.sum();
      const double sr = st - As.dot(z);  // s^T (tau - A z)
      sse += -2 * c * sr + c * c * ss;
      sum -= c * s_sum;
      if (grad) {
        const Eigen::Matrix<double, kLocal, 1> Asp = Ak.transpose() * sp;
        d_sse_z += 2 * c * As;
        d_sse_c = -2 * sr + 2 * c * ss;
        d_sse_qds = -2 * c * (sp.dot(tk) - Asp.dot(z)) + 2 * c * c * sp.dot(s);
        d_sum_c = -s_sum;
        d_sum_qds = -c * sp.sum();
      }
    }
    mean[j] = sum / n_;
    var[j] = std::max(0.0, sse / n_ - mean[j] * mean[j]);
    if (!grad) continue;
    // d var = d sse / n - 2 mean d mean; map local (z, c, qds) onto x.
    auto put = [&](int col, double dsum, double dsse) {
      (*d_mean)(j, col) += dsum / n_;
      (*d_var)(j, col) += dsse / n_ - 2 * mean[j] * dsum / n_;
    };
    for (int i = 0; i < kStandard; ++i) put(i, d_sum_z[i], d_sse_z[i]);
    const int base = kStandard + kf_ * j;
    put(base, d_sum_z[kStandard], d_sse_z[kStandard]);                    // Fc (Eq. 7 column)
    put(base + kf_ - 1, d_sum_z[kStandard + 1], d_sse_z[kStandard + 1]);  // beta
    if (model_ == FrictionModel::eq4) {
      put(base, -d_sum_c, -d_sse_c);  // c = Fs - Fc
      put(base + 1, d_sum_c, d_sse_c);
      put(base + 2, f[2] > 1e-3 ? d_sum_qds : 0.0, f[2] > 1e-3 ? d_sse_qds : 0.0);
    }
  }
}

double TorqueObjective::eq25(const double* x, double k_e, double* grad) const {
  std::array<double, 6> mean{}, var{};
  Eigen::MatrixXd dm, dv;
  residual_moments(x, mean, var, grad ? &dm : nullptr, grad ? &dv : nullptr);
  double J = 0;
  Eigen::Map<Eigen::VectorXd> g(grad, grad ? dimension() : 0);
  if (grad) g.setZero();
  for (int j = 0; j < 6; ++j) {
    const double sd = std::sqrt(var[j]);
    J += std::fabs(mean[j]) + k_e * sd;
    if (grad) {
      g += sgn(mean[j]) * dm.row(j).transpose();
      if (sd > 0) g += k_e / (2 * sd) * dv.row(j).transpose();
    }
  }
  return J;
}

double TorqueObjective::least_squares(const double* x, double* grad) const {
  std::array<double, 6> mean{}, var{};
  Eigen::MatrixXd dm, dv;
  residual_moments(x, mean, var, grad ? &dm : nullptr, grad ? &dv : nullptr);
  double J = 0;
  Eigen::Map<Eigen::VectorXd> g(grad, grad ? dimension() : 0);
  if (grad) g.setZero();
  for (int j = 0; j < 6; ++j) {
    J += mean[j] * mean[j] + var[j];
    if (grad) g += 2 * mean[j] * dm.row(j).transpose() + dv.row(j).transpose();
  }
  return J;
}

SearchRanges search_ranges(const SurveyData& d, FrictionModel model, const Eigen::VectorXd& cad, double width) {
  if (cad.size() != kStandard || !(width >= 0)) throw InputError("search ranges: 60 CAD values and a width >= 0");
  const int kf = model == FrictionModel::eq4 ? 4 : 2;
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
    const double beta = qd > 0 ? tau / qd : 0.0;
    const int b = kStandard + kf * j;
    r.lo.segment(b, kf).setZero();
    r.hi[b] = tau;
    r.hi[b + kf - 1] = beta;
    if (kf == 4) {
      r.hi[b + 1] = tau;
      const auto qds = stribeck_velocity_range(d, j);
      r.lo[b + 2] = qds[0];
      r.hi[b + 2] = qds[1];
    }
  }
  return r;
}

std::array<double, 2> stribeck_velocity_range(const SurveyData& d, int j) {
  const double qd = d.qd.col(j).cwiseAbs().maxCoeff();
  const double lo = std::max(1e-3, 0.01 * qd);
  return {lo, std::max(lo, qd)};
}

std::vector<double> stribeck_start(const SurveyData& d, const Eigen::VectorXd& phi) {
  const Eigen::Index S = d.q.rows();
  Eigen::MatrixXd residual(S, 6);
  Eigen::Matrix<double, 6, kStandard> Ys;
  for (Eigen::Index s = 0; s < S; ++s) {
    Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                              Vec6(d.qdd.row(s).transpose()), Ys);
    residual.row(s) = d.tau.row(s) - (Ys * phi.head(kStandard)).transpose();
  }
  constexpr int kScan = 64;
  std::vector<double> out(24, 0.0);
  for (int j = 0; j < 6; ++j) {
    const auto range = stribeck_velocity_range(d, j);
    double best = INFINITY;
    Eigen::MatrixXd A(S, 3);
    for (int k = 0; k < kScan; ++k) {
      const double qds = range[0] * std::pow(range[1] / range[0], k / (kScan - 1.0));
      for (Eigen::Index s = 0; s < S; ++s) {
        const double v = d.qd(s, j), u = v / qds;
        A.row(s) << sgn(v), sgn(v) * std::exp(-u * u), v;
      }
      const Eigen::Vector3d p = A.colPivHouseholderQr().solve(residual.col(j));
      const double sse = (A * p - residual.col(j)).squaredNorm();
      if (sse < best) {
        best = sse;
        out[4 * j] = std::max(p[0], 0.0);
        out[4 * j + 1] = std::max(p[0] + p[1], 0.0);
        out[4 * j + 2] = qds;
        out[4 * j + 3] = std::max(p[2], 0.0);
      }
    }
  }
  return out;
}

double pseudo_inertia_min_eigenvalue(const double* phi10, double* gradient10) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(pseudo_inertia(phi10));
  if (gradient10) {
    const Eigen::Vector4d v = es.eigenvectors().col(0);
    for (int k = 0; k < 10; ++k) {
      double e[10] = {};
      e[k] = 1.0;
      gradient10[k] = v.dot(pseudo_inertia(e) * v);  // J is linear in phi
    }
  }
  return es.eigenvalues()[0];
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

}  // namespace dyncal::host::survey
