#include "dyncal_host/identification/pipeline/identify.hpp"

#include <cmath>
#include <cstdio>
#include <utility>

#include "dyncal/friction.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/number_text.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "dyncal_host/identification/pipeline/identify_pipeline.hpp"
#include "dyncal_host/identification/pipeline/poor_fit.hpp"
#include "dyncal_host/logs/uniform_grid.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {
namespace {

// Every option range-checked against what it means on this log, before any work (issue 23, fault 8).
// The bounds follow from the processing, not from tuning: the zero-phase filter correlates samples
// over about one cut-off period 1/fc, so a validation block or a validated tail shorter than that
// shares its noise with the fit (leaky validation); one cut-off period is dropped at each end of
// the log, so the log must last more than two.
void check_options(const IdentifyOptions& o, const JointLog& log) {
  if (o.method == "iv") {
    if (!o.closed_loop)
      throw InputError("--method iv needs --law FILE: the drive's control law the run was recorded under");
    if (o.terms != kFrictionEq7 || !o.effects.empty())
      throw InputError(
          "--method iv fits --model eq7: the closed-loop simulation models the rigid body with Coulomb "
          "and viscous friction");
  }
  if (!o.effects.empty() && (o.method == "kf" || o.method == "rls"))
    throw InputError("--method " + o.method + ": a model with effect terms is fitted by wls, ols, pcls, gd, ga or pf");
  if (o.sign_constraints && o.method != "wls" && o.method != "ols")
    throw InputError("--sign-constraints: method wls or ols, not " + o.method);
  if (o.sign_constraints && !o.effects.empty())
    throw InputError("--sign-constraints: a model of compiled terms only (no effect terms)");
  if (o.filter_order < 2 || o.filter_order > kMaxFilterOrder || o.filter_order % 2 != 0)
    throw InputError("--filter-order " + std::to_string(o.filter_order) + " must be even, 2.." +
                     std::to_string(kMaxFilterOrder) + " (cascaded second-order sections)");
  const double fs = 1.0 / log.sample_period();
  const double duration = log.duration();
  if (!(o.cutoff_hz > 0.0) || !(o.cutoff_hz < 0.5 * fs))
    throw InputError("--cutoff " + number_text(o.cutoff_hz) + " Hz must lie in (0, " + number_text(0.5 * fs) +
                     ") Hz, below the Nyquist frequency of the log's " + number_text(fs) + " Hz");
  if (!(o.cutoff_hz * duration > 2.0))
    throw InputError("--cutoff " + number_text(o.cutoff_hz) + " Hz: one cut-off period is dropped at each end of the " +
                     number_text(duration) + " s log, so the cut-off must exceed " + number_text(2.0 / duration) +
                     " Hz");
  if (o.decimate < 0) throw InputError("--decimate " + std::to_string(o.decimate) + " must be >= 0 (0: automatic)");
  const double period = 1.0 / o.cutoff_hz;
  if (o.validate_last != 0.0) {
    if (!(o.validate_last > 0.0 && o.validate_last <= 0.9))
      throw InputError("--validate-last " + number_text(o.validate_last) + " must lie in (0, 0.9]");
    if (!(o.validate_last * duration >= period))
      throw InputError("--validate-last " + number_text(o.validate_last) + " validates " +
                       number_text(o.validate_last * duration) + " s, less than one cut-off period (" +
                       number_text(period) + " s) of the filtered data: validation would share the fit's noise");
  } else {
    if (o.folds < 2) throw InputError("--folds " + std::to_string(o.folds) + " must be >= 2");
    if (!(o.block_seconds >= period) || !std::isfinite(o.block_seconds))
      throw InputError("--block " + number_text(o.block_seconds) + " s must be at least one cut-off period (" +
                       number_text(period) +
                       " s): shorter blocks share their filtered noise with the neighbouring folds");
    if (!(o.block_seconds * o.folds <= duration))
      throw InputError("--folds " + std::to_string(o.folds) + " of --block " + number_text(o.block_seconds) +
                       " s need at least " + number_text(o.block_seconds * o.folds) + " s of log, this one lasts " +
                       number_text(duration) + " s");
  }
  if (!(o.rls_mu > 0.0 && o.rls_mu <= 1.0)) throw InputError("--mu " + number_text(o.rls_mu) + " must lie in (0, 1]");
  if (!(o.p0 > 0.0) || !std::isfinite(o.p0)) throw InputError("--p0 " + number_text(o.p0) + " must be finite and > 0");
  if (!(o.prior_std >= 0.0 && o.prior_std <= 1e6))
    throw InputError("--prior-std " + number_text(o.prior_std) + " must lie in [0, 1e6] (0: no prior)");
  if (!(o.range_width > 0.0 && o.range_width <= 10.0))
    throw InputError("--range-width " + number_text(o.range_width) + " must lie in (0, 10]");
  if (o.search_evaluations < 0 || o.search_evaluations > 10000000)
    throw InputError("--evaluations " + std::to_string(o.search_evaluations) + " must lie in [0, 1e7] (0: default)");
  if (!(o.min_speed_fraction >= 0.0 && o.min_speed_fraction < 1.0))
    throw InputError("--min-speed " + number_text(o.min_speed_fraction) + " must lie in [0, 1)");
}

/// The log on a uniform grid (uniform_grid.hpp: gaps longer than bridgeable_gap(cutoff) split it),
/// checked against the robot and the options; the sampling summary into *note.
const CompiledRobot& checked(const RobotDescription& robot, JointLog raw, const IdentifyOptions& options, JointLog& log,
                             std::string& note) {
  const CompiledRobot& c = compiled_robot_for(robot);
  if (raw.joints() != c.num_joints) {
    throw InputError("the log has " + std::to_string(raw.joints()) + " joints, robot '" + robot.name + "' " +
                     std::to_string(c.num_joints));
  }
  SamplingReport report;
  // A cut-off that is no frequency splits nothing here; check_options then names it.
  const bool valid_cutoff = options.cutoff_hz > 0.0 && std::isfinite(options.cutoff_hz);
  const double max_gap = valid_cutoff ? bridgeable_gap(options.cutoff_hz) : INFINITY;
  log = to_uniform_grid(std::move(raw), max_gap, report);
  note = describe(report, max_gap);
  check_options(options, log);
  return c;
}

}  // namespace

IdentifyResult identify(const RobotDescription& robot, JointLog raw, const IdentifyOptions& options) {
  JointLog log;
  std::string note;
  const JointLogFacts facts = joint_log_facts(raw);  // for the notes on joints that fit badly
  const CompiledRobot& c = checked(robot, std::move(raw), options, log, note);
  IdentifyResult r = run_identify(robot, term_set_model(c, options.terms), std::move(log), options);
  r.notes.insert(r.notes.begin(), note);
  for (std::string& n : poor_fit_notes(facts, robot, r.joints)) r.notes.push_back(std::move(n));
  return r;
}

StackedData prepare_stacked(const RobotDescription& robot, const JointLog& raw, const IdentifyOptions& options) {
  JointLog log;
  std::string note;
  const CompiledRobot& c = checked(robot, raw, options, log, note);  // a copy: the caller keeps raw
  StackedData d = IdentifyPipeline(robot, options, term_set_model(c, options.terms)).prepare(std::move(log), true);
  d.notes.insert(d.notes.begin(), note);
  return d;
}

}  // namespace dyncal::host
