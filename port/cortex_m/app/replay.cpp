// Firmware application: replays the recorded er20 drive samples (port/replay/er20_replay_data.hpp,
// const data in flash) through the causal differentiator, the generated regressor and one updater
// (DYNCAL_FW_UPDATER: 0 KF, 1 RLS with forgetting, 2 EKF with Eq. 4 friction, 3 the friction
// tracker of a calibrated drive, 4 the payload estimator) — the same lib/ code
// as the host — in float on the Cortex-M4F and double on the M7. Prints the instructions per update
// and the estimate's agreement with the host's double run, writes the KF/RLS estimate to the flash
// parameter store and reads it back, and exits 0 only when everything holds.
#include "replay.hpp"

#include "dyncal/table_check.hpp"
#include "dyncal_cortex_m/flash_parameter_store.hpp"
#include "dyncal_cortex_m/instruction_counter.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/stack_usage.hpp"
#include "er20_joint_ratings.hpp"
#include "er20_replay_data.hpp"

#ifndef DYNCAL_FW_SCALAR
#define DYNCAL_FW_SCALAR float
#endif
#ifndef DYNCAL_FW_UPDATER
#define DYNCAL_FW_UPDATER 0
#endif

namespace {

using Scalar = DYNCAL_FW_SCALAR;
constexpr dyncal::replay::Updater kUpdater = static_cast<dyncal::replay::Updater>(DYNCAL_FW_UPDATER);
using Estimator = dyncal::replay::Estimator<Scalar, kUpdater>;
namespace data = dyncal::replay::data;
namespace sh = dyncal::cortex_m;
using Counter = sh::InstructionCounter;

// Tolerance on the relative RMS difference between the torques predicted by this run's estimate
// and by the host double run's (over the replayed samples). Double differs from the host only by
// rounding order: 1e-8. Float32 carries ~7 digits and the recursion loses as many as the data's
// conditioning takes, so its bound is set by what matters to the drive: the float estimate's
// departure from the double one stays under a tenth of the model's own residual (it then adds at
// most 0.5 % to the RMS error the drive sees, sqrt(1 + 0.1^2) - 1), whatever the data.
constexpr bool kFloat = sizeof(Scalar) == 4;
constexpr double kResidualFraction = 0.1;
double tolerance(double rel_residual) {
  return kFloat ? kResidualFraction * rel_residual : 1e-8;
}

// Static storage: no heap, no large stack frames.
Estimator g_est;
dyncal::CausalDifferentiator<Scalar, 6> g_diff;
Scalar g_reference[Estimator::kNumParams];
std::uint32_t g_ticks = 0, g_t0 = 0;
int g_updates = 0;

const double* reference() {
  switch (kUpdater) {
    case dyncal::replay::Updater::kf:
      return data::kReferenceKf;
    case dyncal::replay::Updater::rls:
      return data::kReferenceRls;
    case dyncal::replay::Updater::ekf:
      return data::kReferenceEkf;
    case dyncal::replay::Updater::payload:
      return data::kReferencePayload;
    default:
      return data::kReferenceFriction;
  }
}

// The payload estimator's arm model: the KF replay's reference (what a calibrated drive's table holds).
template <class E>
void set_arm(E& est) {
  if constexpr (kUpdater == dyncal::replay::Updater::payload) est.set_arm(data::kReferenceKf);
}

// Parameter store round trip (the linear models have a table layout; the Eq. 4 parameters of the
// EKF and the friction tracker are not a table model and are not stored, nor is a payload).
bool store_round_trip() {
  if constexpr (kUpdater == dyncal::replay::Updater::ekf || kUpdater == dyncal::replay::Updater::friction ||
                kUpdater == dyncal::replay::Updater::payload) {
    return true;
  } else {
    static dyncal::ParameterTable table;  // one table: RAM is the budget
    dyncal::make_table<dyncal::replay::LinearModel>(g_est.estimate(), table);
    auto& store = sh::flash_parameter_store<dyncal::drive::TermSets<dyncal::replay::Robot, dyncal::kFrictionEq7>>();
    const dyncal::JointRatings<6> ratings = dyncal::replay::ratings();
    store.set_ratings(ratings);
    dyncal::TableStatus reason = dyncal::TableStatus::ok;
    for (int round = 0; round < 3; ++round) {  // three writes: both slots used, newest wins
      table.values[0] += 1.0f;
      if (store.write(table, &reason) != dyncal::port::PortStatus::ok) {
        sh::write("  parameter store write failed: ");
        sh::write(dyncal::to_string(reason));
        sh::write("\n");
        return false;
      }
    }
    // Read back into the same table: the values are the estimate (float32) plus the 3 added above.
    if (store.read(table, &reason) != dyncal::port::PortStatus::ok) return false;
    if (table.count != Estimator::kNumParams) return false;
    for (int i = 0; i < table.count; ++i) {
      const float expected = static_cast<float>(g_est.estimate()[i]) + (i == 0 ? 3.0f : 0.0f);
      if (i == 0 ? !(std::fabs(table.values[0] - expected) <= 1e-5f * std::fabs(expected) + 1e-5f)
                 : table.values[i] != expected)
        return false;
    }
    // A table for another model is refused and leaves the store as it was.
    const float kept = table.values[0];
    table.model_id ^= 1u;
    dyncal::TableStatus refused = dyncal::TableStatus::ok;
    if (store.write(table, &refused) != dyncal::port::PortStatus::rejected) return false;
    if (store.read(table, &reason) != dyncal::port::PortStatus::ok || table.values[0] != kept) return false;
    // So is a table whose rigid body demands far more than the ratings (base parameters x100, a
    // unit slip; table_check.hpp), timed.
    for (int i = 0; i < dyncal::replay::LinearModel::RobotType::kNumBase; ++i) table.values[i] *= 100.0f;
    dyncal::TableStatus implausible = dyncal::TableStatus::ok;
    const std::uint32_t t0 = Counter::ticks();
    const bool refused_rb = store.write(table, &implausible) == dyncal::port::PortStatus::rejected;
    const std::uint32_t ticks = Counter::elapsed(t0, Counter::ticks());
    if (!refused_rb || implausible != dyncal::TableStatus::out_of_range) return false;
    if (store.read(table, &reason) != dyncal::port::PortStatus::ok || table.values[0] != kept) return false;
    // The whole check (all kRatedStates states) on the stored, plausible estimate.
    const std::uint32_t t1 = Counter::ticks();
    const dyncal::TableStatus plausible = dyncal::check_table<dyncal::replay::LinearModel>(table, ratings);
    const std::uint32_t check_ticks = Counter::elapsed(t1, Counter::ticks());
    if (plausible != dyncal::TableStatus::ok) return false;
    sh::write("  parameter table written to the flash store 3 times (generation ");
    sh::write_int(store.generation());
    sh::write("), read back identical; a wrong-model table refused (");
    sh::write(dyncal::to_string(refused));
    sh::write("), base parameters x100 refused (");
    sh::write(dyncal::to_string(implausible));
    sh::write(", the write with its plausibility check about ");
    sh::write_int(static_cast<long long>(ticks) * Counter::kInstructionsPerTick);
    sh::write(" instructions); the check of a plausible table at all its states about ");
    sh::write_int(static_cast<long long>(check_ticks) * Counter::kInstructionsPerTick);
    sh::write(" instructions\n");
    return true;
  }
}

// The KF's refusal on the target's own arithmetic (on the M4F, the assembler kernels'), run on the
// image's filter after the replay: P0 = 2^26 I and a regressor with one 1 per row (in a column the
// structure allows there) with r = 2^-30 make six updated diagonals exactly 0 (2^26 + 2^-30
// rounds to 2^26, L = 2^13), which must be refused with the estimate and P untouched; with
// r = 2^24 the same sample is accepted and those variances shrink (to 0.8 * 2^24).
bool refusal_check() {
#if DYNCAL_FW_UPDATER != 0
  return true;
#else
  using Model = dyncal::replay::LinearModel;
  constexpr int P = Estimator::kNumParams;
  auto& filter = g_est.filter;
  const auto structure = Model::structure();
  const auto p0 = Model::ParamVector<Scalar>::Constant(Scalar(67108864));  // 2^26
  if (filter.reset(Model::ParamVector<Scalar>::Zero(), p0, structure) != dyncal::UpdateStatus::ok) return false;
  auto& K = g_est.K;
  K.setZero();
  int column[6];
  for (int k = 0, c = 0; k < 6; ++k) {
    while (c < P && !(structure.first[c] <= k && k <= structure.last[c])) ++c;
    if (c == P) return false;
    column[k] = c;
    K(k, c++) = Scalar(1);
  }
  using V = Eigen::Matrix<Scalar, 6, 1>;
  const V y = V::Constant(Scalar(1));
  const dyncal::UpdateStatus refused = filter.update(K, y, V::Constant(Scalar(1) / Scalar(1073741824)));
  Model::ParamVector<Scalar> variances;
  filter.covariance().diagonal(variances);
  const bool untouched = filter.estimate() == Model::ParamVector<Scalar>::Zero() && variances == p0;
  const dyncal::UpdateStatus accepted = filter.update(K, y, V::Constant(Scalar(16777216)));  // r = 2^24
  filter.covariance().diagonal(variances);
  bool shrunk = true;
  for (int k = 0; k < 6; ++k) shrunk = shrunk && variances[column[k]] < p0[0] && variances[column[k]] > Scalar(0);
  sh::write("  zero posterior variance: ");
  sh::write(dyncal::to_string(refused));
  sh::write(untouched ? ", state untouched" : ", STATE CHANGED");
  sh::write("; with r = 2^24: ");
  sh::write(dyncal::to_string(accepted));
  sh::write(shrunk ? ", variances shrink\n" : ", VARIANCES WRONG\n");
  return refused == dyncal::UpdateStatus::not_positive_definite && untouched && accepted == dyncal::UpdateStatus::ok &&
         shrunk;
#endif
}

}  // namespace

