#include "dyncal_host/survey/methods/run_data.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <vector>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

using Robot = dyncal::generated::er20::Robot;

RunData sample_rows(const RunData& d, Eigen::Index from, Eigen::Index n) {
  if (from < 0 || n < 0 || from + n > d.q.rows()) throw InputError("sample_rows: rows outside the run");
  RunData r = d;
  r.t = d.t.segment(from, n);
  for (auto [dst, src] : {std::make_pair(&r.q, &d.q), std::make_pair(&r.qd, &d.qd), std::make_pair(&r.qdd, &d.qdd),
                          std::make_pair(&r.q_meas, &d.q_meas), std::make_pair(&r.tau, &d.tau),
                          std::make_pair(&r.tau_load, &d.tau_load)}) {
    *dst = src->middleRows(from, n);
  }
  return r;
}

Eigen::MatrixXd load_torque(const Eigen::MatrixXd& q, const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd,
                            const Eigen::MatrixXd& tau) {
  using Model9 = IdentificationModel<Robot, kFrictionEq9>;
  using Vec6 = Eigen::Matrix<double, 6, 1>;
  const Eigen::Index S = q.rows();
  // The regressor once (load torque = tau to start) and the base regressor at qdd = 0; each round
  // rewrites only the load columns.
  Eigen::MatrixXd load = tau, W(6 * S, Model9::kNumParams);
  Eigen::VectorXd y(6 * S);
  Model9::Regressor<double> K;
  std::vector<Eigen::Matrix<double, 6, Robot::kNumBase>> Y0(static_cast<size_t>(S));
  for (Eigen::Index s = 0; s < S; ++s) {
    Model9::regressor(Vec6(q.row(s).transpose()), Vec6(qd.row(s).transpose()), Vec6(qdd.row(s).transpose()),
                      Vec6(load.row(s).transpose()), K);
    W.middleRows(6 * s, 6) = K;
    y.segment<6>(6 * s) = tau.row(s).transpose();
    Robot::base_regressor(Vec6(q.row(s).transpose()), Vec6(qd.row(s).transpose()), Vec6::Zero().eval(),
                          Y0[static_cast<size_t>(s)]);
  }
  std::vector<std::pair<int, int>> load_columns;  // (column, 0-based joint)
  for (int i = Robot::kNumBase; i < Model9::kNumParams; ++i) {
    const ParamInfo info = Model9::info(i);
    if (info.term == term::load) load_columns.emplace_back(i, info.joint - 1);
  }
  const double tol = 1e-9 * std::max(tau.cwiseAbs().maxCoeff(), 1e-300);
  for (int it = 0; it < 50; ++it) {
    if (it > 0) {
      for (Eigen::Index s = 0; s < S; ++s) {
        for (const auto& [c, j] : load_columns)
          W(6 * s + j, c) = term_column(term::load, qd(s, j), qdd(s, j), load(s, j));
      }
    }
    const Eigen::VectorXd phi = W.colPivHouseholderQr().solve(y);
    Eigen::MatrixXd next(S, 6);
    for (Eigen::Index s = 0; s < S; ++s) {
      next.row(s) = (Y0[static_cast<size_t>(s)] * phi.head<Robot::kNumBase>()).transpose();
    }
    const double change = (next - load).cwiseAbs().maxCoeff();
    load = next;
    if (change < tol) break;
  }
  return load;
}

}  // namespace dyncal::host
