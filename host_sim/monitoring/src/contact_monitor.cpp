#include "dyncal_host/monitoring/contact_monitor.hpp"

#include <algorithm>
#include <cmath>
#include <memory>

#include "dyncal/centred_slope.hpp"
#include "dyncal/contact_threshold.hpp"
#include "dyncal/friction_uncertainty.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "dyncal_host/logs/uniform_grid.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/drive_table.hpp"

namespace dyncal::host {
namespace {

/// The longest velocity window run_observer takes: 2 * 512 + 1 samples.
constexpr int kMaxSlopeHalfWidth = 512;
using Slope = CentredSlope<double, kMaxRobotDescriptionJoints, kMaxSlopeHalfWidth>;

/// Samples at the start of a segment that the statistics skip: 5 time constants.
Eigen::Index start_up(double gain, double period) {
  return static_cast<Eigen::Index>(std::ceil(5.0 / (gain * period)));
}

double positive_number(const nlohmann::json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || !j[key].is_number() || !(j[key].get<double>() > 0.0) || !std::isfinite(j[key].get<double>()))
    throw InputError(where + ": \"" + key + "\" is missing or not a positive number");
  return j[key].get<double>();
}

}  // namespace

double default_observer_gain(double period) {
  return std::min(4.0 / kContactDetectionTime, 1.0 / period);
}

