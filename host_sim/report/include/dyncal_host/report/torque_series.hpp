#pragma once
// A log's measured and predicted torque as a report carries it for plotting: decimated so that a
// long log stays a small page, with the residual's min/max envelope so that no spike is lost.

#include <Eigen/Core>
#include <nlohmann/json.hpp>

namespace dyncal::host {

/// Points of the decimated series and buckets of the envelope (docs/report.md).
inline constexpr int kSeriesPoints = 1500;
inline constexpr int kEnvelopeBuckets = 750;

/// The "series" of a report from t (S) [s], measured and predicted torque (S x N) [Nm] and, when
/// `after` is not null, a second prediction (diagnose: with the effects found): {samples, stride,
/// t[], joints[{joint, measured[], predicted[], predicted_after[]}], residual_envelope{t[],
/// joints[{joint, min[], max[]}]}}. The series keeps every stride-th sample (stride = ceil(S /
/// kSeriesPoints)); the envelope splits the S samples into kEnvelopeBuckets consecutive buckets
/// (fewer when S is smaller) and gives each bucket's mid time and the min and max of measured -
/// predicted over all its samples. Non-finite values are written as null.
nlohmann::json torque_series_json(const Eigen::VectorXd& t, const Eigen::MatrixXd& measured,
                                  const Eigen::MatrixXd& predicted, const Eigen::MatrixXd* after = nullptr);

/// The collision monitor's residual over time for a page: {samples, t[], joints[{joint, min[], max[],
/// threshold[]}]}: the S samples in kEnvelopeBuckets consecutive buckets (fewer when S is smaller),
/// each bucket's mid time, the min and max of `residual` (S x N) [Nm] and the max of `threshold`
/// (S x N, the bound |residual| is compared with) [Nm] over its samples.
nlohmann::json residual_envelope_json(const Eigen::VectorXd& t, const Eigen::MatrixXd& residual,
                                      const Eigen::MatrixXd& threshold);

}  // namespace dyncal::host
