#include "dyncal_host/calibration/stream_plan.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

StreamMode parse_stream_mode(const std::string& word) {
  if (word == "auto") return StreamMode::automatic;
  if (word == "live") return StreamMode::live;
  if (word == "trace") return StreamMode::trace;
  throw InputError("--stream '" + word + "': expected auto, live or trace");
}

namespace {

std::string count(double v) {
  return std::to_string(std::lround(v));
}

}  // namespace

StreamPlan plan_stream(StreamMode requested, const LinkCapacity& link, const std::string& run_name, long run_samples,
                       double sample_rate_hz, int periods) {
  const double duration = static_cast<double>(run_samples) / sample_rate_hz;
  const bool fits = run_samples <= link.ring_capacity;
  const std::string head =
      run_name + " run: " + std::to_string(run_samples) + " samples at " + count(sample_rate_hz) + " Hz, ";
  const std::string carries = "the link carries about " + count(link.samples_per_second) + " samples/s";
  // The upload ends when the link has carried every sample, and not before the run ends.
  const double upload_s = std::max(duration, static_cast<double>(run_samples) / link.samples_per_second);
  const std::string upload = "the drive records it in its " + std::to_string(link.ring_capacity) +
                             "-sample ring and the host uploads it during and after the run, all of it about " +
                             count(upload_s) + " s after the start";
  StreamPlan p;
  if (requested == StreamMode::trace) {
    if (!fits)
      throw InputError(head + "cannot be traced: the drive's ring holds " + std::to_string(link.ring_capacity) +
                       " samples");
    p.trace = true;
    p.line = head + "traced (--stream trace): " + upload;
    return p;
  }
  if (requested == StreamMode::live) {
    p.line = head + "live (--stream live); " + carries;
    return p;
  }
  if (link.samples_per_second >= sample_rate_hz) {
    p.line = head + "live: " + carries;
    return p;
  }
  if (fits) {
    p.trace = true;
    p.line = head + "traced: " + carries + " (too few for live); " + upload;
    return p;
  }
  const double backlog = (sample_rate_hz - link.samples_per_second) * duration;
  if (backlog <= static_cast<double>(link.ring_capacity)) {
    p.line = head + "live: " + carries + "; the backlog, about " + count(backlog) + " samples at the run's end, fits " +
             "the drive's " + std::to_string(link.ring_capacity) + "-sample ring, and the host uploads the rest after";
    return p;
  }
  // Neither: the highest rate the drive accepts (dividing its 1 kHz loop) that traces or streams
  // live, and the most periods a trace holds at this rate.
  std::string rate = "none of the drive's rates";
  for (const double fs : {1000.0, 500.0, 250.0, 200.0, 125.0, 100.0}) {
    if (fs >= sample_rate_hz) continue;
    const double samples = static_cast<double>(run_samples) * fs / sample_rate_hz;
    if (samples <= static_cast<double>(link.ring_capacity) || fs <= link.samples_per_second ||
        (fs - link.samples_per_second) * duration <= static_cast<double>(link.ring_capacity)) {
      rate = "--rate " + count(fs);
      break;
    }
  }
  const long per_period = std::max(1L, run_samples / std::max(1, periods));
  const long most_periods = link.ring_capacity / per_period;
  throw InputError(head + "neither streams live nor fits a trace: " + carries + " and the drive's ring holds " +
                   std::to_string(link.ring_capacity) + " samples; " + rate + " would" +
                   (most_periods >= 1 && most_periods < periods ? ", or " + std::to_string(most_periods) + " period" +
                                                                      (most_periods > 1 ? "s" : "") + " at this rate"
                                                                : std::string()));
}

}  // namespace dyncal::host
