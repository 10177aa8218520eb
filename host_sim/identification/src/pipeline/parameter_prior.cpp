#include "dyncal_host/identification/pipeline/parameter_prior.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/identification/pipeline/compiled_robot.hpp"

namespace dyncal::host {

ParameterPrior parameter_prior(const RobotDescription& robot, const TermSetModel& model, double relative_std) {
  const int P = model.num_params, B = model.num_base;
  ParameterPrior out;
  out.mean = Eigen::VectorXd::Zero(P);
  out.variance = Eigen::VectorXd::Constant(P, std::numeric_limits<double>::quiet_NaN());
  out.has.assign(static_cast<size_t>(P), 0);
  if (!(relative_std > 0.0)) {
    out.missing = "--prior-std 0";
    return out;
  }
  const CompiledRobot& c = compiled_robot_for(robot);
  const Eigen::VectorXd nominal = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  if (nominal.cwiseAbs().maxCoeff() == 0.0) {
    out.missing = "robot " + robot.name + "'s files give no inertials";
    return out;
  }
  const Eigen::MatrixXd K = base_map(c);
  const Eigen::VectorXd s = prior_std(nominal, relative_std);
  const Eigen::MatrixXd sigma = K * s.cwiseAbs2().asDiagonal() * K.transpose();
  const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
  if (llt.info() != Eigen::Success) {
    out.missing = "the base parameters' prior covariance is singular";
    return out;
  }
  out.mean.head(B) = K * nominal;
  out.variance.head(B) = sigma.diagonal();
  out.whitening = Eigen::MatrixXd::Zero(B, P);
  out.whitening.leftCols(B) = llt.matrixL().solve(Eigen::MatrixXd::Identity(B, B));
  std::fill(out.has.begin(), out.has.begin() + B, 1);
  return out;
}

UpdateStatus add_prior_rows(LeastSquaresFit& ls, const ParameterPrior& prior, double sigma) {
  Eigen::VectorXd row;
  for (Eigen::Index b = 0; b < prior.whitening.rows(); ++b) {
    row = prior.whitening.row(b).transpose();
    const UpdateStatus s = ls.add_row(row.data(), row.dot(prior.mean), sigma);
    if (s != UpdateStatus::ok) return s;
  }
  return UpdateStatus::ok;
}

PriorFitStatistics prior_fit_statistics(const ParameterPrior& prior, const Eigen::MatrixXd& R, double sigma2,
                                        double inflation, double data_weight, const std::vector<int>& held) {
  const Eigen::Index P = R.cols();
  std::vector<Eigen::Index> free;
  for (Eigen::Index i = 0; i < P; ++i)
    if (std::find(held.begin(), held.end(), static_cast<int>(i)) == held.end()) free.push_back(i);
  const auto F = static_cast<Eigen::Index>(free.size());
  const Eigen::MatrixXd data_all = R.transpose() * R / sigma2;
  const Eigen::MatrixXd prior_all = prior.whitening.transpose() * prior.whitening;
  Eigen::MatrixXd data(F, F), precision(F, F);
  for (Eigen::Index a = 0; a < F; ++a)
    for (Eigen::Index b = 0; b < F; ++b) {
      data(a, b) = data_all(free[static_cast<size_t>(a)], free[static_cast<size_t>(b)]);
      precision(a, b) = prior_all(free[static_cast<size_t>(a)], free[static_cast<size_t>(b)]);
    }
  const Eigen::LDLT<Eigen::MatrixXd> H(data_weight * data + precision);
  const Eigen::MatrixXd Hinv = H.solve(Eigen::MatrixXd::Identity(F, F));
  const Eigen::MatrixXd cov = Hinv * (data_weight * data_weight * inflation * data + precision) * Hinv;
  const Eigen::MatrixXd influence = Hinv * precision;
  PriorFitStatistics out;
  out.stdev = Eigen::VectorXd::Zero(P);
  out.data_share = Eigen::VectorXd::Constant(P, std::numeric_limits<double>::quiet_NaN());
  for (Eigen::Index a = 0; a < F; ++a) {
    const Eigen::Index i = free[static_cast<size_t>(a)];
    out.stdev[i] = std::sqrt(std::max(0.0, cov(a, a)));
    if (prior.has[static_cast<size_t>(i)]) out.data_share[i] = std::clamp(1.0 - influence(a, a), 0.0, 1.0);
  }
  return out;
}

}  // namespace dyncal::host
