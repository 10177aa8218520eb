// Gautier's weights iterated to their fixed point (joint_weights.hpp), against dense weighted least
// squares on the stacked rows (Eigen's QR) and against the noise the synthetic problem was made with:
// a joint whose rows determine the shared parameters precisely, but whose torque the other joints'
// noisy rows out-weigh under OLS.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "dyncal_host/identification/methods/joint_weights.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace joint_weights_test {

using dyncal::host::iterated_joint_noise;
using dyncal::host::joint_noise_std;
using dyncal::host::JointGrams;
using dyncal::host::ShapePenalty;
using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr int N = 3, P = 5, kRows = 1500;  // rows per joint

/// Joint j's rows (kRows x P) and torques: joints 1 and 2 (0-based 0, 1) see parameters 0..2 with
/// noise 5 and 3 Nm; joint 3 sees parameters 0, 1, 3, 4 with noise 0.01 Nm.
struct Problem {
  std::vector<MatrixXd> K;
  std::vector<VectorXd> y;
  VectorXd truth_sigma = (VectorXd(N) << 5.0, 3.0, 0.01).finished();
};

Problem make_problem() {
  std::mt19937 rng(7);
  std::normal_distribution<double> z;
  const VectorXd phi = (VectorXd(P) << 1.5, -0.7, 2.0, 0.3, -0.4).finished();
  Problem p;
  for (int j = 0; j < N; ++j) {
    MatrixXd K = MatrixXd::Zero(kRows, P);
    for (int r = 0; r < kRows; ++r) {
      if (j < 2) {
        for (int c = 0; c < 3; ++c) K(r, c) = z(rng);
      } else {
        for (int c : {0, 1, 3, 4}) K(r, c) = z(rng);
      }
    }
    VectorXd e(kRows);
    for (int r = 0; r < kRows; ++r) e[r] = p.truth_sigma[j] * z(rng);
    p.K.push_back(K);
    p.y.push_back(K * phi + e);
  }
  return p;
}

/// Dense least squares of the stacked rows, joint j's weighed by w[j], with the penalty's rows
/// sqrt(n_j lambda) L weighed as its joint's (IdentifyPipeline::fit's convention).
VectorXd dense_fit(const Problem& p, const VectorXd& w, const std::vector<ShapePenalty>& penalties) {
  Eigen::Index rows = N * kRows;
  for (const ShapePenalty& pen : penalties) rows += pen.rows.rows();
  MatrixXd A = MatrixXd::Zero(rows, P);
  VectorXd b = VectorXd::Zero(rows);
  for (int j = 0; j < N; ++j) {
    A.middleRows(j * kRows, kRows) = w[j] * p.K[static_cast<size_t>(j)];
    b.segment(j * kRows, kRows) = w[j] * p.y[static_cast<size_t>(j)];
  }
  Eigen::Index r = N * kRows;
  for (const ShapePenalty& pen : penalties) {
    const double scale = w[pen.joint] * std::sqrt(kRows * pen.lambda);
    A.block(r, pen.column, pen.rows.rows(), pen.rows.cols()) = scale * pen.rows;
    r += pen.rows.rows();
  }
  return A.householderQr().solve(b);
}

VectorXd residual_std(const Problem& p, const VectorXd& phi) {
  VectorXd rss(N), n = VectorXd::Constant(N, kRows);
  for (int j = 0; j < N; ++j) rss[j] = (p.y[static_cast<size_t>(j)] - p.K[static_cast<size_t>(j)] * phi).squaredNorm();
  return joint_noise_std(rss, n, P);
}

JointGrams grams_of(const Problem& p) {
  JointGrams g(N, P);
  for (int r = 0; r < kRows; ++r)  // interleaved as a log's samples are
    for (int j = 0; j < N; ++j) {
      const VectorXd k = p.K[static_cast<size_t>(j)].row(r).transpose();
      g.add(j, k.data(), p.y[static_cast<size_t>(j)][r]);
    }
  g.finish();
  return g;
}

TEST(JointWeights, GramsGiveEachJointsResidualSumOfSquares) {
  const Problem p = make_problem();
  const JointGrams g = grams_of(p);
  const VectorXd phi = (VectorXd(P) << 1.4, -0.6, 2.1, 0.2, -0.5).finished();
  for (int j = 0; j < N; ++j) {
    const double direct = (p.y[static_cast<size_t>(j)] - p.K[static_cast<size_t>(j)] * phi).squaredNorm();
    EXPECT_NEAR(g.residual_sum_of_squares(j, phi), direct, 1e-9 * direct) << "joint " << j + 1;
    EXPECT_EQ(g.rows()[j], kRows);
  }
}

TEST(JointWeights, IteratedWeightsReachTheNoiseTheOlsResidualOverstates) {
  const Problem p = make_problem();
  const VectorXd ols_sigma = residual_std(p, dense_fit(p, VectorXd::Ones(N), {}));
  // The defect the iteration mends: under OLS the noisy joints' rows pull the shared parameters, and
  // the precise joint's residual is several times its noise.
  ASSERT_GT(ols_sigma[2], 3.0 * p.truth_sigma[2]);
  int rounds = 0;
  const VectorXd sigma = iterated_joint_noise(grams_of(p), {}, ols_sigma, &rounds);
  EXPECT_GT(rounds, 1);
  EXPECT_LE(rounds, 20);
  for (int j = 0; j < N; ++j) EXPECT_NEAR(sigma[j] / p.truth_sigma[j], 1.0, 0.08) << "joint " << j + 1;
  // A fixed point: the dense weighted fit with these weights leaves these residual std (to the 1 %
  // the iteration stops at).
  const VectorXd again = residual_std(p, dense_fit(p, sigma.cwiseInverse(), {}));
  for (int j = 0; j < N; ++j) EXPECT_NEAR(again[j] / sigma[j], 1.0, 0.015) << "joint " << j + 1;
}

TEST(JointWeights, PenaltyRowsWeighAsTheirJointsRows) {
  const Problem p = make_problem();
  ShapePenalty pen;
  pen.joint = 2;
  pen.column = 3;
  pen.lambda = 0.5;  // strong: parameters 3 and 4 pulled together
  pen.rows = (MatrixXd(1, 2) << 1.0, -1.0).finished();
  const VectorXd ols_sigma = residual_std(p, dense_fit(p, VectorXd::Ones(N), {pen}));
  const VectorXd sigma = iterated_joint_noise(grams_of(p), {pen}, ols_sigma);
  const VectorXd again = residual_std(p, dense_fit(p, sigma.cwiseInverse(), {pen}));
  for (int j = 0; j < N; ++j) EXPECT_NEAR(again[j] / sigma[j], 1.0, 0.015) << "joint " << j + 1;
  // The penalty costs the precise joint: its residual exceeds its noise (0.3 - (-0.4) pulled to 0).
  EXPECT_GT(sigma[2], 2.0 * p.truth_sigma[2]);
}

}  // namespace joint_weights_test
