#include "dyncal_host/survey/physically_consistent.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <unsupported/Eigen/LevenbergMarquardt>

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
/// x = [theta_L (60) | friction]. Linear friction (Eq. 7, 8, 9): F per joint are columns of A, and
/// A, b can be compressed to their QR factor. Nonlinear friction (Eq. 4, 5, 6): one row per joint
/// sample with its velocity, load torque and weight; each scale parameter enters as its log
/// (positive by construction).
struct Residuals : Eigen::DenseFunctor<double> {
  FrictionModel model = FrictionModel::eq7;
  int kf = 2;                      // friction parameters per joint
  Eigen::MatrixXd A;               // rows x (60 [+ 12 linear friction]), scaled by 1 / sigma_j
  Eigen::VectorXd b;               // scaled torques
  Eigen::VectorXd qd, load, w;     // nonlinear only: velocity, load torque, 1 / sigma of each row (joint = row % 6)
  Eigen::VectorXd prior, prior_w;  // prior mean, 1 / s_i (0: no prior term)

  Residuals(int inputs, int values) : Eigen::DenseFunctor<double>(inputs, values) {}

  bool nonlinear() const { return !is_linear(model); }

  /// Friction parameters of joint j in model form (scale parameters from their logs).
  void friction_of(const double* xf, double* th) const {
    for (int k = 0; k < kf; ++k) th[k] = is_scale_parameter(model, k) ? std::exp(xf[k]) : xf[k];
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
        double th[6];
        friction_of(x.data() + kInertial + kf * (i % 6), th);
        r[i] += w[i] * friction_torque(model, th, qd[i], load[i]);
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
      double th[6], jf[6] = {0, 0, 0, 0, 0, 0};
      friction_of(x.data() + kInertial + kf * j, th);
      friction_torque(model, th, qd[i], load[i], jf);
      for (int k = 0; k < kf; ++k) {
        if (is_scale_parameter(model, k)) jf[k] *= th[k];  // d / d log(theta_k)
        J(i, kInertial + kf * j + k) = w[i] * jf[k];
      }
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
  const int kf = friction_count(model);
  // Weighted standard regressor with the linear friction columns: the model's own (Eq. 7, 8, 9),
  // or Eq. 7's (Fc, beta per joint) as the first stage of a nonlinear model.
  const FrictionModel linear = is_linear(model) ? model : FrictionModel::eq7;
  const int kl = friction_count(linear);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * S, kStandard + 6 * kl);
  Eigen::VectorXd b(6 * S), qd(6 * S), load(6 * S), w(6 * S);
  Eigen::Matrix<double, 6, kStandard> Ys;
  for (Eigen::Index s = 0; s < S; ++s) {
    Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                              Vec6(d.qdd.row(s).transpose()), Ys);
    for (int j = 0; j < 6; ++j) {
      const Eigen::Index i = 6 * s + j;
      w[i] = 1.0 / settings.sigma[j];
      qd[i] = d.qd(s, j);
      load[i] = d.tau_load(s, j);
      A.row(i).head<kStandard>() = w[i] * Ys.row(j);
      for (int k = 0; k < kl; ++k) A(i, kStandard + kl * j + k) = w[i] * linear_column(linear, k, qd[i], load[i]);
      b[i] = w[i] * d.tau(s, j);
    }
  }
  const Eigen::VectorXd prior_w = prior_weights(settings.prior, settings.prior_relative_std);
  // Stage 1, linear friction: the data term compressed to its QR factor (60 + 6 kl rows, not 6 S).
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::Index c = A.cols();
  Residuals lin(kInertial + 6 * kl, static_cast<int>(c + kStandard));
  lin.model = linear;
  lin.kf = kl;
  lin.A = qr.matrixQR().topRows(c).triangularView<Eigen::Upper>();
  lin.b = (qr.householderQ().transpose() * b).head(c);
  lin.prior = settings.prior;
  lin.prior_w = prior_w;
  // Start: the prior projected onto the consistent set, friction zero.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(kInertial + 6 * kl);
  for (int l = 0; l < kLinks; ++l) {
    theta_from_pseudo_inertia(pseudo_inertia(settings.prior.data() + kLinkParams * l), x.data() + kLinkParams * l);
  }
  int iterations = solve(lin, x, options);
  Residuals nl(kInertial + 6 * kf, static_cast<int>(6 * S + kStandard));
  if (!is_linear(model)) {
    // Stage 2, nonlinear friction from stage 1's inertial parameters and each joint's friction
    // start (friction_start: no set value used), every sample's row.
    nl.model = model;
    nl.kf = kf;
    nl.A = A.leftCols(kStandard);
    nl.b = b;
    nl.qd = qd;
    nl.load = load;
    nl.w = w;
    nl.prior = settings.prior;
    nl.prior_w = prior_w;
    Eigen::VectorXd x4(kInertial + 6 * kf);
    x4.head(kInertial) = x.head(kInertial);
    const std::vector<double> f = friction_start(d, model, nl.standard(x4));
    for (int i = 0; i < 6 * kf; ++i) {
      x4[kInertial + i] =
          is_scale_parameter(model, i % kf) ? std::log(f[static_cast<size_t>(i)]) : f[static_cast<size_t>(i)];
    }
    iterations += solve(nl, x4, options);
    x = x4;
  }
  const Residuals& p = is_linear(model) ? lin : nl;
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
