#include "dyncal_host/survey/physically_consistent.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <unsupported/Eigen/LevenbergMarquardt>

#include "dyncal/nonlinear_friction.hpp"
#include "dyncal_host/input_error.hpp"
#include "dyncal_host/survey/objective.hpp"
#include "dyncal_host/survey/standard_parameters.hpp"
#include "er20/robot.hpp"

namespace dyncal::host::survey {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Vec6 = Eigen::Matrix<double, 6, 1>;

/// L (lower triangular, diagonal exp(theta[0..3]), below-diagonal theta[4..9] row by row).
Eigen::Matrix4d cholesky_factor(const double* th) {
  Eigen::Matrix4d L = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 4; ++i) L(i, i) = std::exp(th[i]);
  L(1, 0) = th[4];
  L(2, 0) = th[5];
  L(2, 1) = th[6];
  L(3, 0) = th[7];
  L(3, 1) = th[8];
  L(3, 2) = th[9];
  return L;
}
constexpr int kOffRow[6] = {1, 2, 2, 3, 3, 3};
constexpr int kOffCol[6] = {0, 0, 1, 0, 1, 2};

/// theta of the nearest positive definite pseudo-inertia to J.
void theta_from_pseudo_inertia(const Eigen::Matrix4d& J, double* th) {
  const Eigen::Matrix4d L = nearest_positive_definite(J).llt().matrixL();
  for (int i = 0; i < 4; ++i) th[i] = std::log(L(i, i));
  for (int k = 0; k < 6; ++k) th[4 + k] = L(kOffRow[k], kOffCol[k]);
}

constexpr int kLinkParams = 10;
constexpr int kInertial = kLinks * kLinkParams;

/// Standard parameters of link `link` from its log-Cholesky theta, and d phi / d theta (10 x 10).
void standard_from_theta(const double* x, Eigen::VectorXd& phi, Eigen::Matrix<double, kLinkParams, kLinkParams>* jac,
                         int link) {
  const double* th = x + kLinkParams * link;
  const Eigen::Matrix4d L = cholesky_factor(th);
  standard_from_pseudo_inertia(L * L.transpose(), phi.data() + kLinkParams * link);
  if (!jac) return;
  for (int k = 0; k < kLinkParams; ++k) {
    Eigen::Matrix4d E = Eigen::Matrix4d::Zero();
    if (k < 4) {
      E(k, k) = L(k, k);
    } else {
      E(kOffRow[k - 4], kOffCol[k - 4]) = 1.0;
    }
    const Eigen::Matrix4d dJ = E * L.transpose() + L * E.transpose();
    double col[kLinkParams];
    standard_from_pseudo_inertia(dJ, col);
    for (int i = 0; i < kLinkParams; ++i) (*jac)(i, k) = col[i];
  }
}

/// Residuals r = [A [phi(theta_L); F] + w f(theta_F, qd) - b ; prior_w (phi - prior)] over
/// x = [theta_L (60) | friction]. Linear friction (Eq. 7): F = (Fc, beta) per joint are columns of
/// A, and A, b can be compressed to their QR factor. Nonlinear friction (Eq. 4): one row per joint
/// sample with its velocity and weight; qds enters as log(qds) (positive by construction).
struct Residuals : Eigen::DenseFunctor<double> {
  FrictionModel model = FrictionModel::eq7;
  int kf = 2;                      // friction parameters per joint
  Eigen::MatrixXd A;               // rows x (60 [+ 12 linear friction]), scaled by 1 / sigma_j
  Eigen::VectorXd b;               // scaled torques
  Eigen::VectorXd qd, w;           // Eq. 4 only: velocity and 1 / sigma of each row (joint = row % 6)
  Eigen::VectorXd prior, prior_w;  // prior mean, 1 / s_i (0: no prior term)

  Residuals(int inputs, int values) : Eigen::DenseFunctor<double>(inputs, values) {}

  bool nonlinear() const { return model == FrictionModel::eq4; }

  /// Friction parameters of joint j in model form (qds from its log).
  void friction_of(const double* xf, double* th) const {
    for (int k = 0; k < kf; ++k) th[k] = xf[k];
    if (nonlinear()) th[2] = std::exp(xf[2]);
  }

