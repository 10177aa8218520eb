#include "dyncal_host/identification/survey_methods/standard_parameters.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <random>
#include <utility>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace g = dyncal::generated::er20;

static_assert(g::kNumStandard == kStandard && g::kNumBase == kBase, "survey study sized for the er20");

const Eigen::MatrixXd& base_map() {
  static const Eigen::MatrixXd G = [] {
    Eigen::MatrixXd m(kBase, kStandard);
    for (int i = 0; i < kStandard; ++i) {
      Eigen::Matrix<double, kStandard, 1> e = Eigen::Matrix<double, kStandard, 1>::Zero();
      e[i] = 1.0;
      Eigen::Matrix<double, kBase, 1> b;
      g::standard_to_base(e, b);
      m.col(i) = b;
    }
    return m;
  }();
  return G;
}

const Eigen::MatrixXd& base_map_pinv() {
  static const Eigen::MatrixXd Gp = base_map().completeOrthogonalDecomposition().pseudoInverse();
  return Gp;
}

Eigen::VectorXd set_standard() {
  Eigen::VectorXd phi(kStandard);
  for (int i = 0; i < kStandard; ++i) phi[i] = g::kNominalStandard[i];
  return phi;
}

namespace {

/// Standard deviations of one link's 10 drawn parameters: relative_error x max(|v_i|, 5 % of the
/// largest |v| of the same kind); kinds are index ranges.
void kind_scaled_std(const double* v, double relative_error, std::initializer_list<std::pair<int, int>> kinds,
                     double* sd) {
  for (const auto& [from, to] : kinds) {
    double m = 0;
    for (int i = from; i < to; ++i) m = std::max(m, std::fabs(v[i]));
    if (m == 0.0) throw InputError("CAD prior: a link has no nonzero value of a kind, so no scale for its error");
    for (int i = from; i < to; ++i) sd[i] = relative_error * std::max(std::fabs(v[i]), 0.05 * m);
  }
}

}  // namespace

CadPrior cad_prior(double relative_error, std::uint64_t seed, PriorErrors on) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-relative_error, relative_error);
  const Eigen::VectorXd set = set_standard();
  CadPrior p;
  p.mean.resize(kStandard);
  p.covariance = Eigen::MatrixXd::Zero(kStandard, kStandard);
  p.whitening = Eigen::MatrixXd::Zero(kStandard, kStandard);
  for (int l = 0; l < kLinks; ++l) {
    using Mat10 = Eigen::Matrix<double, 10, 10>;
    Mat10 J = Mat10::Identity();
    double sd[10];
    double* mean = p.mean.data() + 10 * l;
    if (on == PriorErrors::table5) {
      std::array<double, 10> v = physical_parameters(set.data() + 10 * l);
      for (double& x : v) x *= 1.0 + u(rng);
      Eigen::Matrix<double, 10, 10, Eigen::RowMajor> jr;
      standard_from_physical(v, mean, jr.data());
      J = jr;
      kind_scaled_std(v.data(), relative_error, {{0, 1}, {1, 4}, {4, 10}}, sd);
    } else {
      for (int i = 0; i < 10; ++i) mean[i] = set[10 * l + i] * (1.0 + u(rng));
      kind_scaled_std(mean, relative_error, {{0, 6}, {6, 9}, {9, 10}}, sd);
    }
    const Mat10 P = J * Eigen::Map<const Eigen::Matrix<double, 10, 1>>(sd).cwiseAbs2().asDiagonal() * J.transpose();
    p.covariance.block<10, 10>(10 * l, 10 * l) = P;
    const Eigen::LLT<Mat10> llt(P);
    if (llt.info() != Eigen::Success) throw InputError("CAD prior: a link's covariance is not positive definite");
    const Mat10 L = llt.matrixL();
    p.whitening.block<10, 10>(10 * l, 10 * l) = L.triangularView<Eigen::Lower>().solve(Mat10::Identity());
  }
  return p;
}

Eigen::VectorXd minimum_norm_standard(const Eigen::VectorXd& phi_b) {
  return base_map_pinv() * phi_b;
}

Eigen::VectorXd standard_from_base(const Eigen::VectorXd& phi_b, const CadPrior& prior) {
  const Eigen::MatrixXd& G = base_map();
  const Eigen::MatrixXd PGt = prior.covariance * G.transpose();
  const Eigen::VectorXd lambda = (G * PGt).completeOrthogonalDecomposition().solve(phi_b - G * prior.mean);
  return prior.mean + PGt * lambda;
}

