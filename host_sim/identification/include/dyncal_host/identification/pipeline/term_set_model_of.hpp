#pragma once
// TermSetModel of IdentificationModel<Robot, Terms>: its layout, the generated regressor and lib/
// least squares of its size. Included only by the robots' translation units (register_robot.hpp).

#include <memory>

#include "dyncal/identification_model.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal_host/identification/pipeline/term_set_model.hpp"

namespace dyncal::host {

template <int P>
class LeastSquaresOf final : public LeastSquaresFit {
 public:
  using Vec = Eigen::Matrix<double, P, 1>;
  void reset() override { ls_.reset(); }
  UpdateStatus add_row(const double* k, double y, double w) override {
    return ls_.add_row(Eigen::Map<const Vec>(k), y, w);
  }
  UpdateStatus solve(Eigen::VectorXd& phi) const override {
    Vec x;
    const UpdateStatus s = ls_.solve(x);
    if (s == UpdateStatus::ok) phi = x;
    return s;
  }
  UpdateStatus inverse_gram_diagonal(Eigen::VectorXd& diag) const override {
    Vec d;
    const UpdateStatus s = ls_.inverse_gram_diagonal(d);
    if (s == UpdateStatus::ok) diag = d;
    return s;
  }
  double residual_sum_of_squares() const override { return ls_.residual_sum_of_squares(); }
  long rows() const override { return ls_.rows(); }
  Eigen::MatrixXd r_factor() const override { return ls_.r_factor(); }
  Eigen::VectorXd rotated_rhs() const override { return ls_.rotated_rhs(); }

 private:
  StreamingLeastSquares<double, P> ls_;
};

/// The TermSetModel of IdentificationModel<Robot, Terms>.
template <class Robot, unsigned Terms>
TermSetModel term_set_model_of() {
  using Model = IdentificationModel<Robot, Terms>;
  constexpr int N = Robot::kNumJoints, P = Model::kNumParams;
  using Vec = Eigen::Matrix<double, N, 1>;
  TermSetModel m;
  m.terms = Terms;
  m.num_joints = N;
  m.num_params = P;
  m.num_base = Robot::kNumBase;
  for (int i = 0; i < P; ++i) {
    const ParamInfo info = Model::info(i);
    m.info.push_back(info);
    m.names.push_back(info.kind == ParamKind::base ? std::string(Robot::base_param_name(info.base_index))
                                                   : std::string(term_name(info.term)) + std::to_string(info.joint));
  }
  for (int j = 0; j < N; ++j) {
    m.rotor_inertia_separate.push_back(Robot::rotor_inertia_separate(j) ? 1 : 0);
    m.rotor_inertia_absorbed_into.push_back(Robot::rotor_inertia_absorbed_into(j));
  }
  m.regressor = [](const double* q, const double* qd, const double* qdd, double* K) {
    typename Model::template Regressor<double> k;
    Model::regressor(Vec(Eigen::Map<const Vec>(q)), Vec(Eigen::Map<const Vec>(qd)), Vec(Eigen::Map<const Vec>(qdd)),
                     Vec(Vec::Zero()), k);
    Eigen::Map<Eigen::Matrix<double, N, P>> out(K);
    out = k;
  };
  m.make_least_squares = []() -> std::unique_ptr<LeastSquaresFit> { return std::make_unique<LeastSquaresOf<P>>(); };
  return m;
}

}  // namespace dyncal::host
