#include "dyncal_host/identification/methods/autocorrelation.hpp"

#include <algorithm>

#include "dyncal_host/identification/methods/signal.hpp"

namespace dyncal::host {
namespace {

// autocorrelation_inflation from each joint's residual series over its rows with train and
// fit_row, written by series(j, e) into e (S long) in sample order; returns its length.
template <class Series>
double inflation_of_series(const StackedData& d, Series series) {
  const int N = static_cast<int>(d.q.cols());
  double rows = 0, weighted = 0;
  Eigen::VectorXd e(d.t.size());
  for (int j = 0; j < N; ++j) {
    const Eigen::Index n = series(j, e);
    if (n < 8) continue;
    const double dn = static_cast<double>(n);
    rows += dn;
    weighted += dn * dn / effective_samples(e.head(n));
  }
  return rows > 0 ? std::max(1.0, weighted / rows) : 1.0;
}

}  // namespace

double autocorrelation_inflation(const StackedData& d, const std::vector<char>& train,
                                 const Eigen::VectorXd& residual) {
  const int N = static_cast<int>(d.q.cols());
  return inflation_of_series(d, [&](int j, Eigen::VectorXd& e) {
    Eigen::Index n = 0;
    for (Eigen::Index s = 0; s < d.t.size(); ++s) {
      if (train[static_cast<size_t>(s)] && d.fit_row[s * N + j]) e[n++] = residual[s * N + j];
    }
    return n;
  });
}

double streamed_autocorrelation_inflation(const StackedData& d, const std::vector<char>& train,
                                          const Eigen::VectorXd& phi) {
  const int N = static_cast<int>(d.q.cols());
  Eigen::MatrixXd K;
  Eigen::VectorXd tau_hat(N);
  return inflation_of_series(d, [&](int j, Eigen::VectorXd& e) {
    Eigen::Index n = 0;
    for (Eigen::Index s = 0; s < d.t.size(); ++s) {
      if (!train[static_cast<size_t>(s)] || !d.fit_row[s * N + j]) continue;
      d.regressor(s, K);
      tau_hat.noalias() = K * phi;
      e[n++] = d.y[s * N + j] - tau_hat[j];
    }
    return n;
  });
}

}  // namespace dyncal::host
