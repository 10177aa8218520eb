// Why a joint fits badly (poor_fit.hpp).
#include "dyncal_host/identification/pipeline/poor_fit.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "dyncal_host/identification/methods/signal.hpp"

namespace dyncal::host {

JointLogFacts joint_log_facts(const JointLog& raw) {
  const int n = raw.joints();
  JointLogFacts f;
  f.q_span.assign(static_cast<size_t>(n), 0.0);
  f.tau_quantum.assign(static_cast<size_t>(n), 0.0);
  f.tau_std.assign(static_cast<size_t>(n), 0.0);
  f.tau_noise.assign(static_cast<size_t>(n), 0.0);
  if (raw.samples() < 5) return f;
  const Eigen::VectorXd noise = white_noise_std(raw.tau, raw.segments());
  for (int j = 0; j < n; ++j) f.tau_noise[static_cast<size_t>(j)] = noise[j];
  for (int j = 0; j < n; ++j) {
    const size_t i = static_cast<size_t>(j);
    f.q_span[i] = raw.q.col(j).maxCoeff() - raw.q.col(j).minCoeff();
    const double mean = raw.tau.col(j).mean();
    f.tau_std[i] = std::sqrt((raw.tau.col(j).array() - mean).square().mean());
    double quantum = std::numeric_limits<double>::infinity();
    for (const auto& [a, b] : raw.segments())
      for (Eigen::Index k = a + 1; k < b; ++k) {
        const double step = std::abs(raw.tau(k, j) - raw.tau(k - 1, j));
        if (step > 0) quantum = std::min(quantum, step);
      }
    f.tau_quantum[i] = std::isfinite(quantum) ? quantum : 0.0;
  }
  return f;
}

std::vector<std::string> poor_fit_notes(const JointLogFacts& facts, const RobotDescription& robot,
                                        const std::vector<JointMetrics>& joints) {
  std::vector<std::string> notes;
  for (const JointMetrics& m : joints) {
    if (!(m.r2 < kPoorFitR2)) continue;
    const size_t i = static_cast<size_t>(m.joint - 1);
    if (i >= facts.q_span.size()) continue;
    char text[300];
    if (std::isfinite(m.r2))
      std::snprintf(text, sizeof text, "joint %d fits badly (cross-validated R^2 %.3g, residual %.3g Nm RMS):", m.joint,
                    m.r2, m.rms);
    else
      std::snprintf(text, sizeof text,
                    "joint %d fits badly (R^2 undefined: its filtered torque does not vary):", m.joint);
    std::string note = text;
    bool cause = false;
    const double range = robot.q_max[static_cast<Eigen::Index>(i)] - robot.q_min[static_cast<Eigen::Index>(i)];
    if (range > 0 && facts.q_span[i] < 0.1 * range) {
      std::snprintf(text, sizeof text, " it moved over %.3g %% of its range (%.3g of %.3g rad): too little motion;",
                    100 * facts.q_span[i] / range, facts.q_span[i], range);
      note += text;
      cause = true;
    }
    const double rounding = facts.tau_quantum[i] / std::sqrt(12.0);
    if (facts.tau_quantum[i] > 0 && rounding >= 0.3 * m.rms) {
      std::snprintf(text, sizeof text,
                    " its effort comes in steps of %.3g Nm, whose rounding alone is %.3g Nm RMS (%.0f %% of the "
                    "residual): effort quantised;",
                    facts.tau_quantum[i], rounding, 100 * rounding / std::max(m.rms, 1e-300));
      note += text;
      cause = true;
    }
    if (facts.tau_noise[i] >= 0.5 * facts.tau_std[i]) {
      std::snprintf(text, sizeof text,
                    " its torque's sample-to-sample noise, %.3g Nm, is %.0f %% of its variation (%.3g Nm std about "
                    "its mean): the torque is near the noise;",
                    facts.tau_noise[i], 100 * facts.tau_noise[i] / std::max(facts.tau_std[i], 1e-300),
                    facts.tau_std[i]);
      note += text;
      cause = true;
    }
    if (!cause)
      note +=
          " its motion, effort resolution and torque level do not explain it: an effect the model lacks? (dyncal "
          "diagnose)";
    else
      note.pop_back();
    notes.push_back(note);
  }
  return notes;
}

}  // namespace dyncal::host