  Eigen::VectorXd standard(const InputType& x) const {
    Eigen::VectorXd phi(kStandard);
    for (int l = 0; l < kLinks; ++l) standard_from_theta(x.data(), phi, nullptr, l);
    return phi;
  }

  int operator()(const InputType& x, ValueType& r) const {
    const Eigen::VectorXd phi = standard(x);
    const Eigen::Index n = b.size();
    r.head(n) = A.leftCols(kStandard) * phi - b;
    if (!nonlinear()) {
      r.head(n) += A.rightCols(A.cols() - kStandard) * x.tail(x.size() - kInertial);
    } else {
      for (Eigen::Index i = 0; i < n; ++i) {
        double th[4];
        friction_of(x.data() + kInertial + kf * (i % 6), th);
        r[i] += w[i] * NonlinearFriction<NonlinearFrictionModel::eq4>::torque(th, qd[i], static_cast<double*>(nullptr));
      }
    }
    r.tail(kStandard) = prior_w.cwiseProduct(phi - prior);
    return 0;
  }

  int df(const InputType& x, JacobianType& J) const {
    J.setZero();
    Eigen::VectorXd phi(kStandard);
    const Eigen::Index n = b.size();
    for (int l = 0; l < kLinks; ++l) {
      Eigen::Matrix<double, kLinkParams, kLinkParams> jac;
      standard_from_theta(x.data(), phi, &jac, l);
      J.block(0, kLinkParams * l, n, kLinkParams).noalias() = A.middleCols(kLinkParams * l, kLinkParams) * jac;
      J.block(n + kLinkParams * l, kLinkParams * l, kLinkParams, kLinkParams) =
          prior_w.segment<kLinkParams>(kLinkParams * l).asDiagonal() * jac;
    }
    if (!nonlinear()) {
      J.block(0, kInertial, n, A.cols() - kStandard) = A.rightCols(A.cols() - kStandard);
      return 0;
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      const int j = static_cast<int>(i % 6);
      double th[4], jf[4] = {0, 0, 0, 0};
      friction_of(x.data() + kInertial + kf * j, th);
      NonlinearFriction<NonlinearFrictionModel::eq4>::torque(th, qd[i], jf);
      jf[2] *= th[2];  // d / d log(qds)
      for (int k = 0; k < kf; ++k) J(i, kInertial + kf * j + k) = w[i] * jf[k];
    }
    return 0;
  }
};

/// Prior weights 1 / s_i, s_i = relative_std * max(|prior_i|, 5 % of the largest prior of the same
/// kind in the link), so that a zero CAD value (a centred mass) still has a finite scale.
Eigen::VectorXd prior_weights(const Eigen::VectorXd& prior, double relative_std) {
  Eigen::VectorXd pw(kStandard);
  for (int l = 0; l < kLinks; ++l) {
    const auto kind = [&](int from, int to) {
      double m = 0;
      for (int i = from; i < to; ++i) m = std::max(m, std::fabs(prior[kLinkParams * l + i]));
      for (int i = from; i < to; ++i) {
        const double s = relative_std * std::max(std::fabs(prior[kLinkParams * l + i]), 0.05 * m);
        pw[kLinkParams * l + i] = s > 0 ? 1.0 / s : 0.0;
      }
    };
    kind(0, 6);   // inertia
    kind(6, 9);   // first moments
    kind(9, 10);  // mass
  }
  return pw;
}

/// Levenberg-Marquardt from x; returns the iterations. Throws InputError on failure.
int solve(Residuals& p, Eigen::VectorXd& x, const ConsistentSettings& options) {
  Eigen::LevenbergMarquardt<Residuals> lm(p);
  lm.setMaxfev(options.max_evaluations);
  lm.setFtol(options.relative_tolerance);
  lm.setXtol(options.relative_tolerance);
  const Eigen::LevenbergMarquardtSpace::Status res = lm.minimize(x);
  if (res == Eigen::LevenbergMarquardtSpace::ImproperInputParameters || !x.allFinite()) {
    throw InputError("physically consistent LS: Levenberg-Marquardt failed (status " + std::to_string(res) + ")");
  }
  return static_cast<int>(lm.iterations());
}

}  // namespace

std::array<double, 6> pseudo_inertia_min_eigenvalues(const Eigen::VectorXd& phi) {
  std::array<double, 6> out{};
  for (int l = 0; l < kLinks; ++l) {
    out[l] = Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(pseudo_inertia(phi.data() + kLinkParams * l))
                 .eigenvalues()
                 .minCoeff();
  }
  return out;
}