std::array<double, 10> physical_parameters(const double* p) {
  const double m = p[9];
  // A zero mass (a minimum-norm estimate of an unidentifiable link) has no centre of mass: taken
  // at the origin, so that its errors count as 100 % instead of undefined.
  const Eigen::Vector3d c =
      m != 0.0 ? Eigen::Vector3d(Eigen::Vector3d(p[6], p[7], p[8]) / m) : Eigen::Vector3d(Eigen::Vector3d::Zero());
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  // Parallel axis (Huygens-Steiner): I_origin = I_com + m (c^T c 1 - c c^T).
  const Eigen::Matrix3d Ic = I - m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  return {m, c[0], c[1], c[2], Ic(0, 0), Ic(0, 1), Ic(0, 2), Ic(1, 1), Ic(1, 2), Ic(2, 2)};
}

void standard_from_physical(const std::array<double, 10>& v, double* p, double* jac) {
  const double m = v[0];
  const Eigen::Vector3d c(v[1], v[2], v[3]);
  Eigen::Matrix3d Ic;
  Ic << v[4], v[5], v[6], v[5], v[7], v[8], v[6], v[8], v[9];
  const Eigen::Matrix3d S = c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose();
  const Eigen::Matrix3d I = Ic + m * S;
  constexpr int kRow[6] = {0, 0, 0, 1, 1, 2}, kCol[6] = {0, 1, 2, 1, 2, 2};
  for (int k = 0; k < 6; ++k) p[k] = I(kRow[k], kCol[k]);
  for (int a = 0; a < 3; ++a) p[6 + a] = m * c[a];
  p[9] = m;
  if (!jac) return;
  Eigen::Map<Eigen::Matrix<double, 10, 10, Eigen::RowMajor>> J(jac);
  J.setZero();
  for (int k = 0; k < 6; ++k) {
    J(k, 0) = S(kRow[k], kCol[k]);
    J(k, 4 + k) = 1.0;
    for (int a = 0; a < 3; ++a) {
      // d/dc_a of m (c^T c 1 - c c^T) = m (2 c_a 1 - e_a c^T - c e_a^T).
      Eigen::Matrix3d E = 2.0 * c[a] * Eigen::Matrix3d::Identity();
      E.row(a) -= c.transpose();
      E.col(a) -= c;
      J(k, 1 + a) = m * E(kRow[k], kCol[k]);
    }
  }
  for (int a = 0; a < 3; ++a) {
    J(6 + a, 0) = c[a];
    J(6 + a, 1 + a) = m;
  }
  J(9, 0) = 1.0;
}

Eigen::Matrix4d pseudo_inertia(const double* p) {
  Eigen::Matrix3d I;
  I << p[0], p[1], p[2], p[1], p[3], p[4], p[2], p[4], p[5];
  Eigen::Matrix4d J;
  J.topLeftCorner<3, 3>() = 0.5 * I.trace() * Eigen::Matrix3d::Identity() - I;
  J.topRightCorner<3, 1>() = Eigen::Vector3d(p[6], p[7], p[8]);
  J.bottomLeftCorner<1, 3>() = Eigen::RowVector3d(p[6], p[7], p[8]);
  J(3, 3) = p[9];
  return J;
}

Eigen::Matrix4d nearest_positive_definite(const Eigen::Matrix4d& J) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(J);
  const Eigen::Vector4d ev = es.eigenvalues();
  const double floor = 1e-4 * std::max(ev.maxCoeff(), 1e-9);
  if (ev.minCoeff() >= floor) return J;
  return es.eigenvectors() * ev.cwiseMax(floor).asDiagonal() * es.eigenvectors().transpose();
}

Eigen::VectorXd nearest_consistent(const Eigen::VectorXd& phi) {
  Eigen::VectorXd out = phi;
  for (Eigen::Index l = 0; l < phi.size() / 10; ++l) {
    standard_from_pseudo_inertia(nearest_positive_definite(pseudo_inertia(phi.data() + 10 * l)), out.data() + 10 * l);
  }
  return out;
}

void standard_from_pseudo_inertia(const Eigen::Matrix4d& J, double* p) {
  const Eigen::Matrix3d S = J.topLeftCorner<3, 3>();
  const Eigen::Matrix3d I = S.trace() * Eigen::Matrix3d::Identity() - S;
  p[0] = I(0, 0);
  p[1] = I(0, 1);
  p[2] = I(0, 2);
  p[3] = I(1, 1);
  p[4] = I(1, 2);
  p[5] = I(2, 2);
  p[6] = J(0, 3);
  p[7] = J(1, 3);
  p[8] = J(2, 3);
  p[9] = J(3, 3);
}

}  // namespace dyncal::host
