// Firmware application: the instructions of one control period of lib/'s drive application
// (dyncal/drive/drive_application.hpp) on the er20 drive of the drive image (port/replay/
// er20_drive.hpp), under qemu -icount. It plays three runs of 2 s (2 000 periods at 1 kHz, a sample
// every 10th) with the arm's true table (the full model: Eq. 7, rotor inertias, offsets): a plain
// run; a run watched by the collision monitor (the momentum observer, the centred slope and the
// friction weight every period, thresholds 0: every joint judged never, the work done in full);
// and a payload run watched likewise (the payload estimator's update on each recorded sample, and
// its verdict and loaded table's commit at the end). It prints the drive application's instructions
// per control period apart from the simulated arm's (RK4 of the generated model: what a real drive
// does not run), and exits 0 when every run records every sample, the true table leaves a model
// error under 2 % of the friction it cancels, and the largest period stays within the target: half
// a 1 kHz period of a 168 MHz M4F, 84 000 instructions (issue 69).
#include <cstdint>

#include "dyncal_cortex_m/flash_parameter_store.hpp"
#include "dyncal_cortex_m/instruction_counter.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/stack_usage.hpp"
#include "er20_drive.hpp"

#ifndef DYNCAL_FW_SCALAR
#define DYNCAL_FW_SCALAR float
#endif

namespace {

namespace sh = dyncal::cortex_m;
namespace mm = dyncal::modbus_map;
namespace data = dyncal::replay::data;
using Scalar = DYNCAL_FW_SCALAR;
using Counter = sh::InstructionCounter;
using Application = dyncal::replay::Er20Drive<Scalar, 64>;

constexpr long long kTargetInstructions = 84000;

/// The simulated arm with its instructions counted apart.
struct CountedArm final : dyncal::port::Joints<Scalar> {
  dyncal::replay::SimulatedArm<dyncal::replay::Er20, Scalar> arm{dyncal::replay::arm_physics(2026)};
  std::uint32_t ticks = 0;
  void place(const Scalar* q, const Scalar* qd) noexcept override { arm.place(q, qd); }
  void sense(Scalar* q) noexcept override {
    const std::uint32_t t0 = Counter::ticks();
    arm.sense(q);
    ticks += Counter::elapsed(t0, Counter::ticks());
  }
  void actuate(const Scalar* tau, Scalar* measured) noexcept override {
    const std::uint32_t t0 = Counter::ticks();
    arm.actuate(tau, measured);
    ticks += Counter::elapsed(t0, Counter::ticks());
  }
};

/// Mean and largest instructions of what it tallies.
struct Tally {
  long long sum = 0, largest = 0, count = 0;
  void add(long long instructions) {
    sum += instructions;
    largest = instructions > largest ? instructions : largest;
    ++count;
  }
  long long mean() const { return count > 0 ? sum / count : 0; }
};

CountedArm g_arm;
Application g_drive{sh::flash_parameter_store<dyncal::replay::DriveModels>(), g_arm,
                    dyncal::replay::drive_settings<Application>()};
std::uint16_t g_inputs[mm::kInputWords];

/// One run to its end as a host reading every sample would; false when it does not record every
/// sample or trips. Prints its tallies.
bool play(const char* name, mm::Command command, double monitor_gain, long long& largest) {
  dyncal::drive::MonitorSettings monitor;
  monitor.gain = monitor_gain;
  std::uint32_t t0 = Counter::ticks();
  // 3 harmonics at f_f = 0.5 Hz, one period sampled at 100 Hz, inside the er20's ranges.
  if (!g_drive.start(command, dyncal::replay::excitation_run(0.5, 1, 100, 0.3), monitor)) return false;
  const long long start = static_cast<long long>(Counter::elapsed(t0, Counter::ticks())) * 40;
  Tally application, recording, arm;
  long long last = 0;  // the call that ends the run (a payload run's verdict and commit)
  while (g_drive.state() == mm::DriveState::playing) {
    if (!g_drive.wants_period()) g_drive.ack(g_drive.produced());  // the host read the ring
    const std::uint32_t produced = g_drive.produced();
    g_arm.ticks = 0;
    t0 = Counter::ticks();
    g_drive.period();
    const long long total = static_cast<long long>(Counter::elapsed(t0, Counter::ticks())) * 40;
    if (g_drive.state() != mm::DriveState::playing) {
      last = total;
      break;
    }
    const long long in_arm = static_cast<long long>(g_arm.ticks) * 40;
    application.add(total - in_arm);
    arm.add(in_arm);
    if (g_drive.produced() != produced) recording.add(total - in_arm);
  }
  sh::write("  ");
  sh::write(name);
  sh::write(": start ");
  sh::write_int(start);
  sh::write("; per control period mean ");
  sh::write_int(application.mean());
  sh::write(", largest ");
  sh::write_int(application.largest);
  sh::write("; per recording period mean ");
  sh::write_int(recording.mean());
  sh::write("; the run's end ");
  sh::write_int(last);
  sh::write("; the simulated arm (RK4 x 2, not in a real drive) ");
  sh::write_int(arm.mean());
  sh::write("\n");
  largest = application.largest > largest ? application.largest : largest;
  return g_drive.state() == mm::DriveState::finished && g_drive.produced() == 200;
}

}  // namespace

int main() {
  sh::StackUsage::paint();
  static dyncal::ParameterTable table;
  table = dyncal::replay::true_table();
  if (g_drive.activate(table) != dyncal::TableStatus::ok) return 2;
  Counter::start();
  sh::write("dyncal firmware drive application (lib/ drive_application.hpp; er20, the full model's table), ");
  sh::write("3 runs of 2 000 control periods at 1 kHz, 200 samples each; instructions (qemu -icount, +-40):\n");
  long long largest = 0;
  bool ok = play("plain run", mm::Command::start, 0, largest);
  g_drive.publish_inputs(g_inputs);
  double error[6];
  for (int j = 0; j < 6; ++j) error[j] = mm::get_f32(g_inputs + mm::kModelErrorReg + 2 * j);
  ok = play("watched run (collision monitor, K = 200 1/s)", mm::Command::start, 200, largest) && ok;
  ok = play("watched payload run", mm::Command::identify_payload, 200, largest) && ok;
  sh::write("  largest period: ");
  sh::write_int(largest);
  sh::write(" (target ");
  sh::write_int(kTargetInstructions);
  sh::write(")\n  model error RMS(tau_cmd - tau_ff) with the true table, plain run [Nm]:");
  for (int j = 0; j < 6; ++j) {
    sh::write(" ");
    sh::write_float(error[j], 3);
    ok = ok && error[j] < 0.02 * data::kCoulomb[j];
  }
  sh::write("\n  peak stack ");
  sh::write_int(sh::StackUsage::peak_bytes());
  sh::write(" of ");
  sh::write_int(sh::StackUsage::reserved_bytes());
  sh::write(" bytes\n");
  ok = ok && largest <= kTargetInstructions;
  sh::write(ok ? "PASS\n" : "FAIL\n");
  return ok ? 0 : 1;
}