int main() {
  sh::StackUsage::paint();
  set_arm(g_est);
  if (g_est.reset() != dyncal::UpdateStatus::ok) return 2;
  for (int i = 0; i < Estimator::kNumParams; ++i) g_reference[i] = Scalar(reference()[i]);
  Counter::start();
  const dyncal::replay::Counts c = dyncal::replay::run(g_est, g_diff, data::kSamples, data::kCount, data::kSamplePeriod,
                                                       data::kSigma, [](int phase) {
                                                         if (phase == 0) {
                                                           g_t0 = Counter::ticks();
                                                         } else {
                                                           g_ticks += Counter::elapsed(g_t0, Counter::ticks());
                                                           ++g_updates;
                                                         }
                                                       });
  double difference = 0, residual = 0;
  dyncal::replay::compare(g_est, g_reference, g_diff, data::kSamples, data::kCount, data::kSamplePeriod, difference,
                          residual);
  sh::write("dyncal firmware replay (");
  sh::write(dyncal::replay::name(kUpdater));
  sh::write(sizeof(Scalar) == 4 ? ", float" : ", double");
  sh::write("): ");
  sh::write_int(data::kCount);
  sh::write(" drive samples, ");
  sh::write_int(Estimator::kNumParams);
  sh::write(" parameters; updates accepted ");
  sh::write_int(c.accepted);
  sh::write(", rejected ");
  sh::write_int(c.rejected);
  sh::write(", filter warm-up ");
  sh::write_int(c.not_ready);
  sh::write("\n  instructions per update (regressor + updater, qemu -icount, +-40): ");
  sh::write_int(g_updates > 0 ? static_cast<long long>(g_ticks) * Counter::kInstructionsPerTick / g_updates : 0);
  sh::write("\n  torque predicted by this estimate vs the host double run: relative RMS difference ");
  sh::write_float(difference, 3);
  sh::write(" (tolerance ");
  sh::write_float(tolerance(residual), kFloat ? 2 : 1);
  sh::write(kFloat ? " = 0.1 x the relative residual" : "");
  sh::write("); relative residual ");
  sh::write_float(residual, 4);
  sh::write("\n");
  const bool stored = store_round_trip();
  sh::write("  stack: peak ");
  sh::write_int(sh::StackUsage::peak_bytes());
  sh::write(" bytes of ");
  sh::write_int(sh::StackUsage::reserved_bytes());
  sh::write(" reserved\n");
  const bool refusals = refusal_check();
  // residual > 0: a run whose predictions are all zero (a corrupted state) must not pass as agreeing.
  const bool ok =
      difference < tolerance(residual) && residual > 0 && c.accepted > data::kCount * 9 / 10 && stored && refusals;
  return ok ? 0 : 1;
}
