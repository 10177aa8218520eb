#include "dyncal_host/identification/methods/friction_fit.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "dyncal_host/identification/methods/signal.hpp"

namespace dyncal::host {

std::array<double, 2> velocity_scale_range(double max_speed) {
  const double lo = std::max(1e-3, 0.01 * max_speed);
  return {lo, std::max(lo, max_speed)};
}

std::array<double, 2> scale_parameter_range(FrictionModel model, int k, const std::array<double, 2>& v) {
  if (is_inverse_velocity(model, k)) return {1.0 / v[1], 1.0 / v[0]};
  return v;
}

std::vector<double> fit_joint_friction(FrictionModel model, const Eigen::VectorXd& qd, const Eigen::VectorXd& load,
                                       const Eigen::VectorXd& target, const std::array<double, 2>& velocity_range,
                                       std::vector<ScaleInterval>* intervals) {
  const Eigen::Index S = qd.size();
  const int kf = friction_count(model);
  std::vector<int> scale, amplitude;
  for (int k = 0; k < kf; ++k) (is_scale_parameter(model, k) ? scale : amplitude).push_back(k);
  const int per_axis = scale.size() == 1 ? 64 : (scale.size() == 2 ? 16 : 1);
  const int points = scale.size() == 2 ? per_axis * per_axis : per_axis;
  auto grid_value = [&](size_t axis, int index) {
    const auto range = scale_parameter_range(model, scale[axis], velocity_range);
    return per_axis > 1 ? range[0] * std::pow(range[1] / range[0], index / (per_axis - 1.0)) : range[0];
  };
  auto axis_index = [&](int p, size_t axis) {
    for (size_t i = 0; i < axis; ++i) p /= per_axis;
    return p % per_axis;
  };
  double best = INFINITY;
  int best_point = 0;
  std::vector<double> sse(static_cast<size_t>(points), INFINITY);
  Eigen::VectorXd best_residual = target;
  Eigen::MatrixXd A(S, static_cast<Eigen::Index>(amplitude.size()));
  std::vector<double> th(static_cast<size_t>(kf), 0.0), g(static_cast<size_t>(kf)), out = th;
  for (int p = 0; p < points; ++p) {
    for (size_t i = 0; i < scale.size(); ++i) th[static_cast<size_t>(scale[i])] = grid_value(i, axis_index(p, i));
    // The columns: d tau_f / d amplitude, which does not depend on the amplitudes.
    for (Eigen::Index s = 0; s < S; ++s) {
      friction_torque(model, th.data(), qd[s], load[s], g.data());
      for (size_t c = 0; c < amplitude.size(); ++c)
        A(s, static_cast<Eigen::Index>(c)) = g[static_cast<size_t>(amplitude[c])];
    }
    const Eigen::VectorXd a = A.colPivHouseholderQr().solve(target);
    const Eigen::VectorXd residual = A * a - target;
    sse[static_cast<size_t>(p)] = residual.squaredNorm();
    if (!(sse[static_cast<size_t>(p)] < best)) continue;
    best = sse[static_cast<size_t>(p)];
    best_point = p;
    best_residual = residual;
    for (size_t c = 0; c < amplitude.size(); ++c)
      th[static_cast<size_t>(amplitude[c])] = a[static_cast<Eigen::Index>(c)];
    out = th;
  }
  if (intervals) {
    intervals->clear();
    const double dof = std::max(1.0, static_cast<double>(S - kf));
    const double sigma2 = best / dof, weight = effective_samples(best_residual) / static_cast<double>(S);
    for (size_t i = 0; i < scale.size(); ++i) {
      std::vector<double> profile(static_cast<size_t>(per_axis), INFINITY);
      for (int p = 0; p < points; ++p) {
        double& v = profile[static_cast<size_t>(axis_index(p, i))];
        v = std::min(v, sse[static_cast<size_t>(p)]);
      }
      const int at = axis_index(best_point, i);
      int lo = at, hi = at;
      auto inside = [&](int v) {
        return sigma2 > 0 && (profile[static_cast<size_t>(v)] - best) / sigma2 * weight <= 3.84;
      };
      while (lo > 0 && inside(lo - 1)) --lo;
      while (hi < per_axis - 1 && inside(hi + 1)) ++hi;
      ScaleInterval r;
      r.parameter = scale[i];
      r.best = grid_value(i, at);
      // The interval's ends lie between the last grid point inside and the first outside: report
      // the outside ones (conservative by at most one grid step).
      r.lo = grid_value(i, std::max(lo - 1, 0));
      r.hi = grid_value(i, std::min(hi + 1, per_axis - 1));
      r.open_below = lo == 0;
      r.open_above = hi == per_axis - 1;
      intervals->push_back(r);
    }
  }
  return out;
}

}  // namespace dyncal::host
