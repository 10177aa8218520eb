// The decimated torque series, the residual envelopes of a report (torque_series.hpp).
#include "dyncal_host/report/torque_series.hpp"

#include <algorithm>
#include <cmath>

namespace dyncal::host {
namespace {

nlohmann::json value(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

/// Per bucket of [0, S) in B consecutive buckets: the min and max of f(s) over its finite values.
template <typename F>
void bucket_range(Eigen::Index S, Eigen::Index B, F f, nlohmann::json& lo, nlohmann::json& hi) {
  for (Eigen::Index b = 0; b < B; ++b) {
    double mn = INFINITY, mx = -INFINITY;
    for (Eigen::Index s = b * S / B; s < (b + 1) * S / B; ++s) {
      const double v = f(s);
      if (!std::isfinite(v)) continue;
      mn = std::min(mn, v);
      mx = std::max(mx, v);
    }
    lo.push_back(value(mn));
    hi.push_back(value(mx));
  }
}

nlohmann::json bucket_mid_times(const Eigen::VectorXd& t, Eigen::Index B) {
  const Eigen::Index S = t.size();
  nlohmann::json mid = nlohmann::json::array();
  for (Eigen::Index b = 0; b < B; ++b) mid.push_back(0.5 * (t[b * S / B] + t[(b + 1) * S / B - 1]));
  return mid;
}

}  // namespace

nlohmann::json torque_series_json(const Eigen::VectorXd& t, const Eigen::MatrixXd& measured,
                                  const Eigen::MatrixXd& predicted, const Eigen::MatrixXd* after) {
  const Eigen::Index S = t.size(), N = measured.cols();
  const Eigen::Index stride = std::max<Eigen::Index>(1, (S + kSeriesPoints - 1) / kSeriesPoints);
  nlohmann::json times = nlohmann::json::array(), joints = nlohmann::json::array();
  for (Eigen::Index s = 0; s < S; s += stride) times.push_back(t[s]);
  for (Eigen::Index j = 0; j < N; ++j) {
    nlohmann::json m = nlohmann::json::array(), p = nlohmann::json::array(), a = nlohmann::json::array();
    for (Eigen::Index s = 0; s < S; s += stride) {
      m.push_back(value(measured(s, j)));
      p.push_back(value(predicted(s, j)));
      if (after != nullptr) a.push_back(value((*after)(s, j)));
    }
    nlohmann::json joint = {{"joint", j + 1}, {"measured", m}, {"predicted", p}};
    if (after != nullptr) joint["predicted_after"] = a;
    joints.push_back(joint);
  }
  const Eigen::Index B = std::min<Eigen::Index>(kEnvelopeBuckets, S);
  nlohmann::json envelope = nlohmann::json::array();
  for (Eigen::Index j = 0; j < N; ++j) {
    nlohmann::json lo = nlohmann::json::array(), hi = nlohmann::json::array();
    bucket_range(
        S, B, [&](Eigen::Index s) { return measured(s, j) - predicted(s, j); }, lo, hi);
    envelope.push_back({{"joint", j + 1}, {"min", lo}, {"max", hi}});
  }
  return {{"samples", S},
          {"stride", stride},
          {"t", times},
          {"joints", joints},
          {"residual_envelope", {{"t", bucket_mid_times(t, B)}, {"joints", envelope}}}};
}

nlohmann::json residual_envelope_json(const Eigen::VectorXd& t, const Eigen::MatrixXd& residual,
                                      const Eigen::MatrixXd& threshold) {
  const Eigen::Index S = t.size(), N = residual.cols();
  const Eigen::Index B = std::min<Eigen::Index>(kEnvelopeBuckets, S);
  nlohmann::json joints = nlohmann::json::array();
  for (Eigen::Index j = 0; j < N; ++j) {
    nlohmann::json lo = nlohmann::json::array(), hi = nlohmann::json::array(), unused = nlohmann::json::array(),
                   bound = nlohmann::json::array();
    bucket_range(
        S, B, [&](Eigen::Index s) { return residual(s, j); }, lo, hi);
    bucket_range(
        S, B, [&](Eigen::Index s) { return threshold(s, j); }, unused, bound);
    joints.push_back({{"joint", j + 1}, {"min", lo}, {"max", hi}, {"threshold", bound}});
  }
  return {{"samples", S}, {"t", bucket_mid_times(t, B)}, {"joints", joints}};
}

}  // namespace dyncal::host
