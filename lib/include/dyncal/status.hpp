#pragma once

namespace dyncal {

/// Outcome of every updater call in lib/. Nothing in lib/ fails silently: a call that does not
/// return `ok` has left the estimator state exactly as it was before the call.
enum class UpdateStatus {
  ok,
  rejected_non_finite,    ///< an input (regressor, torque, weight) was NaN or infinite
  rejected_outlier,       ///< innovation beyond the gate (|e| > gate * sqrt(innovation variance))
  not_positive_definite,  ///< a variance or innovation variance was <= 0
  rank_deficient,         ///< the accumulated regressor does not determine every parameter
  invalid_argument,       ///< a configuration value out of its documented range
  not_ready,              ///< accepted, but no output yet (a filter still filling its history)
};

/// Stable lower-case name of a status, for logs and reports.
constexpr const char* to_string(UpdateStatus s) noexcept {
  switch (s) {
    case UpdateStatus::ok:
      return "ok";
    case UpdateStatus::rejected_non_finite:
      return "rejected_non_finite";
    case UpdateStatus::rejected_outlier:
      return "rejected_outlier";
    case UpdateStatus::not_positive_definite:
      return "not_positive_definite";
    case UpdateStatus::rank_deficient:
      return "rank_deficient";
    case UpdateStatus::invalid_argument:
      return "invalid_argument";
    case UpdateStatus::not_ready:
      return "not_ready";
  }
  return "unknown";
}

}  // namespace dyncal
