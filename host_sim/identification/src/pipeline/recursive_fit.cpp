#include "dyncal_host/identification/pipeline/recursive_fit.hpp"

#include <utility>

#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/robot_model.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

/// lib/ StreamingLeastSquares at the run-time size behind LeastSquaresFit: the same updater and
/// arithmetic as at a fixed size.
class RunTimeLeastSquares final : public LeastSquaresFit {
 public:
  using Ls = StreamingLeastSquares<double, Eigen::Dynamic, kMaxFitParams>;
  /// invalid_argument for a size beyond the capacity.
  UpdateStatus resize(int num_params) { return ls_.reset(num_params); }
  void reset() override { ls_.reset(); }
  UpdateStatus add_row(const double* k, double y, double w) override {
    return ls_.add_row(Eigen::Map<const Eigen::VectorXd>(k, ls_.size()), y, w);
  }
  UpdateStatus solve(Eigen::VectorXd& phi) const override {
    Ls::Vector x;
    const UpdateStatus s = ls_.solve(x);
    if (s == UpdateStatus::ok) phi = x;
    return s;
  }
  UpdateStatus inverse_gram_diagonal(Eigen::VectorXd& diag) const override {
    Ls::Vector d;
    const UpdateStatus s = ls_.inverse_gram_diagonal(d);
    if (s == UpdateStatus::ok) diag = d;
    return s;
  }
  double residual_sum_of_squares() const override { return ls_.residual_sum_of_squares(); }
  long rows() const override { return ls_.rows(); }
  Eigen::MatrixXd r_factor() const override { return ls_.r_factor(); }
  Eigen::VectorXd rotated_rhs() const override { return ls_.rotated_rhs(); }

 private:
  Ls ls_;
};

template <int N>
using RunTimeCovariance = PackedCovariance<double, Eigen::Dynamic, N, max_model_params(N)>;

/// A lib/ filter of N joints and run-time P behind RecursiveFit.
template <class Filter, int N>
class RunTimeRecursiveFit final : public RecursiveFit {
 public:
  explicit RunTimeRecursiveFit(int num_params) : k_(N, num_params) {}
  Filter filter;
  UpdateStatus update(const double* K, const double* tau, const double* noise) override {
    k_ = Eigen::Map<const Eigen::Matrix<double, N, Eigen::Dynamic>>(K, N, k_.cols());
    return filter.update(k_, Eigen::Map<const Eigen::Matrix<double, N, 1>>(tau),
                         Eigen::Map<const Eigen::Matrix<double, N, 1>>(noise));
  }
  Eigen::VectorXd estimate() const override { return filter.estimate(); }
  Eigen::VectorXd covariance_diagonal() const override {
    typename Filter::ParamVector d;
    filter.covariance().diagonal(d);
    return d.cwiseSqrt();
  }

 private:
  typename Filter::Regressor k_;
};

template <int N>
std::unique_ptr<RecursiveFit> make_fit(const TermSetModel& m, double p0, double mu, bool rls, UpdateStatus* status) {
  using Kf = KalmanFilter<double, Eigen::Dynamic, N, RunTimeCovariance<N>>;
  using Rls = RlsForgetting<double, Eigen::Dynamic, N, RunTimeCovariance<N>>;
  using ParamVector = typename Kf::ParamVector;
  const ParamVector phi0 = ParamVector::Zero(m.num_params), cov0 = ParamVector::Constant(m.num_params, p0);
  if (rls) {
    auto f = std::make_unique<RunTimeRecursiveFit<Rls, N>>(m.num_params);
    *status = f->filter.reset(phi0, cov0, mu);
    if (*status != UpdateStatus::ok) return nullptr;
    return f;
  }
  auto f = std::make_unique<RunTimeRecursiveFit<Kf, N>>(m.num_params);
  *status = f->filter.reset(phi0, cov0);
  if (*status != UpdateStatus::ok) return nullptr;
  return f;
}

template <int... I>
std::unique_ptr<RecursiveFit> make_for_joints(const TermSetModel& m, double p0, double mu, bool rls,
                                              UpdateStatus* status, std::integer_sequence<int, I...>) {
  using Make = std::unique_ptr<RecursiveFit> (*)(const TermSetModel&, double, double, bool, UpdateStatus*);
  static constexpr Make by_joints[] = {&make_fit<I + 1>...};
  if (m.num_joints < 1 || m.num_joints > kMaxRobotJoints || m.num_params < 1 ||
      m.num_params > max_model_params(m.num_joints))
    throw InputError("recursive fit: a model of " + std::to_string(m.num_joints) + " joints and " +
                     std::to_string(m.num_params) + " parameters is beyond the compiled sizes");
  return by_joints[m.num_joints - 1](m, p0, mu, rls, status);
}

}  // namespace

std::unique_ptr<LeastSquaresFit> make_least_squares(const TermSetModel& model) {
  auto ls = std::make_unique<RunTimeLeastSquares>();
  if (ls->resize(model.num_params) != UpdateStatus::ok)
    throw InputError("least squares: a model of " + std::to_string(model.num_params) +
                     " parameters is beyond the compiled capacity of " + std::to_string(kMaxFitParams));
  return ls;
}

std::unique_ptr<RecursiveFit> make_kalman_filter(const TermSetModel& model, double p0, UpdateStatus* status) {
  return make_for_joints(model, p0, 1.0, false, status, std::make_integer_sequence<int, kMaxRobotJoints>());
}

std::unique_ptr<RecursiveFit> make_rls(const TermSetModel& model, double p0, double mu, UpdateStatus* status) {
  return make_for_joints(model, p0, mu, true, status, std::make_integer_sequence<int, kMaxRobotJoints>());
}

}  // namespace dyncal::host
