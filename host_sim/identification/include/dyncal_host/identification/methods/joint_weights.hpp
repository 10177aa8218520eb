#pragma once
// Gautier's weighted least squares with its weights iterated to their fixed point (feasible
// generalised least squares): the per-joint Gram matrices of one pass over the data, and the
// weights they give.

#include <Eigen/Core>
#include <vector>

#include "dyncal_host/identification/methods/effect_model.hpp"

namespace dyncal::host {

/// Per joint j: the Gram matrix K_j^T K_j (P x P) of its fitted rows, K_j^T y_j, y_j^T y_j and the
/// rows' count, gathered row by row (add) in blocks of kBlock rows per joint (one matrix product
/// a block). What the weights are iterated on without another pass over the data.
class JointGrams {
 public:
  JointGrams(int joints, Eigen::Index params);
  /// One fitted row of joint j: k (P entries, the regressor row) and y [Nm].
  void add(int j, const double* k, double y);
  /// Folds the rows still buffered into the Grams; call once after the last add.
  void finish();

  int joints() const { return static_cast<int>(G_.size()); }
  const Eigen::MatrixXd& gram(int j) const { return G_[static_cast<size_t>(j)]; }
  const Eigen::VectorXd& cross(int j) const { return g_[static_cast<size_t>(j)]; }
  double y_squared(int j) const { return yy_[j]; }
  const Eigen::VectorXd& rows() const { return n_; }

  /// Joint j's residual sum of squares at phi [Nm^2]: y^T y - 2 phi^T K^T y + phi^T K^T K phi.
  double residual_sum_of_squares(int j, const Eigen::VectorXd& phi) const;

 private:
  static constexpr Eigen::Index kBlock = 64;
  std::vector<Eigen::MatrixXd> G_, buffer_;
  std::vector<Eigen::VectorXd> g_, ybuf_;
  std::vector<Eigen::Index> used_;
  Eigen::VectorXd yy_, n_;
  void flush(int j);
};

/// Gautier's per-joint noise sigma (joint_noise_std, stacked_data.hpp) iterated: from `start` (the
/// OLS residual's), sigma_j becomes the residual std of the fit weighted by 1 / sigma_j so far, until
/// no sigma_j moves by more than 1 % (at most 20 rounds). Each round's fit solves the weighted normal
/// equations of `grams` with the penalised shapes' roughness (each weighed as its joint's rows, as
/// IdentifyPipeline::fit adds them), the columns scaled to unit diagonal and a ridge of 1e-10 on that
/// diagonal for the directions the data leave undetermined (they do not move the residual).
/// Why: the OLS residual over-states the noise of a joint whose torque is small against the
/// others' (the parameters the joints share are fitted to the large ones first), so that joint weighs
/// too little, and the terms only its own rows determine (its friction, its effect terms) are left
/// to trade with each other out of sample. `rounds`, if given, receives the rounds taken.
/// Returns sigma (N) [Nm].
Eigen::VectorXd iterated_joint_noise(const JointGrams& grams, const std::vector<ShapePenalty>& penalties,
                                     const Eigen::VectorXd& start, int* rounds = nullptr);

}  // namespace dyncal::host
