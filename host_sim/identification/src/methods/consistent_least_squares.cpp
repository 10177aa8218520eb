#include "dyncal_host/identification/methods/consistent_least_squares.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/log_cholesky.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace {

using Mat10 = Eigen::Matrix<double, 10, 10>;

/// r = [(R [K phi(theta); x(y)] - z) / sqrt(sigma2) ; (phi(theta) - prior) / s ; 0] (or the prior's
/// rows W (phi(theta) - prior) with ConsistentProblem::prior_whitening W) over
/// v = [theta (10 L) | y (P - num_base)], x_i = y_i^2 for the non-negative parameters, y_i otherwise.
/// Without a prior there are fewer data rows (P) than unknowns (10 L + P - num_base), which Eigen's
/// Levenberg-Marquardt refuses: zero rows pad r to the unknowns' count (they change nothing).
struct Residuals : Eigen::DenseFunctor<double> {
  const ConsistentProblem& p;
  Eigen::MatrixXd RK;  // R's base columns times K: P x 10 L
  Eigen::VectorXd inv_s;
  int L = 0, nx = 0;
  bool with_prior = false;
  double wd = 1;              // 1 / sqrt(sigma2): the data rows in units of their effective noise
  std::vector<char> squared;  // per x: held >= 0 as y^2

  Residuals(const ConsistentProblem& problem, int links, const Eigen::VectorXd& inv_std, bool prior)
      : Eigen::DenseFunctor<double>(10 * links + static_cast<int>(problem.R.cols()) - problem.num_base,
                                    std::max(static_cast<int>(problem.R.rows()) + (prior ? 10 * links : 0),
                                             10 * links + static_cast<int>(problem.R.cols()) - problem.num_base)),
        p(problem),
        inv_s(inv_std),
        L(links),
        nx(static_cast<int>(problem.R.cols()) - problem.num_base),
        with_prior(prior) {
    RK = p.R.leftCols(p.num_base) * p.K;
    wd = 1.0 / std::sqrt(p.sigma2);
    squared.assign(static_cast<size_t>(nx), 0);
    for (int i : p.nonnegative) squared[static_cast<size_t>(i - p.num_base)] = 1;
  }

  /// The model's non-inertial parameters x of v's tail y.
  Eigen::VectorXd x_of(const Eigen::VectorXd& v) const {
    Eigen::VectorXd x = v.tail(nx);
    for (int i = 0; i < nx; ++i)
      if (squared[static_cast<size_t>(i)]) x[i] *= x[i];
    return x;
  }

  Eigen::VectorXd standard(const Eigen::VectorXd& v, std::vector<Mat10>* jac = nullptr) const {
    Eigen::VectorXd phi(10 * L);
    if (jac) jac->resize(static_cast<size_t>(L));
    for (int l = 0; l < L; ++l)
      standard_from_theta(v.data() + 10 * l, phi.data() + 10 * l, jac ? &(*jac)[static_cast<size_t>(l)] : nullptr);
    return phi;
  }

  int operator()(const Eigen::VectorXd& v, Eigen::VectorXd& r) const {
    const Eigen::VectorXd phi = standard(v);
    const Eigen::Index n = p.R.rows();
    r.head(n) = RK * phi - p.z;
    if (nx > 0) r.head(n) += p.R.rightCols(nx) * x_of(v);
    r.head(n) *= wd;
    if (with_prior && p.prior_whitening.size() > 0) {
      r.segment(n, 10 * L).noalias() = p.prior_whitening * (phi - p.prior);
    } else if (with_prior) {
      r.segment(n, 10 * L) = (phi - p.prior).cwiseProduct(inv_s);
    }
    r.tail(r.size() - n - (with_prior ? 10 * L : 0)).setZero();
    return 0;
  }

  int df(const Eigen::VectorXd& v, Eigen::MatrixXd& J) const {
    J.setZero();
    std::vector<Mat10> jac;
    standard(v, &jac);
    const Eigen::Index n = p.R.rows();
    for (int l = 0; l < L; ++l) {
      const Mat10& d = jac[static_cast<size_t>(l)];
      J.block(0, 10 * l, n, 10) = wd * RK.middleCols(10 * l, 10) * d;
      if (with_prior && p.prior_whitening.size() > 0) {
        J.block(n + 10 * l, 10 * l, 10, 10).noalias() = p.prior_whitening.block<10, 10>(10 * l, 10 * l) * d;
      } else if (with_prior) {
        J.block(n + 10 * l, 10 * l, 10, 10) = inv_s.segment(10 * l, 10).asDiagonal() * d;
      }
    }
    for (int i = 0; i < nx; ++i) {
      const double dx = squared[static_cast<size_t>(i)] ? 2.0 * v[10 * L + i] : 1.0;
      J.block(0, 10 * L + i, n, 1) = (wd * dx) * p.R.col(p.num_base + i);
    }
    return 0;
  }
};

}  // namespace

Eigen::VectorXd prior_std(const Eigen::VectorXd& nominal, double relative_std) {
  const int L = static_cast<int>(nominal.size() / 10);
  const int kinds[3][2] = {{0, 6}, {6, 9}, {9, 10}};  // inertia, first moment, mass
  double robot_max[3] = {0, 0, 0};
  for (int l = 0; l < L; ++l)
    for (int k = 0; k < 3; ++k)
      for (int i = kinds[k][0]; i < kinds[k][1]; ++i)
        robot_max[k] = std::max(robot_max[k], std::abs(nominal[10 * l + i]));
  Eigen::VectorXd s(nominal.size());
  for (int l = 0; l < L; ++l) {
    for (int k = 0; k < 3; ++k) {
      double m = 0;
      for (int i = kinds[k][0]; i < kinds[k][1]; ++i) m = std::max(m, std::abs(nominal[10 * l + i]));
      if (m == 0) m = robot_max[k] > 0 ? robot_max[k] : 1.0;
      for (int i = kinds[k][0]; i < kinds[k][1]; ++i)
        s[10 * l + i] = relative_std * std::max(std::abs(nominal[10 * l + i]), 0.05 * m);
    }
  }
  return s;
}

