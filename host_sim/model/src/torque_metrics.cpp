#include "dyncal_host/model/torque_metrics.hpp"

#include <algorithm>
#include <cmath>

namespace dyncal::host {

std::vector<JointMetrics> torque_metrics(const Eigen::VectorXd& y, const Eigen::VectorXd& pred, int N,
                                         const Eigen::VectorXd& tau_max) {
  return torque_metrics(
      y, N, tau_max, [&](Eigen::Index s, int j) { return !std::isnan(pred[s * N + j]); },
      [&](Eigen::Index s) { return pred.data() + s * N; });
}

std::vector<JointMetrics> torque_metrics(const Eigen::VectorXd& y, int N, const Eigen::VectorXd& tau_max,
                                         const std::function<bool(Eigen::Index s, int j)>& predicted,
                                         const std::function<const double*(Eigen::Index s)>& prediction) {
  const Eigen::Index S = y.size() / N;
  // Per joint, sums over its predicted rows in sample order (first the torque's mean, then the errors).
  Eigen::VectorXd sum_tau = Eigen::VectorXd::Zero(N), se = sum_tau, st = sum_tau, sum_abs = sum_tau, sum_abs2 = sum_tau;
  std::vector<long> n(static_cast<size_t>(N), 0);
  for (Eigen::Index s = 0; s < S; ++s) {
    for (int j = 0; j < N; ++j) {
      if (!predicted(s, j)) continue;
      sum_tau[j] += y[s * N + j];
      ++n[static_cast<size_t>(j)];
    }
  }
  Eigen::VectorXd mean_tau(N);
  for (int j = 0; j < N; ++j)
    mean_tau[j] = n[static_cast<size_t>(j)] > 0 ? sum_tau[j] / static_cast<double>(n[static_cast<size_t>(j)]) : 0.0;
  for (Eigen::Index s = 0; s < S; ++s) {
    const double* p = nullptr;
    for (int j = 0; j < N; ++j) {
      if (!predicted(s, j)) continue;
      if (!p) p = prediction(s);
      const double v = y[s * N + j];
      const double e = v - p[j];
      se[j] += e * e;
      st[j] += (v - mean_tau[j]) * (v - mean_tau[j]);
      const double a = std::abs(e) / tau_max[j];
      sum_abs[j] += a;
      sum_abs2[j] += a * a;
    }
  }
  std::vector<JointMetrics> out;
  for (int j = 0; j < N; ++j) {
    JointMetrics m;
    m.joint = j + 1;
    const long count = n[static_cast<size_t>(j)];
    if (count > 0) {
      const double dn = static_cast<double>(count);
      m.rms = std::sqrt(se[j] / dn);
      m.rms_tau = std::sqrt((st[j] + dn * mean_tau[j] * mean_tau[j]) / dn);
      m.relative_rms = m.rms / m.rms_tau;
      m.r2 = 1.0 - se[j] / st[j];
      m.e_T_abs = sum_abs[j] / dn;
      m.e_T_abs_std = std::sqrt(std::max(0.0, sum_abs2[j] / dn - m.e_T_abs * m.e_T_abs));
    }
    out.push_back(m);
  }
  return out;
}

}  // namespace dyncal::host