namespace {

/// `log` on a uniform grid, bridging gaps up to pi / K of the default gain; the observer's period and
/// gain (K dt <= 1; a gain up to lower_gain_within above it lowered to 1 / dt) into `run`, with the
/// grid's note. Throws InputError for a gain the discrete observer cannot run.
void to_observer_grid(JointLog& log, double gain, double lower_gain_within, ObserverRun& run) {
  SamplingReport sampling;
  const double raw_period = log.sample_period();
  const double planned = gain > 0 ? gain : default_observer_gain(raw_period);
  const double max_gap = M_PI / planned;
  log = to_uniform_grid(std::move(log), max_gap, sampling);
  run.period = log.sample_period();
  run.gain = gain > 0 ? gain : default_observer_gain(run.period);
  if (run.gain * run.period > 1.0 && run.gain * run.period <= 1.0 + lower_gain_within) run.gain = 1.0 / run.period;
  if (run.gain * run.period > 1.0)
    throw InputError("observer gain " + std::to_string(run.gain) +
                     " 1/s: the discrete observer needs K dt <= 1, at most " + std::to_string(1.0 / run.period) +
                     " 1/s for this log");
  run.notes.push_back(describe(sampling, max_gap));
}

/// A log without qd: its velocity (and the direct residual's acceleration) from the centred slope of q
/// over the gain's window, tau weighted as the slope weights it, the rest flags, each segment shortened
/// by the window's half width (run.segments, run.delay, run.still). Throws InputError (a window longer
/// than kMaxSlopeHalfWidth allows, a sample that is not finite).
void slope_velocity(const JointLog& log, bool direct, ObserverRun& run, Eigen::MatrixXd& qd, Eigen::MatrixXd& tau,
                    Eigen::MatrixXd& qdd, const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments) {
  const Eigen::Index S = log.samples();
  const int N = log.joints();
  // The velocity at sample m: the slope of the least-squares line through q_{m-D} .. q_{m+D}
  // (lib/ centred_slope.hpp, as a drive runs it), D = 1 / (K dt) samples, so that the observer
  // takes q, qd and tau of one instant, D dt after it online, tau weighted over the window as the
  // slope weights the acceleration (a stop or start's acceleration step then leaves no residual).
  // A difference of neighbouring samples carries the encoder's quantisation straight into
  // p = M qd and the residual (K M a quantum per period, in sparse impulses on a slow joint:
  // tails far heavier than Gaussian).
  const Eigen::Index D = centred_slope_half_width(run.gain, run.period);
  if (D > kMaxSlopeHalfWidth)
    throw InputError("observer gain " + std::to_string(run.gain) + " 1/s: its velocity window of " +
                     std::to_string(2 * D + 1) + " samples is longer than " +
                     std::to_string(2 * kMaxSlopeHalfWidth + 1) + "; a gain of at least " +
                     std::to_string(1.0 / (kMaxSlopeHalfWidth * run.period)) + " 1/s");
  run.delay = static_cast<double>(D) * run.period;
  qd = Eigen::MatrixXd::Zero(S, N);
  if (direct) qdd = Eigen::MatrixXd::Zero(S, N);
  run.still = Eigen::MatrixXi::Zero(S, N);
  const auto slope = std::make_unique<Slope>();  // lib/ centred_slope.hpp, as a drive runs it
  Slope::Vec q_in = Slope::Vec::Zero(), tau_in = Slope::Vec::Zero(), q_c, qd_c, qdd_c, tau_c;
  Slope::Flags still;
  for (const auto& [a, b] : segments) {
    if (b - a < 2 * D + 3) continue;
    slope->reset(static_cast<int>(D), run.period, N);
    for (Eigen::Index m = a; m < b; ++m) {
      q_in.head(N) = log.q.row(m).transpose();
      tau_in.head(N) = log.tau.row(m).transpose();
      const UpdateStatus st = direct ? slope->update(q_in, tau_in, q_c, qd_c, qdd_c, tau_c, still)
                                     : slope->update(q_in, tau_in, q_c, qd_c, tau_c, still);
      if (st == UpdateStatus::rejected_non_finite)
        throw InputError("sample " + std::to_string(m + 1) + " of the log is not finite");
      if (st != UpdateStatus::ok) continue;
      qd.row(m - D) = qd_c.head(N).transpose();
      tau.row(m - D) = tau_c.head(N).transpose();
      if (direct) qdd.row(m - D) = qdd_c.head(N).transpose();
      run.still.row(m - D) = still.head(N).transpose();
    }
    run.segments.emplace_back(a + D, b - D);
  }
  run.notes.push_back("velocity: the slope of q over " + std::to_string(2 * D + 1) +
                      " samples (the log has none), centred: an online observer runs " + std::to_string(D) +
                      " samples (" + std::to_string(run.delay * 1e3) + " ms) behind the log");
}

/// run.band: `band` when given (one per joint), else kStandstillQuantile times the white-noise std
/// of the velocity one sample resolves.
void standstill_band(const JointLog& log, const Eigen::MatrixXd& qd, const std::vector<double>& band,
                     ObserverRun& run) {
  const Eigen::Index S = log.samples();
  const int N = log.joints();
  if (!band.empty()) {
    if (static_cast<int>(band.size()) != N) throw InputError("the standstill band is not one per joint");
    run.band = band;
  } else {
    // The velocity one sample resolves: a backward difference of q (the log's qd when it has one),
    // whose noise holds the encoder's quantisation and the motion's own fast fluctuation (a PD loop
    // answering that quantisation) that the slope over the window smooths away: where the true
    // velocity may cross 0 within it, the friction's sign is unknown.
    Eigen::MatrixXd qd_sample = qd;
    if (!log.has_qd) {
      qd_sample = Eigen::MatrixXd::Zero(S, N);
      for (const auto& [a, b] : run.segments)
        for (Eigen::Index m = a; m < b; ++m) qd_sample.row(m) = (log.q.row(m) - log.q.row(m - 1)) / run.period;
    }
    const Eigen::VectorXd noise = white_noise_std(qd_sample, run.segments);
    for (int j = 0; j < N; ++j) run.band.push_back(kStandstillQuantile * noise[j]);
  }
}

/// run.friction_weight: lib/ friction_uncertainty.hpp's weight per sample, restarted per segment.
void friction_weights(const Eigen::MatrixXd& qd_friction, ObserverRun& run) {
  const Eigen::Index S = qd_friction.rows();
  const int N = static_cast<int>(qd_friction.cols());
  run.friction_weight = Eigen::MatrixXd::Zero(S, N);
  using Uncertainty = FrictionUncertainty<double, kMaxRobotDescriptionJoints>;
  Uncertainty uncertainty;
  Uncertainty::Vec v = Uncertainty::Vec::Zero(), w;
  Uncertainty::Flags still = Uncertainty::Flags::Zero();
  for (const auto& [a, b] : run.segments) {
    uncertainty.reset(run.gain, run.period, N);
    for (Eigen::Index m = a; m < b; ++m) {
      v.head(N) = qd_friction.row(m).transpose();
      still.head(N) = run.still.row(m).transpose();
      uncertainty.update(v, still, w);
      run.friction_weight.row(m) = w.head(N).transpose();
    }
  }
}

}  // namespace

