// The decimated torque series and residual envelope of a report (torque_series.hpp).
#include "dyncal_host/report/torque_series.hpp"

#include <algorithm>
#include <cmath>

namespace dyncal::host {
namespace {

nlohmann::json value(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
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
  nlohmann::json mid = nlohmann::json::array(), envelope = nlohmann::json::array();
  for (Eigen::Index b = 0; b < B; ++b) {
    const Eigen::Index from = b * S / B, to = (b + 1) * S / B;
    mid.push_back(0.5 * (t[from] + t[to - 1]));
  }
  for (Eigen::Index j = 0; j < N; ++j) {
    nlohmann::json lo = nlohmann::json::array(), hi = nlohmann::json::array();
    for (Eigen::Index b = 0; b < B; ++b) {
      const Eigen::Index from = b * S / B, to = (b + 1) * S / B;
      double mn = INFINITY, mx = -INFINITY;
      for (Eigen::Index s = from; s < to; ++s) {
        const double r = measured(s, j) - predicted(s, j);
        if (!std::isfinite(r)) continue;
        mn = std::min(mn, r);
        mx = std::max(mx, r);
      }
      lo.push_back(value(mn));
      hi.push_back(value(mx));
    }
    envelope.push_back({{"joint", j + 1}, {"min", lo}, {"max", hi}});
  }
  return {{"samples", S},
          {"stride", stride},
          {"t", times},
          {"joints", joints},
          {"residual_envelope", {{"t", mid}, {"joints", envelope}}}};
}

}  // namespace dyncal::host
