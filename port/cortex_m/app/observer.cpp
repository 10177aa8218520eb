// Firmware application: the generalised-momentum observer of a calibrated drive (lib/
// momentum_observer.hpp, docs/monitor.md) over the recorded er20 drive samples
// (port/replay/er20_replay_data.hpp: q, tau at 100 Hz, const data in flash), q and qd from the
// causal differentiator as on a drive, the model the KF replay's reference estimate as a parameter
// table (what a calibrated drive holds). Runs the observer in the image's scalar (float on the
// Cortex-M4F, double on the M7) and in double beside it, prints the instructions per observer
// update, the stack and the two residuals' agreement, and exits 0 only when they agree. Then the
// rest of a drive's collision monitor step on the same samples (lib/ centred_slope.hpp with the
// window of a 1 kHz drive, D = 5, and friction_uncertainty.hpp): its instructions per sample.
#include <cmath>

#include "dyncal/centred_slope.hpp"
#include "dyncal/friction_uncertainty.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_cortex_m/instruction_counter.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/stack_usage.hpp"
#include "er20_replay_data.hpp"
#include "replay.hpp"

#ifndef DYNCAL_FW_SCALAR
#define DYNCAL_FW_SCALAR float
#endif

namespace {

using Scalar = DYNCAL_FW_SCALAR;
using Robot = dyncal::replay::Robot;
namespace data = dyncal::replay::data;
namespace sh = dyncal::cortex_m;
using Counter = sh::InstructionCounter;
constexpr bool kFloat = sizeof(Scalar) == 4;

// The image's observer and a double one (the reference: software double on the M4F), static.
dyncal::MomentumObserver<Robot, Scalar> g_observer;
dyncal::MomentumObserver<Robot, double> g_reference;
dyncal::CausalDifferentiator<Scalar, 6> g_diff;
dyncal::CausalDifferentiator<double, 6> g_diff_reference;
dyncal::ParameterTable g_table;
// The rest of a drive's monitor step: the velocity's window of a 1 kHz drive at its default gain
// (K = 200 1/s, D = round(1 / (K dt)) = 5) and the friction's uncertainty.
dyncal::CentredSlope<Scalar, 6, 8> g_slope;
dyncal::FrictionUncertainty<Scalar, 6> g_uncertainty;

/// The observer over the replay's samples against the double reference: updates, rejected ones,
/// the counter's ticks in the updates, and the sums of the squared difference, reference residual
/// and torque.
struct ObserverRun {
  int updates = 0, rejected = 0;
  std::uint32_t ticks = 0;
  double sd = 0, sr = 0, st = 0;
};

ObserverRun observe_replay() {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  using Vd = Eigen::Matrix<double, 6, 1>;
  ObserverRun r;
  for (int k = 0; k < data::kCount; ++k) {
    V q_in, tau_in, q, qd, qdd, tau;
    Vd qd_in, taud_in, q_d, qd_d, qdd_d, tau_d;
    for (int j = 0; j < 6; ++j) {
      q_in[j] = Scalar(data::kSamples[k][j]);
      tau_in[j] = Scalar(data::kSamples[k][6 + j]);
      qd_in[j] = double(data::kSamples[k][j]);
      taud_in[j] = double(data::kSamples[k][6 + j]);
    }
    const bool ready = g_diff.update(q_in, tau_in, q, qd, qdd, tau) == dyncal::UpdateStatus::ok;
    const bool ready_d = g_diff_reference.update(qd_in, taud_in, q_d, qd_d, qdd_d, tau_d) == dyncal::UpdateStatus::ok;
    if (!ready || !ready_d) continue;
    const std::uint32_t t0 = Counter::ticks();
    const dyncal::UpdateStatus s = g_observer.update(q, qd, tau);
    r.ticks += Counter::elapsed(t0, Counter::ticks());
    ++r.updates;
    if (s != dyncal::UpdateStatus::ok || g_reference.update(q_d, qd_d, tau_d) != dyncal::UpdateStatus::ok) {
      ++r.rejected;
      continue;
    }
    for (int j = 0; j < 6; ++j) {
      const double a = double(g_observer.residual()[j]), b = g_reference.residual()[j];
      r.sd += (a - b) * (a - b);
      r.sr += b * b;
      r.st += tau_d[j] * tau_d[j];
    }
  }
  return r;
}

/// The monitor step's other parts over the same samples (slope, friction weight, threshold check):
/// steps, the counter's ticks in them, alarms. False when a part refuses its settings.
struct MonitorRun {
  int steps = 0, alarms = 0;
  std::uint32_t ticks = 0;
};

bool monitor_replay(MonitorRun& r) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  if (g_slope.reset(5, Scalar(1e-3), 6, dyncal::TorqueHold::zero_order) != dyncal::UpdateStatus::ok ||
      g_uncertainty.reset(Scalar(200), Scalar(1e-3), 6) != dyncal::UpdateStatus::ok)
    return false;
  for (int k = 0; k < data::kCount; ++k) {
    V q_in, tau_in, q, qd, tau, weight;
    for (int j = 0; j < 6; ++j) {
      q_in[j] = Scalar(data::kSamples[k][j]);
      tau_in[j] = Scalar(data::kSamples[k][6 + j]);
    }
    dyncal::CentredSlope<Scalar, 6, 8>::Flags still;
    const std::uint32_t t0 = Counter::ticks();
    if (g_slope.update(q_in, tau_in, q, qd, tau, still) == dyncal::UpdateStatus::ok) {
      V qd_friction = qd;
      for (int j = 0; j < 6; ++j)
        if (std::fabs(qd[j]) < Scalar(1e-3)) qd_friction[j] = Scalar(0);
      if (g_uncertainty.update(qd_friction, still, weight) == dyncal::UpdateStatus::ok) {
        for (int j = 0; j < 6; ++j) r.alarms += std::fabs(tau[j]) > Scalar(1e6) + weight[j] ? 1 : 0;
        r.ticks += Counter::elapsed(t0, Counter::ticks());
        ++r.steps;
      }
    }
  }
  return true;
}

}  // namespace