ObserverRun run_observer(const RobotDescription& robot, JointLog log, const ParameterSet& params, double gain,
                         const std::vector<double>& band, ResidualKind kind, double lower_gain_within) {
  if (params.robot != robot.name)
    throw InputError("the parameters are for robot '" + params.robot + "', not '" + robot.name + "'");
  const CompiledRobot& compiled = compiled_robot_for(robot);
  ObserverRun run;
  run.kind = kind;
  const bool direct = kind == ResidualKind::direct;
  if (direct && log.has_qd)
    throw InputError("the direct residual takes its acceleration from the window of q: not from a log with qd");
  std::vector<std::string> notes;
  const ParameterTable table = parameter_table(params, robot, &notes);
  // The grid first (its period sets the default gain), bridging gaps up to pi / K of the default.
  to_observer_grid(log, gain, lower_gain_within, run);
  run.notes.insert(run.notes.end(), notes.begin(), notes.end());
  const Eigen::Index S = log.samples();
  const int N = log.joints();
  Eigen::MatrixXd qd = log.qd;
  Eigen::MatrixXd tau = log.tau;  // the observer's torque: the slope's weighting of it without qd
  Eigen::MatrixXd qdd;            // the direct residual's acceleration
  const std::vector<std::pair<Eigen::Index, Eigen::Index>> segments = log.segments();
  if (!log.has_qd) {
    slope_velocity(log, direct, run, qd, tau, qdd, segments);
  } else {
    run.segments = segments;
    run.notes.push_back("velocity: the log's qd");
  }
  if (run.segments.empty()) throw InputError("the log has no segment long enough for the observer");
  // The friction terms' velocity: qd, 0 inside the standstill band (identification's rule: the
  // velocity's white-noise std times kStandstillQuantile; a joint at rest reads above it on 0.1 % of
  // its samples). The sign of a raw difference instead flickers with the encoder's counts at low
  // speed (tried: 20 times the false alarms on smooth motion).
  standstill_band(log, qd, band, run);
  Eigen::MatrixXd qd_friction = qd;
  if (log.has_qd) run.still = Eigen::MatrixXi::Zero(S, N);
  for (const auto& [a, b] : run.segments)
    for (Eigen::Index m = a; m < b; ++m)
      for (int j = 0; j < N; ++j)
        if (std::abs(qd(m, j)) < run.band[static_cast<size_t>(j)]) {
          qd_friction(m, j) = 0;
          if (log.has_qd) run.still(m, j) = 1;
        }
  for (int j = 0; j < N; ++j) {
    double fc = 0;
    for (size_t i = 0; i < params.names.size(); ++i)
      if (params.names[i] == "Fc" + std::to_string(j + 1)) fc = std::abs(params.values[static_cast<Eigen::Index>(i)]);
    run.static_friction.push_back(fc);
  }
  // The friction the model cannot know (lib/ friction_uncertainty.hpp), per segment as a drive
  // restarts it.
  friction_weights(qd_friction, run);
  run.r = Eigen::MatrixXd::Zero(S, N);
  for (const auto& [a, b] : run.segments) {
    if (direct)
      compiled.direct_residual(table, run.gain, run.period, log.q, qd, qd_friction, qdd, tau, a, b, run.r);
    else
      compiled.momentum_residual(table, run.gain, run.period, log.q, qd, qd_friction, tau, a, b, run.r);
  }
  if (direct)
    run.notes.push_back(
        "residual: direct, the model's torque error with qdd from the window's parabola, low-passed by K");
  run.t = log.t;
  return run;
}

