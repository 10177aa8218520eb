#pragma once
// How a drive run's samples cross the link: live (the host keeps up with the drive) or trace (the
// drive records the whole run in its ring and the host uploads it during and after the run, as a
// drive maker's scope/trace function does). docs/modbus.md "Trace".

#include <string>

namespace dyncal::host {

/// What `dyncal calibrate --stream` asks for.
enum class StreamMode { automatic, live, trace };

/// "auto", "live" or "trace" as a StreamMode. Throws InputError for any other word.
StreamMode parse_stream_mode(const std::string& word);

/// What the link and the drive offer, measured before the runs (ModbusDrive::measure_link).
struct LinkCapacity {
  double samples_per_second = 0;   ///< live: samples per block / the mean transaction time [1/s]
  double transaction_seconds = 0;  ///< the mean wall time of one ring transaction [s]
  long ring_capacity = 0;          ///< samples the drive's ring holds (register ring_capacity)
};

/// A run's way over the link and why, in one line for the user.
struct StreamPlan {
  bool trace = false;  ///< start the run with the trace command (the drive refuses a run its ring cannot hold)
  std::string
      line;  ///< e.g. "excitation run: 20000 samples at 1000 Hz, traced: the link carries about 246 samples/s ..."
};

/// Chooses how `run_name`'s run of `run_samples` samples at `sample_rate_hz` [Hz] streams:
/// - live when the link carries the rate (link.samples_per_second >= sample_rate_hz);
/// - else trace when the run fits the ring; the upload then lasts about run_samples / link rate;
/// - else live when the backlog a live stream builds, (rate - link rate) x the run's duration,
///   fits the ring (the ring absorbs it; the line says so);
/// - else neither works: throws InputError naming the highest sample rate and the most periods
///   (`periods` of the run now) that would.
/// `requested` live forces live (a loss is then reported by the drive's overrun counter as ever);
/// trace forces trace and throws InputError when the run does not fit the ring.
StreamPlan plan_stream(StreamMode requested, const LinkCapacity& link, const std::string& run_name, long run_samples,
                       double sample_rate_hz, int periods);

}  // namespace dyncal::host
