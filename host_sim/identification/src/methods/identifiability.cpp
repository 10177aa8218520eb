#include "dyncal_host/identification/methods/identifiability.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

DeterminedFit determined_least_squares(const Eigen::MatrixXd& R, const Eigen::VectorXd& z, double rss, long rows,
                                       const Eigen::VectorXd& scale, double inflation, const std::vector<int>* forced) {
  const Eigen::Index P = R.cols();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Scaled parameters theta = phi / scale: a kept parameter needs kVerdictZ std(theta) <= 1.
  const Eigen::MatrixXd Rs = Eigen::MatrixXd(R.triangularView<Eigen::Upper>()) * scale.asDiagonal();
  std::vector<char> keep(static_cast<size_t>(P), 1);
  if (forced) {
    for (int i : *forced) keep[static_cast<size_t>(i)] = 0;
  } else {
    // Exactly dependent columns first (QR with column pivoting, Eigen's default rank threshold).
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Rs);
    for (Eigen::Index k = qr.rank(); k < P; ++k) keep[static_cast<size_t>(qr.colsPermutation().indices()[k])] = 0;
  }
  DeterminedFit out;
  Eigen::VectorXd theta, gram;
  std::vector<Eigen::Index> kept;
  Eigen::MatrixXd A;
  Eigen::HouseholderQR<Eigen::MatrixXd> qr;
  for (;;) {
    kept.clear();
    for (Eigen::Index i = 0; i < P; ++i)
      if (keep[static_cast<size_t>(i)]) kept.push_back(i);
    if (kept.empty()) throw InputError("the log determines none of the model's parameters: it hardly moves the arm");
    const auto K = static_cast<Eigen::Index>(kept.size());
    A.resize(P, K);
    for (Eigen::Index k = 0; k < K; ++k) A.col(k) = Rs.col(kept[static_cast<size_t>(k)]);
    qr.compute(A);
    theta = qr.solve(z);
    const double increase = (A * theta - z).squaredNorm();
    out.sigma2 = (rss + increase) / std::max(1.0, static_cast<double>(rows - K));
    // diag((A^T A)^-1) = squared row norms of Rk^-1.
    const Eigen::MatrixXd Rk = qr.matrixQR().topRows(K).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd Rinv = Rk.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(K, K));
    gram = Rinv.rowwise().squaredNorm();
    if (forced) break;
    Eigen::Index worst = -1;
    double worst_ratio = 1.0;
    for (Eigen::Index k = 0; k < K; ++k) {
      const double r = kVerdictZ * std::sqrt(out.sigma2 * inflation * gram[k]);
      if (!std::isfinite(r) || r > worst_ratio) {
        worst = k;
        worst_ratio = std::isfinite(r) ? r : std::numeric_limits<double>::infinity();
      }
    }
    if (worst < 0) break;
    keep[static_cast<size_t>(kept[static_cast<size_t>(worst)])] = 0;
  }
  out.phi = Eigen::VectorXd::Zero(P);
  out.stdev = Eigen::VectorXd::Constant(P, nan);
  out.gram_diag = Eigen::VectorXd::Constant(P, nan);
  for (size_t k = 0; k < kept.size(); ++k) {
    const Eigen::Index i = kept[k], kk = static_cast<Eigen::Index>(k);
    out.phi[i] = scale[i] * theta[kk];
    out.gram_diag[i] = scale[i] * scale[i] * gram[kk];
    out.stdev[i] = std::sqrt(out.sigma2 * inflation * out.gram_diag[i]);
  }
  for (Eigen::Index i = 0; i < P; ++i) {
    if (keep[static_cast<size_t>(i)]) continue;
    out.dropped.push_back(static_cast<int>(i));
    // Its column regressed on the kept ones: named when they explain at least half its squared norm.
    const Eigen::VectorXd c = Rs.col(i);
    const Eigen::VectorXd coef = qr.solve(c);
    std::vector<int> into;
    if (c.squaredNorm() > 0.0 && (A * coef - c).squaredNorm() <= 0.5 * c.squaredNorm()) {
      std::vector<std::pair<double, int>> share;
      for (size_t k = 0; k < kept.size(); ++k) {
        const auto kk = static_cast<Eigen::Index>(k);
        share.push_back({-std::abs(coef[kk]) * A.col(kk).norm(), static_cast<int>(kept[k])});
      }
      std::sort(share.begin(), share.end());
      const double largest = -share.front().first;
      for (const auto& s : share) {
        if (-s.first < 0.25 * largest || into.size() == 3) break;
        into.push_back(s.second);
      }
    }
    out.absorbed_into.push_back(into);
  }
  return out;
}

std::string dropped_parameters_text(const DeterminedFit& fit, const std::vector<std::string>& names) {
  std::string text;
  for (size_t d = 0; d < fit.dropped.size(); ++d) {
    text += (text.empty() ? "" : ", ") + names[static_cast<size_t>(fit.dropped[d])];
    const std::vector<int>& into = fit.absorbed_into[d];
    if (into.empty()) {
      text += " (too little excited)";
      continue;
    }
    text += " (included in ";
    for (size_t k = 0; k < into.size(); ++k) text += (k ? ", " : "") + names[static_cast<size_t>(into[k])];
    text += ")";
  }
  return text;
}

}  // namespace dyncal::host
