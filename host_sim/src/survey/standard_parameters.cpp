#include "dyncal_host/survey/standard_parameters.hpp"

#include <Eigen/Dense>
#include <random>

#include "er20/robot.hpp"

namespace dyncal::host::survey {
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

Eigen::VectorXd cad_prior(double relative_error, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-relative_error, relative_error);
  Eigen::VectorXd phi = set_standard();
  for (int i = 0; i < kStandard; ++i) phi[i] *= 1.0 + u(rng);
  return phi;
}

Eigen::VectorXd minimum_norm_standard(const Eigen::VectorXd& phi_b) {
  return base_map_pinv() * phi_b;
}

Eigen::VectorXd standard_from_base(const Eigen::VectorXd& phi_b, const Eigen::VectorXd& prior, double relative_std) {
  const Eigen::MatrixXd& G = base_map();
  const Eigen::VectorXd s2 = (relative_std * prior).cwiseAbs2();
  const Eigen::MatrixXd GS2 = G * s2.asDiagonal();
  const Eigen::MatrixXd A = GS2 * G.transpose();
  const Eigen::VectorXd lambda = A.completeOrthogonalDecomposition().solve(phi_b - G * prior);
  return prior + GS2.transpose() * lambda;
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
  for (int l = 0; l < kLinks; ++l) {
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

}  // namespace dyncal::host::survey
