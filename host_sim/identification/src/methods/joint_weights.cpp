#include "dyncal_host/identification/methods/joint_weights.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {

JointGrams::JointGrams(int joints, Eigen::Index params)
    : G_(static_cast<size_t>(joints), Eigen::MatrixXd::Zero(params, params)),
      buffer_(static_cast<size_t>(joints), Eigen::MatrixXd(kBlock, params)),
      g_(static_cast<size_t>(joints), Eigen::VectorXd::Zero(params)),
      ybuf_(static_cast<size_t>(joints), Eigen::VectorXd(kBlock)),
      used_(static_cast<size_t>(joints), 0),
      yy_(Eigen::VectorXd::Zero(joints)),
      n_(Eigen::VectorXd::Zero(joints)) {}

void JointGrams::add(int j, const double* k, double y) {
  const size_t u = static_cast<size_t>(j);
  const Eigen::Index P = G_[u].cols();
  buffer_[u].row(used_[u]) = Eigen::Map<const Eigen::RowVectorXd>(k, P);
  ybuf_[u][used_[u]] = y;
  if (++used_[u] == kBlock) flush(j);
}

void JointGrams::flush(int j) {
  const size_t u = static_cast<size_t>(j);
  const Eigen::Index b = used_[u];
  if (b == 0) return;
  const auto B = buffer_[u].topRows(b);
  const auto y = ybuf_[u].head(b);
  G_[u].noalias() += B.transpose() * B;
  g_[u].noalias() += B.transpose() * y;
  yy_[j] += y.squaredNorm();
  n_[j] += static_cast<double>(b);
  used_[u] = 0;
}

void JointGrams::finish() {
  for (int j = 0; j < joints(); ++j) flush(j);
}

double JointGrams::residual_sum_of_squares(int j, const Eigen::VectorXd& phi) const {
  const size_t u = static_cast<size_t>(j);
  return std::max(0.0, yy_[j] - 2.0 * phi.dot(g_[u]) + phi.dot(G_[u] * phi));
}

Eigen::VectorXd iterated_joint_noise(const JointGrams& grams, const std::vector<ShapePenalty>& penalties,
                                     const Eigen::VectorXd& start, int* rounds) {
  const int N = grams.joints();
  const Eigen::Index P = grams.gram(0).cols();
  Eigen::VectorXd sigma = start;
  int r = 0;
  for (; r < 20; ++r) {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(P, P);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(P);
    for (int j = 0; j < N; ++j) {
      const double w2 = 1.0 / (sigma[j] * sigma[j]);
      A.noalias() += w2 * grams.gram(j);
      b.noalias() += w2 * grams.cross(j);
    }
    for (const ShapePenalty& pen : penalties) {
      const double w2 = grams.rows()[pen.joint] * pen.lambda / (sigma[pen.joint] * sigma[pen.joint]);
      const Eigen::Index m = pen.rows.cols();
      A.block(pen.column, pen.column, m, m).noalias() += w2 * pen.rows.transpose() * pen.rows;
    }
    Eigen::VectorXd d = A.diagonal();
    for (Eigen::Index i = 0; i < P; ++i) d[i] = d[i] > 0 ? 1.0 / std::sqrt(d[i]) : 1.0;
    Eigen::MatrixXd As = d.asDiagonal() * A * d.asDiagonal();
    As.diagonal().array() += 1e-10;
    const Eigen::VectorXd phi = d.cwiseProduct(As.ldlt().solve(d.cwiseProduct(b)));
    Eigen::VectorXd rss(N);
    for (int j = 0; j < N; ++j) rss[j] = grams.residual_sum_of_squares(j, phi);
    const Eigen::VectorXd next = joint_noise_std(rss, grams.rows(), P);
    const double change = (next.array() / sigma.array() - 1.0).abs().maxCoeff();
    sigma = next;
    if (!(change > 0.01)) {
      ++r;
      break;
    }
  }
  if (rounds) *rounds = r;
  return sigma;
}

}  // namespace dyncal::host