std::vector<int> nonnegative_terms(const std::vector<std::string>& names, int num_base) {
  std::vector<int> out;
  for (size_t i = static_cast<size_t>(num_base); i < names.size(); ++i) {
    const std::string& n = names[i];
    const bool kind = n.rfind("Fc", 0) == 0 || n.rfind("Fv", 0) == 0 || n.rfind("Ia", 0) == 0;
    if (kind && n.size() > 2 && std::all_of(n.begin() + 2, n.end(), [](char c) { return c >= '0' && c <= '9'; }))
      out.push_back(static_cast<int>(i));
  }
  return out;
}

void consistent_covariance(ConsistentSolution& s, double inflation) {
  if (s.information_data.size() == 0) return;
  const Eigen::MatrixXd Hinv =
      (s.information_data + s.information_prior).completeOrthogonalDecomposition().pseudoInverse();
  const Eigen::MatrixXd cov = Hinv * (inflation * s.information_data + s.information_prior) * Hinv;
  s.params_std = (s.model_jacobian * cov * s.model_jacobian.transpose()).diagonal().cwiseMax(0.0).cwiseSqrt();
  s.standard_cov = s.standard_jacobian * cov * s.standard_jacobian.transpose();
  s.inflation = inflation;
}

ConsistentSolution consistent_least_squares(const ConsistentProblem& p) {
  const int L = static_cast<int>(p.K.cols() / 10);
  const Eigen::Index P = p.R.cols();
  const int nx = static_cast<int>(P) - p.num_base;
  const bool whitened = p.prior_whitening.size() > 0;
  if (whitened && (p.prior_whitening.rows() != 10 * L || p.prior_whitening.cols() != 10 * L))
    throw InputError("physically consistent LS: the prior's whitening is not 10 L x 10 L");
  Eigen::VectorXd inv_s;
  if (!whitened && p.prior_relative_std > 0) inv_s = prior_std(p.prior, p.prior_relative_std).cwiseInverse();
  Residuals f(p, L, inv_s, whitened || inv_s.size() > 0);
  // Start: the nominal inertials projected onto the consistent set, the other parameters from `start`.
  Eigen::VectorXd v = Eigen::VectorXd::Zero(10 * L + nx);
  for (int l = 0; l < L; ++l) theta_from_pseudo_inertia(pseudo_inertia(p.prior.data() + 10 * l), v.data() + 10 * l);
  if (nx > 0 && p.start.size() == P) v.tail(nx) = p.start.tail(nx);
  // A non-negative parameter starts at the root of its start's magnitude (0 would stall: dx/dy = 0).
  for (int i = 0; i < nx; ++i)
    if (f.squared[static_cast<size_t>(i)]) v[10 * L + i] = std::sqrt(std::abs(v[10 * L + i]));
  Eigen::LevenbergMarquardt<Residuals> lm(f);
  lm.setMaxfev(p.max_evaluations);
  lm.setFtol(p.relative_tolerance);
  lm.setXtol(p.relative_tolerance);
  const auto status = lm.minimize(v);
  if (status == Eigen::LevenbergMarquardtSpace::ImproperInputParameters || !v.allFinite())
    throw InputError("physically consistent LS: Levenberg-Marquardt failed (status " + std::to_string(status) + ")");
  ConsistentSolution s;
  s.iterations = static_cast<int>(lm.iterations());
  s.theta = v.head(10 * L);
  std::vector<Mat10> jac;
  s.standard = f.standard(v, &jac);
  s.params.resize(P);
  s.params.head(p.num_base) = p.K * s.standard;
  if (nx > 0) s.params.tail(nx) = f.x_of(v);
  for (int l = 0; l < L; ++l) s.min_eigenvalue.push_back(theta_min_eigenvalue(v.data() + 10 * l));
  if (f.with_prior)
    for (int l = 0; l < L; ++l) s.prior_mass.push_back(p.prior[10 * l + 9]);
  // Covariance of v from the Gauss-Newton matrix (data rows already in units of sigma2, prior as
  // is), propagated to the model parameters p = G v, G = [K dphi/dtheta, 0; 0, dx/dy].
  Eigen::MatrixXd J(f.values(), f.inputs());
  f.df(v, J);
  const Eigen::Index n = p.R.rows();
  s.information_data = J.topRows(n).transpose() * J.topRows(n);
  s.information_prior = Eigen::MatrixXd::Zero(f.inputs(), f.inputs());
  if (f.with_prior) s.information_prior = J.middleRows(n, 10 * L).transpose() * J.middleRows(n, 10 * L);
  s.model_jacobian = Eigen::MatrixXd::Zero(P, f.inputs());
  for (int l = 0; l < L; ++l)
    s.model_jacobian.block(0, 10 * l, p.num_base, 10) = p.K.middleCols(10 * l, 10) * jac[static_cast<size_t>(l)];
  for (int i = 0; i < nx; ++i)
    s.model_jacobian(p.num_base + i, 10 * L + i) = f.squared[static_cast<size_t>(i)] ? 2.0 * v[10 * L + i] : 1.0;
  s.standard_jacobian = Eigen::MatrixXd::Zero(10 * L, f.inputs());  // d standard / d v
  for (int l = 0; l < L; ++l) s.standard_jacobian.block(10 * l, 10 * l, 10, 10) = jac[static_cast<size_t>(l)];
  consistent_covariance(s, 1.0);
  return s;
}

}  // namespace dyncal::host