ResidualStatistics residual_statistics(const ObserverRun& run, const std::string& source) {
  const int N = static_cast<int>(run.r.cols());
  const Eigen::Index skip = start_up(run.gain, run.period);
  ResidualStatistics s;
  s.source = source;
  s.gain = run.gain;
  s.period = run.period;
  s.band = run.band;
  // Samples where the model knows the friction: 5 time constants after the joint last rested or
  // reversed (friction_weight below e^-5, the start-up's rule), as the threshold, widened by the
  // friction the model cannot know, is to hold for the rest.
  const double forgotten = std::exp(-5.0);
  const auto friction_known = [&](Eigen::Index k, int j) { return run.friction_weight(k, j) < forgotten; };
  for (int j = 0; j < N; ++j) {
    double sum = 0, sq = 0, dsq = 0;
    Eigen::Index n = 0, differences = 0;
    for (const auto& [a, b] : run.segments) {
      for (Eigen::Index k = a + skip; k < b; ++k) {
        if (!friction_known(k, j)) continue;
        sum += run.r(k, j);
        sq += run.r(k, j) * run.r(k, j);
        ++n;
        if (k > a + skip && friction_known(k - 1, j)) {
          dsq += (run.r(k, j) - run.r(k - 1, j)) * (run.r(k, j) - run.r(k - 1, j));
          ++differences;
        }
      }
    }
    if (differences < 2)
      throw InputError(source + ": no segment is longer than the observer's start-up (" + std::to_string(skip) +
                       " samples): no residual statistics");
    const double mean = sum / static_cast<double>(n);
    s.samples = std::max(s.samples, n);
    s.mean.push_back(mean);
    s.std.push_back(std::sqrt(std::max(0.0, sq / static_cast<double>(n) - mean * mean)));
    s.difference_std.push_back(std::sqrt(dsq / static_cast<double>(differences)));
    // The peak the unwidened threshold would have to clear: detect_contacts widens it by the
    // friction the model cannot know, so each sample counts by what exceeds that.
    const double fc = run.static_friction.empty() ? 0.0 : run.static_friction[static_cast<size_t>(j)];
    double peak = 0;
    for (const auto& [a, b] : run.segments)
      for (Eigen::Index k = a + skip; k < b; ++k)
        peak = std::max(peak, std::abs(run.r(k, j) - mean) - run.friction_weight(k, j) * fc);
    s.peak.push_back(peak);
  }
  return s;
}

nlohmann::json residual_statistics_json(const ResidualStatistics& s) {
  nlohmann::json joints = nlohmann::json::array();
  for (size_t j = 0; j < s.mean.size(); ++j)
    joints.push_back({{"joint", j + 1},
                      {"band", s.band[j]},
                      {"mean", s.mean[j]},
                      {"std", s.std[j]},
                      {"difference_std", s.difference_std[j]},
                      {"peak", s.peak[j]}});
  return {{"source", s.source}, {"gain", s.gain}, {"period", s.period}, {"samples", s.samples}, {"joints", joints}};
}

ResidualStatistics read_residual_statistics(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw InputError(where + ": \"monitor\" is not an object");
  ResidualStatistics s;
  s.source = j.value("source", std::string());
  s.gain = positive_number(j, "gain", where);
  s.period = positive_number(j, "period", where);
  s.samples = static_cast<Eigen::Index>(positive_number(j, "samples", where));
  if (!j.contains("joints") || !j["joints"].is_array() || j["joints"].empty())
    throw InputError(where + ": \"monitor\" has no \"joints\"");
  for (const auto& e : j["joints"]) {
    if (!e.contains("mean") || !e["mean"].is_number() || !std::isfinite(e["mean"].get<double>()))
      throw InputError(where + ": a joint's \"mean\" is missing or not a number");
    s.mean.push_back(e["mean"].get<double>());
    s.std.push_back(positive_number(e, "std", where));
    s.difference_std.push_back(positive_number(e, "difference_std", where));
    s.peak.push_back(positive_number(e, "peak", where));
    if (!e.contains("band") || !e["band"].is_number() || !(e["band"].get<double>() >= 0.0))
      throw InputError(where + ": a joint's \"band\" is missing or negative");
    s.band.push_back(e["band"].get<double>());
  }
  return s;
}

