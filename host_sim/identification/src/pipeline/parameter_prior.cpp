#include "dyncal_host/identification/pipeline/parameter_prior.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/methods/consistent_least_squares.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {

namespace {

/// robot.json's nominal friction as the prior of model column i (a Coulomb or viscous term), or 0
/// when it gives none: no value > 0, or a motor that turns with other joints too (its friction is
/// the motor's, robot.json's is per joint).
double nominal_friction(const RobotDescription& robot, const TermSetModel& model, int i) {
  const dyncal::ParamInfo& p = model.info[static_cast<size_t>(i)];
  const int j = p.joint - 1;
  if (p.kind != dyncal::ParamKind::term || j < 0 || static_cast<size_t>(j) >= robot.friction.size()) return 0.0;
  if (robot.transmission.rows() > j) {
    for (Eigen::Index k = 0; k < robot.transmission.cols(); ++k)
      if (k != j && robot.transmission(j, k) != 0.0) return 0.0;
  }
  const NominalFriction& f = robot.friction[static_cast<size_t>(j)];
  if (p.term == term::coulomb) return f.Fc > 0.0 ? f.Fc : 0.0;
  if (p.term == term::viscous) return f.beta > 0.0 ? f.beta : 0.0;
  return 0.0;
}

}  // namespace

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
  // The base parameters' block, from the inertials.
  Eigen::MatrixXd base_rows;
  const CompiledRobot& c = compiled_robot_for(robot);
  const Eigen::VectorXd nominal = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  if (nominal.cwiseAbs().maxCoeff() == 0.0) {
    out.missing = "robot " + robot.name + "'s files give no inertials";
  } else {
    const Eigen::MatrixXd K = base_map(c);
    const Eigen::VectorXd s = prior_std(nominal, relative_std);
    const Eigen::MatrixXd sigma = K * s.cwiseAbs2().asDiagonal() * K.transpose();
    const Eigen::LLT<Eigen::MatrixXd> llt(sigma);
    if (llt.info() != Eigen::Success) {
      out.missing = "the base parameters' prior covariance is singular";
    } else {
      out.mean.head(B) = K * nominal;
      out.variance.head(B) = sigma.diagonal();
      base_rows = Eigen::MatrixXd::Zero(B, P);
      base_rows.leftCols(B) = llt.matrixL().solve(Eigen::MatrixXd::Identity(B, B));
      std::fill(out.has.begin(), out.has.begin() + B, 1);
    }
  }
  // Coulomb and viscous friction from robot.json's "friction" list, independent of the rest.
  std::vector<int> friction;
  for (int i = B; i < P; ++i) {
    const double value = nominal_friction(robot, model, i);
    if (!(value > 0.0)) continue;
    const double sd = relative_std * value;
    out.mean[i] = value;
    out.variance[i] = sd * sd;
    out.has[static_cast<size_t>(i)] = 1;
    friction.push_back(i);
  }
  out.whitening = Eigen::MatrixXd::Zero(base_rows.rows() + static_cast<Eigen::Index>(friction.size()), P);
  out.whitening.topRows(base_rows.rows()) = base_rows;
  for (size_t k = 0; k < friction.size(); ++k)
    out.whitening(base_rows.rows() + static_cast<Eigen::Index>(k), friction[k]) =
        1.0 / std::sqrt(out.variance[friction[k]]);
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
