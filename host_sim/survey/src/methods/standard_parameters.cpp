#include "dyncal_host/survey/methods/standard_parameters.hpp"

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

}  // namespace dyncal::host