std::vector<ContactThreshold> contact_thresholds(const ResidualStatistics& s, double alarms_per_hour) {
  if (!(alarms_per_hour > 0.0) || !std::isfinite(alarms_per_hour))
    throw InputError("the false-alarm rate must be a positive number per hour");
  const int N = static_cast<int>(s.std.size());
  std::vector<ContactThreshold> c;
  for (int j = 0; j < N; ++j) {
    const size_t i = static_cast<size_t>(j);
    ContactThreshold t;
    t.gaussian = contact_threshold(s.std[i], s.difference_std[i], s.period, N, alarms_per_hour / 3600.0);
    if (!std::isfinite(t.gaussian)) throw InputError("joint " + std::to_string(j + 1) + " has no residual statistics");
    t.peak_bound = s.peak[i] > t.gaussian;
    t.value = t.peak_bound ? s.peak[i] : t.gaussian;
    c.push_back(t);
  }
  return c;
}

double statistics_rate_tolerance(const ResidualStatistics& s, const std::vector<ContactThreshold>& thresholds) {
  double z = 0;
  for (size_t j = 0; j < thresholds.size() && j < s.std.size(); ++j)
    if (s.std[j] > 0) z = std::max(z, thresholds[j].gaussian / s.std[j]);
  return z > 0 ? std::log(2.0) / (z * z) : 0.0;
}

double contact_limit(const ObserverRun& run, const std::vector<ContactThreshold>& thresholds, Eigen::Index k, int j) {
  const size_t i = static_cast<size_t>(j);
  return thresholds[i].value + run.friction_weight(k, j) * run.static_friction[i];
}

std::vector<Contact> detect_contacts(const ObserverRun& run, const ResidualStatistics& s,
                                     const std::vector<ContactThreshold>& thresholds) {
  const int N = static_cast<int>(run.r.cols());
  const double memory = 1.0 / run.gain;
  const auto limit = [&](Eigen::Index k, int j) { return contact_limit(run, thresholds, k, j); };
  std::vector<Contact> out;
  for (const auto& [a, b] : run.segments) {
    bool open = false;
    for (Eigen::Index k = a; k < b; ++k) {
      int first = 0;
      bool any = false;
      for (int j = 0; j < N; ++j) {
        const double e = std::abs(run.r(k, j) - s.mean[static_cast<size_t>(j)]);
        if (e > limit(k, j)) {
          if (!any) first = j + 1;
          any = true;
        }
      }
      if (any && !open) {
        // A new contact, or the last one again within the observer's memory.
        const bool merge = !out.empty() && run.t[k] - out.back().end < memory && out.back().end >= run.t[a];
        if (!merge) {
          Contact c;
          c.start = run.t[k];
          c.detected = run.t[k] + run.delay;
          c.first_joint = first;
          c.peak.assign(static_cast<size_t>(N), 0.0);
          out.push_back(c);
        }
        open = true;
      }
      if (open) {
        Contact& c = out.back();
        for (int j = 0; j < N; ++j) {
          const double e = std::abs(run.r(k, j) - s.mean[static_cast<size_t>(j)]);
          c.peak[static_cast<size_t>(j)] = std::max(c.peak[static_cast<size_t>(j)], e);
          if (e > limit(k, j) && std::find(c.joints.begin(), c.joints.end(), j + 1) == c.joints.end())
            c.joints.push_back(j + 1);
        }
        c.end = run.t[k];
        if (!any) open = false;
      }
    }
  }
  for (auto& c : out) std::sort(c.joints.begin(), c.joints.end());
  return out;
}

}  // namespace dyncal::host