Estimate physically_consistent_ls(const SurveyData& d, FrictionModel model, const MethodSettings& settings,
                                  const ConsistentSettings& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::Index S = d.q.rows();
  const int kf = static_cast<int>(friction_parameter_names(model).size());
  // Weighted standard regressor with the Eq. 7 friction columns (Fc, beta per joint).
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * S, kStandard + 12);
  Eigen::VectorXd b(6 * S), qd(6 * S), w(6 * S);
  Eigen::Matrix<double, 6, kStandard> Ys;
  for (Eigen::Index s = 0; s < S; ++s) {
    Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                              Vec6(d.qdd.row(s).transpose()), Ys);
    for (int j = 0; j < 6; ++j) {
      const Eigen::Index i = 6 * s + j;
      w[i] = 1.0 / settings.sigma[j];
      qd[i] = d.qd(s, j);
      A.row(i).head<kStandard>() = w[i] * Ys.row(j);
      A(i, kStandard + 2 * j) = w[i] * (qd[i] > 0 ? 1.0 : (qd[i] < 0 ? -1.0 : 0.0));
      A(i, kStandard + 2 * j + 1) = w[i] * qd[i];
      b[i] = w[i] * d.tau(s, j);
    }
  }
  const Eigen::VectorXd prior_w = prior_weights(settings.prior, settings.prior_relative_std);
  // Stage 1, Eq. 7 friction: the data term compressed to its QR factor (72 rows instead of 6 S).
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::Index c = A.cols();
  Residuals lin(kInertial + 12, static_cast<int>(c + kStandard));
  lin.A = qr.matrixQR().topRows(c).triangularView<Eigen::Upper>();
  lin.b = (qr.householderQ().transpose() * b).head(c);
  lin.prior = settings.prior;
  lin.prior_w = prior_w;
  // Start: the prior projected onto the consistent set, friction zero.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kInertial + 12);
  for (int l = 0; l < kLinks; ++l) {
    theta_from_pseudo_inertia(pseudo_inertia(settings.prior.data() + kLinkParams * l), x.data() + kLinkParams * l);
  }
  int iterations = solve(lin, x, options);
  Residuals nl(kInertial + 6 * kf, static_cast<int>(6 * S + kStandard));
  if (model == FrictionModel::eq4) {
    // Stage 2, Eq. 4 friction from stage 1's inertial parameters and each joint's Stribeck start
    // (stribeck_start: no set value used), every sample's row.
    nl.model = model;
    nl.kf = kf;
    nl.A = A.leftCols(kStandard);
    nl.b = b;
    nl.qd = qd;
    nl.w = w;
    nl.prior = settings.prior;
    nl.prior_w = prior_w;
    Eigen::VectorXd x4(kInertial + 6 * kf);
    x4.head(kInertial) = x.head(kInertial);
    const std::vector<double> f4 = stribeck_start(d, nl.standard(x4));
    for (int j = 0; j < 6; ++j) {
      x4.segment(kInertial + kf * j, kf) << f4[4 * j], f4[4 * j + 1], std::log(f4[4 * j + 2]), f4[4 * j + 3];
    }
    iterations += solve(nl, x4, options);
    x = x4;
  } else if (model != FrictionModel::eq7) {
    throw InputError("physically consistent LS: Eq. 7 or Eq. 4 friction");
  }
  const Residuals& p = model == FrictionModel::eq4 ? nl : lin;
  Estimate e;
  e.method = "physically consistent LS";
  e.model = model;
  e.standard = p.standard(x);
  e.standard_prior = e.standard;
  e.base = base_map() * e.standard;
  e.friction.resize(static_cast<size_t>(6 * kf));
  for (int j = 0; j < 6; ++j) p.friction_of(x.data() + kInertial + kf * j, e.friction.data() + kf * j);
  e.iterations = iterations;
  for (int l = 0; l < kLinks; ++l) {
    const Eigen::Matrix4d L = cholesky_factor(x.data() + kLinkParams * l);
    const double smin = Eigen::JacobiSVD<Eigen::Matrix4d>(L).singularValues().minCoeff();
    e.pseudo_inertia_min_eigenvalue.push_back(smin * smin);
  }
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace dyncal::host::survey