int main() {
  sh::StackUsage::paint();
  dyncal::make_table<dyncal::replay::LinearModel>(
      Eigen::Map<const Eigen::Matrix<double, dyncal::replay::LinearModel::kNumParams, 1>>(data::kReferenceKf), g_table);
  // The default gain's rule (docs/monitor.md): 4 / 20 ms, at most the sample rate.
  const double dt = data::kSamplePeriod, gain = 4.0 / 0.02 < 1.0 / dt ? 4.0 / 0.02 : 1.0 / dt;
  using V = Eigen::Matrix<Scalar, 6, 1>;
  using Vd = Eigen::Matrix<double, 6, 1>;
  if (g_observer.configure(g_table, V::Constant(Scalar(gain)), Scalar(dt)) != dyncal::UpdateStatus::ok ||
      g_reference.configure(g_table, Vd::Constant(gain), dt) != dyncal::UpdateStatus::ok)
    return 2;
  g_diff.reset(Scalar(dt), Scalar(dyncal::replay::Settings::kCutoffHz));
  g_diff_reference.reset(dt, dyncal::replay::Settings::kCutoffHz);
  Counter::start();
  const ObserverRun run = observe_replay();
  const int updates = run.updates, rejected = run.rejected;
  const std::uint32_t ticks = run.ticks;
  const double sd = run.sd, sr = run.sr, st = run.st;
  // The monitor step's other parts over the same samples: slope, friction weight, threshold check.
  MonitorRun monitor;
  if (!monitor_replay(monitor)) return 3;
  const std::uint32_t monitor_ticks = monitor.ticks;
  const int monitor_steps = monitor.steps, alarms = monitor.alarms;
  const double difference = sr > 0 ? std::sqrt(sd / sr) : 1.0, residual = st > 0 ? std::sqrt(sr / st) : 0.0;
  // Float: the thresholds scale with the residual's RMS, so a float error within 1 % of that RMS
  // moves them by at most 1 % (the observer subtracts momenta of about the torque times the time
  // constant: float's 7 digits leave about 3). Double: rounding order only.
  const double tolerance = kFloat ? 1e-2 : 1e-9;
  sh::write("dyncal firmware momentum observer (");
  sh::write(kFloat ? "float" : "double");
  sh::write("): ");
  sh::write_int(updates);
  sh::write(" updates of the er20 drive samples, rejected ");
  sh::write_int(rejected);
  sh::write(
      "\n  instructions per observer update (mass matrix, inverse dynamics, friction, step; qemu -icount, +-40): ");
  sh::write_int(updates > 0 ? static_cast<long long>(ticks) * Counter::kInstructionsPerTick / updates : 0);
  sh::write("\n  residual against the double run: relative RMS difference ");
  sh::write_float(difference, 3);
  sh::write(" (tolerance ");
  sh::write_float(tolerance, 1);
  sh::write("); residual RMS / torque RMS ");
  sh::write_float(residual, 4);
  sh::write(
      "\n  instructions per sample for the rest of a drive's monitor step (slope of q over 11 samples, "
      "friction weight, threshold check): ");
  sh::write_int(
      monitor_steps > 0 ? static_cast<long long>(monitor_ticks) * Counter::kInstructionsPerTick / monitor_steps : 0);
  sh::write("\n  stack: peak ");
  sh::write_int(sh::StackUsage::peak_bytes());
  sh::write(" bytes of ");
  sh::write_int(sh::StackUsage::reserved_bytes());
  sh::write(" reserved\n");
  const bool ok = difference < tolerance && residual > 0 && rejected == 0 && updates > data::kCount * 9 / 10 &&
                  monitor_steps > data::kCount * 9 / 10 && alarms == 0;
  return ok ? 0 : 1;
}
