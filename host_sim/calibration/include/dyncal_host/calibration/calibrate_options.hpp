#pragma once
// The options of `dyncal calibrate` (calibrate.hpp).

#include <cstdint>
#include <optional>
#include <string>

#include "dyncal_host/calibration/stream_plan.hpp"
#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_port/modbus_drive.hpp"

namespace dyncal::host {

struct CalibrateOptions {
  std::string uri = "tcp://127.0.0.1:1502";
  unsigned terms = 0;  ///< identification model (dyncal::term bits)
  double sample_rate_hz = 1000;
  double f_f = 0.1;        ///< Fourier fundamental frequency [Hz] (Eq. 27)
  int harmonics = 5;       ///< L
  int periods = 2;         ///< excitation periods streamed and identified
  int verify_periods = 1;  ///< periods of the fresh verification trajectory
  int candidates = 16;     ///< random trajectories tried; the one with the smallest cond(K) plays
  /// A designed excitation (dyncal excite) to play instead of the random candidates; f_f and
  /// harmonics are then the trajectory's own.
  std::optional<linux_port::Trajectory> excitation;
  std::uint64_t seed = 1;
  double online_cutoff_hz = 20;  ///< causal low-pass of the online path
  double rls_mu = 0.9999;
  bool flash = true;
  bool diagnose = false;  ///< run dyncal diagnose on the excitation and flash the effects found
  bool progress = true;   ///< report the runs' samples as progress (progress.hpp; shown where the program set a sink)
  bool keep_trace =
      false;             ///< keep the excitation run's torque and the batch fit's prediction (CalibrateResult::trace)
  std::string save_log;  ///< if set, the excitation log is written here as CSV (dyncal identify --data)
  /// If set, the excitation run's control law is written here (docs/cli.md "Law file": trajectory,
  /// periods, rates, the drive's PD gains, the table active during the run beside it as NAME.table),
  /// what `identify --method iv --law` needs for the saved log.
  std::string save_law;
  /// Where a run that ends in a drive fault leaves the samples recorded before it.
  std::string fault_dir = ".";
  /// Live or trace per run (stream_plan.hpp): automatic picks from the link measured before the runs.
  StreamMode stream = StreamMode::automatic;
  IdentifyOptions identify = stiction_excluded();  ///< batch fit settings (terms copied from above)

  /// Batch defaults for drive data: rows of a joint below 2 % of its top speed are left out of the
  /// fit, because the excitation reverses every joint several times per period and a joint with
  /// Coulomb friction sticks at reversals (see IdentifyOptions::min_speed_fraction); friction and
  /// rotor inertia held >= 0 (IdentifyOptions::sign_constraints), since the fit becomes the drive's
  /// table and a joint with negligible friction would otherwise come out negative half the time.
  static IdentifyOptions stiction_excluded() {
    IdentifyOptions o;
    o.min_speed_fraction = 0.02;
    o.sign_constraints = true;
    return o;
  }
};

}  // namespace dyncal::host
