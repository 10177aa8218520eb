#include "dyncal_host/identification/pipeline/identify_pipeline.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/progress.hpp"
#include "dyncal_host/identification/methods/autocorrelation.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/identification/methods/instrumental_variables.hpp"
#include "dyncal_host/identification/methods/sign_constrained.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "dyncal_host/identification/pipeline/parameter_prior.hpp"
#include "dyncal_host/identification/pipeline/parameter_scales.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/identification/pipeline/recursive_fit.hpp"
#include "dyncal_host/logs/torque_delay.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {

namespace {

using FilteredTerm = IdentifyPipeline::FilteredTerm;

void check(UpdateStatus s) {
  if (s != UpdateStatus::ok) throw InputError(std::string("estimator rejected the data: ") + to_string(s));
}

/// The standstill band of motor m's velocity T.row(m) qd [rad/s]: the joints' bands `band`
/// combined as independent noise through the row.
double motor_band(const Eigen::MatrixXd& motor, int m, const Eigen::Ref<const Eigen::VectorXd>& band) {
  return std::sqrt((motor.row(m).transpose().cwiseProduct(band)).squaredNorm());
}

/// Sample s's regressor rows from the kept signals: the generated regressor at the filtered q,
/// qd, qdd (qdd = 0 with load), the filtered sign columns, and a coupled motor's terms at its
/// velocity v_m = T.row(m) qd through the transmission's transpose (its sign from the unfiltered
/// motor velocity with the band of its noise).
void regressor_at(const StackedData& d, Eigen::Index s, bool load, const TermSetModel& model,
                  const Eigen::MatrixXd& motor, const std::vector<int>& coupled,
                  const std::vector<FilteredTerm>& filtered, Eigen::MatrixXd& K) {
  const int N = model.num_joints;
  const Eigen::VectorXd q = d.q.row(s).transpose(), qd = d.qd.row(s).transpose();
  const Eigen::VectorXd qdd = load ? Eigen::VectorXd::Zero(N).eval() : Eigen::VectorXd(d.qdd.row(s).transpose());
  K.resize(N, model.num_params);
  model.regressor(q.data(), qd.data(), qdd.data(), K.data());
  for (size_t i = 0; i < filtered.size(); ++i) {
    const FilteredTerm& f = filtered[i];
    const double value = d.filtered_terms(s, static_cast<Eigen::Index>(i));
    if (!f.coupled) {
      K(f.m, f.col) = value;
    } else {
      for (int j = 0; j < N; ++j) K(j, f.col) = motor(f.m, j) * value;
    }
  }
  for (size_t c = 0; c < coupled.size(); ++c) {
    const int m = coupled[c];
    const double sign =
        friction_sign(d.motor_qd_raw(s, static_cast<Eigen::Index>(c)), motor_band(motor, m, d.standstill_band));
    const double vm = sign == 0.0 ? 0.0 : motor.row(m).dot(qd), am = motor.row(m).dot(qdd);
    for (const unsigned t : {term::viscous, term::rotor_inertia}) {
      const int col = model.column(t, m);
      if (col < 0) continue;
      const double value = term_column(t, vm, am, 0.0);
      for (int j = 0; j < N; ++j) K(j, col) = motor(m, j) * value;
    }
  }
}

void run_recursive(RecursiveFit& f, const StackedData& data, const std::vector<char>& train, int N,
                   const Eigen::VectorXd& noise) {
  Eigen::MatrixXd K;
  Eigen::VectorXd tau(N);
  for (Eigen::Index s = 0; s < data.t.size(); ++s) {
    if (!train[static_cast<size_t>(s)]) continue;
    data.regressor(s, K);
    tau = data.y.segment(s * N, N);
    for (int j = 0; j < N; ++j) {  // an excluded row carries no information: zero it
      if (data.fit_row[static_cast<size_t>(s * N + j)]) continue;
      K.row(j).setZero();
      tau[j] = 0.0;
    }
    check(f.update(K.data(), tau.data(), noise.data()));
  }
}

// cond(W) = cond(R): the triangular factor has the singular values of the stacked regressor.
double condition_number(const LeastSquaresFit& ls) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(ls.r_factor());
  const auto& sv = svd.singularValues();
  return sv[0] / sv[sv.size() - 1];
}

// Estimate and sqrt(diag P) of a recursive filter; cond(W) from the OLS factor of the same data.
void recursive_result(const RecursiveFit& f, const LeastSquaresFit& ls, Eigen::VectorXd& phi, Eigen::VectorXd& stdev,
                      double* cond) {
  phi = f.estimate();
  stdev = f.covariance_diagonal();
  if (cond) *cond = condition_number(ls);
}

/// Flags each Coulomb, viscous and rotor-inertia term of res.params below 0 beyond its 95 %
/// interval (ParamEstimate::contradicts_physics) and names them in a note.
void physics_check(const std::vector<std::string>& names, IdentifyResult& res) {
  std::string named;
  for (const int i : nonnegative_terms(names, 0)) {
    if (static_cast<size_t>(i) >= res.params.size()) break;
    ParamEstimate& p = res.params[static_cast<size_t>(i)];
    if (!(p.value < 0.0) || !std::isfinite(p.std) || -p.value <= kVerdictZ * p.std) continue;
    p.contradicts_physics = true;
    char v[120];
    std::snprintf(v, sizeof v, "%s = %.3g +- %.2g", p.name.c_str(), p.value, p.std);
    named += (named.empty() ? "" : ", ") + std::string(v);
  }
  if (named.empty()) return;
  res.notes.push_back("physics: " + named +
                      " (std): below 0 beyond the 95 % interval, which friction and rotor inertia cannot be: the "
                      "model lacks an effect the log holds (dyncal diagnose finds it), or the torque's sign or "
                      "transmission is wrong; a drive table refuses it (docs/accuracy.md \"Real arms\")");
}

/// Each parameter's physical scale and verdict (identifiability.hpp) into res.params, and a note
/// naming the parameters the log does not determine and what their values rest on; with --strict,
/// InputError naming them instead.
void judge_parameters(const Eigen::VectorXd& scale, const IdentifyPipeline::FitDetails& fit, const IdentifyOptions& opt,
                      const ParameterPrior& prior, const std::vector<std::string>& names, IdentifyResult& res) {
  // What a not-determined parameter's value rests on, per method, and the note's words for it.
  const std::string& m = opt.method;
  const char* basis = "held at 0";
  std::string rests = "held at 0, the fit keeps the combination the log determines";
  const bool map = prior.usable() && fit.data_share.size() > 0;
  // iv: the undetermined parameters held at the prior's mean where it has one (fit_instrumental).
  const bool held_at_prior = m == "iv" && prior.usable();
  if (map) {
    rests = "their values are the MAP estimate with robot.json's inertials and friction as prior (+-" +
            std::to_string(static_cast<int>(std::lround(100 * opt.prior_std))) +
            " %, --prior-std; each parameter's data share says how much the log adds)";
  } else if (held_at_prior) {
    rests =
        "those the log does not determine at all are held at robot.json's values (the prior's mean), the fit "
        "keeps the combination the log determines; the others are the data's wide estimates";
  } else if (m == "pcls") {
    basis = "prior";
    rests = opt.prior_std > 0 ? "their values rest on the prior (robot.json's inertials, --prior-std)"
                              : "their values rest on the consistency constraints alone (no prior)";
  } else if (is_search_method(m)) {
    basis = "search";
    rests = "their values rest on the search's start and range (robot.json's inertials, --range-width)";
  } else if (m == "kf" || m == "rls") {
    basis = "start";
    rests = "their values are the filter's start, not estimates";
  } else if (m == "wls" || m == "ols") {
    if (!prior.missing.empty()) rests += " (no prior: " + prior.missing + ")";
  }
  std::string undetermined, unsupported;
  for (size_t i = 0; i < res.params.size() && i < static_cast<size_t>(scale.size()); ++i) {
    ParamEstimate& p = res.params[i];
    const auto ii = static_cast<Eigen::Index>(i);
    p.scale = scale[ii];
    if (map) p.data_share = fit.data_share[ii];
    const bool dropped = std::find(fit.decision.dropped.begin(), fit.decision.dropped.end(), static_cast<int>(i)) !=
                         fit.decision.dropped.end();
    // The data's own std, or the reported one where it is wider (the MAP estimate's spread): a
    // verdict never claims more than the interval printed beside it.
    double data_std = fit.data_stdev.size() > ii ? fit.data_stdev[ii] : p.std;
    if (map && std::isfinite(data_std)) data_std = std::max(data_std, p.std);
    p.verdict = dropped ? Verdict::not_determined : verdict_of(data_std, p.scale);
    if (std::find(fit.held.begin(), fit.held.end(), static_cast<int>(i)) != fit.held.end()) {
      p.basis = "sign constraint";  // at its bound: the free fit has it below 0
      p.value = 0.0;
      continue;
    }
    if (p.verdict != Verdict::not_determined) continue;
    const bool has_prior = prior.usable() && prior.has[i];
    if (map) {  // the MAP estimate, or without a prior: held at 0 when dropped, else the data's wide estimate
      p.basis = has_prior ? "prior" : dropped ? "held at 0" : "least squares";
    } else if (m == "wls" || m == "ols" || m == "iv") {  // the data alone; a dropped one held
      p.basis = !dropped ? "least squares" : held_at_prior && has_prior ? "prior" : "held at 0";
    } else {
      p.basis = basis;
    }
    if (!dropped || ((map || held_at_prior) && has_prior)) undetermined += (undetermined.empty() ? "" : ", ") + p.name;
  }
  if (map || held_at_prior) {  // the dropped parameters no prior covers: held at 0 as without a prior
    DeterminedFit held;
    for (size_t k = 0; k < fit.decision.dropped.size(); ++k) {
      if (prior.has[static_cast<size_t>(fit.decision.dropped[k])]) continue;
      held.dropped.push_back(fit.decision.dropped[k]);
      held.absorbed_into.push_back(fit.decision.absorbed_into[k]);
    }
    unsupported = dropped_parameters_text(held, names);
  }
  physics_check(names, res);
  const bool by_prior = map || held_at_prior;
  std::string named = by_prior ? undetermined : dropped_parameters_text(fit.decision, names);
  if (!by_prior && !undetermined.empty()) named += (named.empty() ? "" : ", ") + undetermined;
  if (named.empty() && unsupported.empty()) return;
  if (opt.strict)
    throw InputError("--strict: the log does not determine " + named +
                     (named.empty() || unsupported.empty() ? "" : ", ") + unsupported +
                     " (95 % interval wider than the parameter's physical scale; docs/accuracy.md \"Real arms\")");
  if (!named.empty())
    res.notes.push_back(
        "not determined by this log (95 % interval wider than the parameter's physical scale, "
        "docs/accuracy.md \"Real arms\"): " +
        named + "; " + rests + " (--strict: refuse instead)");
  if (!unsupported.empty())
    res.notes.push_back(
        "not determined by this log (95 % interval wider than the parameter's physical scale, docs/accuracy.md "
        "\"Real arms\") and without a prior (robot.json holds none for rotor inertia or offsets, and its friction "
        "list none for these): " +
        unsupported + "; held at 0, the fit keeps the combination the log determines (--strict: refuse instead)");
}

}  // namespace

IdentifyPipeline::IdentifyPipeline(const RobotDescription& robot, const IdentifyOptions& options,
                                   const TermSetModel& model, const Eigen::VectorXd& effect_scales)
    : robot_(robot),
      opt_(options),
      model_(model),
      N(model.num_joints),
      P(model.num_params),
      motor_(motor_velocity_map(robot, !options.friction_per_joint, options.motors)),
      robot_coupled_(!motor_velocity_map(robot, !options.friction_per_joint, {}).isDiagonal(0.0)),
      scale_(parameter_scales(robot, model)),
      prior_(options.method == "wls" || options.method == "ols" || options.method == "iv"
                 ? parameter_prior(robot, model, options.prior_std)
                 : ParameterPrior{}) {
  scale_.tail(effect_scales.size()) = effect_scales;
  for (int m = 0; m < N; ++m) {
    for (int j = 0; j < N; ++j) {
      if (j != m && motor_(m, j) != 0.0) {
        coupled_.push_back(m);
        break;
      }
    }
  }
  for (int m = 0; m < N; ++m) {
    const bool coupled = std::find(coupled_.begin(), coupled_.end(), m) != coupled_.end();
    for (const unsigned t : {term::coulomb, term::power}) {
      const int col = model_.column(t, m);
      if (col >= 0) filtered_.push_back({t, m, col, coupled});
    }
  }
}

namespace {

/// W (and W_load with `load`) of `out` as dense matrices, from its regressor's rows.
void fill_dense_regressor(StackedData& out, bool load) {
  const int N = static_cast<int>(out.q.cols());
  const Eigen::Index kept = out.t.size(), P = static_cast<Eigen::Index>(out.names.size());
  Eigen::MatrixXd K;
  out.W.resize(kept * N, P);
  if (load) out.W_load.resize(kept * N, P);
  for (Eigen::Index s = 0; s < kept; ++s) {
    out.regressor(s, K);
    out.W.middleRows(s * N, N) = K;
    if (!load) continue;
    out.regressor(s, K, true);
    out.W_load.middleRows(s * N, N) = K;
  }
}

/// fit_row: 0 on the rows of a joint slower than min_speed_fraction of its top speed (with a note).
void leave_out_slow_rows(StackedData& out, double min_speed_fraction) {
  const int N = static_cast<int>(out.q.cols());
  const Eigen::Index kept = out.t.size();
  const Eigen::VectorXd threshold = out.qd.cwiseAbs().colwise().maxCoeff().transpose() * min_speed_fraction;
  out.fit_row.assign(static_cast<size_t>(kept * N), 1);
  for (Eigen::Index r = 0; r < kept; ++r) {
    for (int j = 0; j < N; ++j) {
      if (std::abs(out.qd(r, j)) < threshold[j]) out.fit_row[static_cast<size_t>(r * N + j)] = 0;
    }
  }
  if (min_speed_fraction > 0.0) {
    const auto slow = std::count(out.fit_row.begin(), out.fit_row.end(), 0);
    char m[200];
    std::snprintf(m, sizeof m,
                  "--min-speed %g: %.3g %% of the joint rows (slower than that fraction of the joint's top speed) "
                  "left out of the fit and of the validation metrics",
                  min_speed_fraction, 100.0 * static_cast<double>(slow) / static_cast<double>(kept * N));
    out.notes.push_back(m);
  }
}

/// The note on the standstill band (per joint [rad/s]) and the share of joint samples at rest.
std::string standstill_note(const Eigen::VectorXd& band, const StackedData& out) {
  const int N = static_cast<int>(out.q.cols());
  const Eigen::Index kept = out.t.size();
  std::string line = "standstill: an unfiltered |qd| below " + std::to_string(kStandstillQuantile).substr(0, 4) +
                     " x its own noise counts as rest (friction sign 0); dead band [rad/s]";
  char v[32];
  for (int j = 0; j < N; ++j) {
    std::snprintf(v, sizeof v, " %.3g", band[j]);
    line += v;
  }
  const double at_rest = static_cast<double>((out.qd.array() == 0.0).count()) / static_cast<double>(kept * N);
  std::snprintf(v, sizeof v, "; %.3g %%", 100.0 * at_rest);
  return line + v + " of the joint samples at rest";
}

/// Per coupled motor, a note on the joints it turns with and where its terms act.
void add_motor_notes(const std::vector<int>& coupled, const Eigen::MatrixXd& motor,
                     const std::vector<CoupledMotor>& declared_motors, StackedData& out) {
  const int N = static_cast<int>(out.q.cols());
  char v[32];
  for (const int m : coupled) {
    const bool declared = std::none_of(declared_motors.begin(), declared_motors.end(),
                                       [m](const CoupledMotor& c) { return c.motor == m; });
    std::string t = std::string(declared ? "transmission (robot.json)" : "coupled motor (model)") + ": motor " +
                    std::to_string(m + 1) + " turns with";
    std::string on;
    for (int j = 0; j < N; ++j) {
      if (motor(m, j) == 0.0) continue;
      std::snprintf(v, sizeof v, " %+.4g q%d", motor(m, j), j + 1);
      t += v;
      on += (on.empty() ? "" : ", ") + std::to_string(j + 1);
    }
    out.notes.push_back(t + "; its friction and rotor inertia terms (joint " + std::to_string(m + 1) +
                        "'s columns) act on joints " + on + " through the transmission's transpose");
  }
}

}  // namespace

StackedData IdentifyPipeline::prepare(JointLog&& log, bool dense, const Eigen::VectorXd* band_override) const {
  for (const TorqueDelay& delay : opt_.torque_delays) undo_torque_delay(log, delay);
  const double fs = 1.0 / log.sample_period();
  const ButterworthLowPass filter(opt_.filter_order, opt_.cutoff_hz, fs);
  int d = opt_.decimate > 0 ? opt_.decimate : static_cast<int>(std::floor(fs / (25.0 * opt_.cutoff_hz)));
  d = std::max(d, 1);
  const KeptSamples keep{log.segments(), static_cast<Eigen::Index>(std::ceil(fs / opt_.cutoff_hz)), d};
  const Eigen::VectorXd band = band_override ? *band_override : standstill_band(log, keep.segments);
  StackedData out;
  out.rate_hz = fs / d;
  out.cutoff_hz = opt_.cutoff_hz;
  out.filter_order = opt_.filter_order;
  out.num_base = model_.num_base;
  out.names = model_.names;
  const Eigen::Index kept = keep.count();
  long short_segments = 0;
  for (const auto& [a, b] : keep.segments) short_segments += keep.count(a, b) == 0;
  if (kept * N <= 2 * P) {
    throw InputError("too few samples (" + std::to_string(log.samples()) + ", " + std::to_string(kept) +
                     " after filtering and decimation) for " + std::to_string(P) + " parameters");
  }
  out.notes.push_back(log.has_qd
                          ? std::string("states: the log's measured qd (filtered), ") +
                                (log.has_qdd ? "its measured qdd" : "qdd differentiated from it") + "; q filtered"
                          : "states: qd and qdd differentiated from the filtered q (no measured velocity in "
                            "the log)");
  for (const TorqueDelay& delay : opt_.torque_delays) {
    char text[160];
    std::snprintf(text, sizeof text, "torque delay undone: joint %d's torque read %.4g ms later than its position",
                  delay.joint + 1, 1e3 * delay.seconds);
    out.notes.push_back(text);
  }
  if (short_segments > 0)
    out.notes.push_back(std::to_string(short_segments) + " segment(s) not longer than two cut-off periods (" +
                        std::to_string(2 * keep.edge) + " samples) left out: filtering would only see their ends");
  // The torques first, filtered in place; then their memory goes back before the rest is built.
  // Dense data keep them unfiltered too (the diagnosis finds the torque's steps in them).
  out.y.resize(kept * N);
  out.tau_raw.resize(dense ? kept : 0, N);
  if (dense) keep.for_each([&](Eigen::Index row, Eigen::Index k) { out.tau_raw.row(k) = log.tau.row(row); });
  for (const auto& [a, b] : keep.segments) {
    if (keep.count(a, b) == 0) continue;
    for (int j = 0; j < N; ++j) filter.filtfilt(log.tau.col(j).segment(a, b - a));
  }
  keep.for_each([&](Eigen::Index row, Eigen::Index k) { out.y.segment(k * N, N) = log.tau.row(row).transpose(); });
  log.tau = Eigen::MatrixXd();
  out.E.resize(kept * N, effect_column_count(opt_.effects));
  out.qd.resize(kept, N);
  out.qdd.resize(kept, N);
  // The unfiltered velocity is read by the consumers of dense data (the diagnosis' friction
  // candidates); otherwise it is not kept. A coupled motor's unfiltered velocity is.
  out.qd_raw.resize(dense ? kept : 0, N);
  out.motor_qd_raw.resize(kept, static_cast<Eigen::Index>(coupled_.size()));
  out.filtered_terms.resize(kept, static_cast<Eigen::Index>(filtered_.size()));
  out.standstill_band = band;
  Eigen::Index k = 0;
  for (const auto& [a, b] : keep.segments) {
    if (keep.count(a, b) == 0) continue;
    process_segment(log, a, b, filter, band, keep, k, out);
    k += keep.count(a, b);
  }
  // process_segment left the filtered positions in the log: they and the times become the kept q, t.
  keep_rows_in_place(log.q, keep);
  out.q = std::move(log.q);
  keep_rows_in_place(log.t, keep);
  out.t = std::move(log.t);
  out.regressor_rows = [model = model_, motor = motor_, coupled = coupled_, filtered = filtered_](
                           const StackedData& data, Eigen::Index s, bool load, Eigen::MatrixXd& K) {
    regressor_at(data, s, load, model, motor, coupled, filtered, K);
  };
  if (dense) fill_dense_regressor(out, opt_.load_regressor);
  // Rows of a joint moving slower than min_speed_fraction of its top speed stay out of the fit:
  // there a real joint sticks and Coulomb friction takes any value in [-Fc, Fc], which sgn(qd)
  // cannot represent. They are left out of the validation metrics too.
  leave_out_slow_rows(out, opt_.min_speed_fraction);
  out.notes.push_back(standstill_note(band, out));
  add_motor_notes(coupled_, motor_, opt_.motors, out);
  return out;
}

namespace {

/// Per-joint residual std of the fit phi on the training samples' fitted rows (Gautier's WLS weights;
/// KF/RLS noise): joint_noise_std.
Eigen::VectorXd ols_joint_noise(const StackedData& data, const std::vector<char>& train, const Eigen::VectorXd& phi,
                                Eigen::Index P) {
  const int N = static_cast<int>(data.q.cols());
  const Eigen::Index S = data.t.size();
  Eigen::MatrixXd K;
  Eigen::VectorXd ss = Eigen::VectorXd::Zero(N), n = Eigen::VectorXd::Zero(N);
  for (Eigen::Index s = 0; s < S; ++s) {
    if (!train[static_cast<size_t>(s)]) continue;
    data.regressor(s, K);
    for (int j = 0; j < N; ++j) {
      if (!data.fit_row[static_cast<size_t>(s * N + j)]) continue;
      const double e = data.y[s * N + j] - K.row(j).dot(phi);
      ss[j] += e * e;
      n[j] += 1;
    }
  }
  return joint_noise_std(ss, n, P);
}

}  // namespace

void IdentifyPipeline::fit(const StackedData& data, const std::vector<char>& train, Eigen::VectorXd& phi,
                           Eigen::VectorXd& stdev, FitDetails* details, const FitDetails* decided) const {
  const std::vector<int>* dropped = decided ? &decided->decision.dropped : nullptr;
  const Eigen::Index S = data.t.size();
  std::unique_ptr<LeastSquaresFit> ls = make_least_squares(model_);
  Eigen::MatrixXd K;
  Eigen::VectorXd row(P);
  // Every fitted row of the training samples, its weight from `weight` (joint); then the penalised
  // shapes' roughness rows, sqrt(n_j lambda) L on the shape's columns, weighed as joint j's rows.
  std::vector<double> fitted_rows(static_cast<size_t>(N), 0.0);
  auto add_rows = [&](auto weight) {
    std::fill(fitted_rows.begin(), fitted_rows.end(), 0.0);
    for (Eigen::Index s = 0; s < S; ++s) {
      if (!train[static_cast<size_t>(s)]) continue;
      data.regressor(s, K);
      for (int j = 0; j < N; ++j) {
        if (!data.fit_row[static_cast<size_t>(s * N + j)]) continue;
        row = K.row(j).transpose();
        check(ls->add_row(row.data(), data.y[s * N + j], weight(j)));
        fitted_rows[static_cast<size_t>(j)] += 1;
      }
    }
    for (const ShapePenalty& pen : penalties_) {
      const double scale = std::sqrt(fitted_rows[static_cast<size_t>(pen.joint)] * pen.lambda);
      for (Eigen::Index r = 0; r < pen.rows.rows(); ++r) {
        row.setZero();
        row.segment(pen.column, pen.rows.cols()) = scale * pen.rows.row(r).transpose();
        check(ls->add_row(row.data(), 0.0, weight(pen.joint)));
      }
    }
  };
  add_rows([](int) { return 1.0; });
  // OLS of the parameters the data determine (white noise: the weights need only a fit).
  Eigen::VectorXd ols_std;
  least_squares(*ls, dropped, 1.0, false, phi, ols_std, nullptr, nullptr, nullptr);
  // Per-joint residual std of the OLS fit (Gautier's WLS weights; KF/RLS noise).
  const Eigen::VectorXd sigma = ols_joint_noise(data, train, phi, P);
  // The final fit decides with the residual's autocorrelation (the std it reports are inflated so).
  const double decision_inflation = decided   ? decided->decision_inflation
                                    : details ? streamed_autocorrelation_inflation(data, train, phi)
                                              : 1.0;
  if (details) details->decision_inflation = decision_inflation;
  double* cond = details ? &details->cond : nullptr;
  const std::string& m = opt_.method;
  // ols, wls: the MAP estimate with the robot's prior where it has one (parameter_prior.hpp). The
  // data alone decide first which parameters they determine (the verdict; their std is the data's);
  // the prior then enters as pseudo-rows weighed against the data rows' residual variance, and only
  // a parameter the data do not determine and the prior does not cover is held at 0.
  MapData map_data;
  const double data_weight = details ? details->data_weight : decided ? decided->data_weight : 1.0;
  ParameterPrior search_prior;  // gd, ga, pf: the spread of what the log determines only with the prior
  if (m == "ols") {
    fit_least_squares_with_prior(*ls, dropped, decision_inflation, data_weight, phi, stdev, details, map_data);
  } else if (m == "wls" || m == "iv" || m == "pcls" || is_search_method(m)) {
    ls->reset();
    add_rows([&](int j) { return 1.0 / sigma[j]; });
    if (m == "wls" || m == "iv") {
      fit_least_squares_with_prior(*ls, dropped, decision_inflation, data_weight, phi, stdev, details, map_data);
    } else {  // the WLS solution starts the consistent fit of the same weighted data
      fit_consistent(*ls, data, train, dropped, decision_inflation, phi, stdev, details, map_data, search_prior);
    }
  } else if (m == "kf" || m == "rls") {
    UpdateStatus status = UpdateStatus::ok;
    std::unique_ptr<RecursiveFit> f =
        m == "kf" ? make_kalman_filter(model_, opt_.p0, &status) : make_rls(model_, opt_.p0, opt_.rls_mu, &status);
    check(status);
    // KF: the measurement variance sigma^2; RLS: the weight 1 / sigma.
    const Eigen::VectorXd noise =
        m == "kf" ? Eigen::VectorXd(sigma.cwiseAbs2()) : Eigen::VectorXd(sigma.cwiseInverse());
    run_recursive(*f, data, train, N, noise);
    recursive_result(*f, *ls, phi, stdev, cond);
  } else {
    throw InputError("unknown method '" + m + "' (expected wls, ols, kf, rls, pcls, gd, ga or pf)");
  }
  if (!details) return;
  final_statistics(data, train, phi, stdev, *details, map_data, search_prior, data_weight);
}

void IdentifyPipeline::fit_least_squares_with_prior(LeastSquaresFit& ls, const std::vector<int>* dropped,
                                                    double decision_inflation, double data_weight, Eigen::VectorXd& phi,
                                                    Eigen::VectorXd& stdev, FitDetails* details,
                                                    MapData& map_data) const {
  double* cond = details ? &details->cond : nullptr;
  std::vector<int>* held = details ? &details->held : nullptr;
  DeterminedFit* decision = details ? &details->decision : nullptr;
  const std::string& m = opt_.method;
  LeastSquaresFit* lsp = &ls;
  if (!prior_.usable() || m == "iv") {  // iv: its start (fit_instrumental) decides on the data alone
    least_squares(*lsp, dropped, decision_inflation, opt_.sign_constraints, phi, stdev, cond, held, decision);
    return;
  }
  DeterminedFit d;
  Eigen::VectorXd data_std;
  least_squares(*lsp, dropped, decision_inflation, false, phi, data_std, cond, nullptr, &d);
  const std::vector<int>& undetermined = dropped ? *dropped : d.dropped;
  std::vector<int> unsupported;
  for (const int i : undetermined)
    if (!prior_.has[static_cast<size_t>(i)]) unsupported.push_back(i);
  const double kept = static_cast<double>(P) - static_cast<double>(undetermined.size());
  const Eigen::MatrixXd R = lsp->r_factor().triangularView<Eigen::Upper>();
  const double sigma2 = (lsp->residual_sum_of_squares() + (R * phi - lsp->rotated_rhs()).squaredNorm()) /
                        std::max(1.0, static_cast<double>(lsp->rows()) - kept);
  check(add_prior_rows(*lsp, prior_, std::sqrt(sigma2 / data_weight)));
  least_squares(*lsp, &unsupported, 1.0, opt_.sign_constraints, phi, stdev, nullptr, held, nullptr);
  if (!details) return;
  details->data_stdev = data_std;
  details->decision = std::move(d);
  map_data = {R, sigma2, unsupported, unsupported};
  if (held) map_data.held.insert(map_data.held.end(), held->begin(), held->end());
}

void IdentifyPipeline::fit_consistent(LeastSquaresFit& ls, const StackedData& data, const std::vector<char>& train,
                                      const std::vector<int>* dropped, double decision_inflation, Eigen::VectorXd& phi,
                                      Eigen::VectorXd& stdev, FitDetails* details, MapData& map_data,
                                      ParameterPrior& search_prior) const {
  double* cond = details ? &details->cond : nullptr;
  const std::string& m = opt_.method;
  LeastSquaresFit* lsp = &ls;
  DeterminedFit d;
  Eigen::VectorXd data_std;
  least_squares(*lsp, dropped, decision_inflation, false, phi, data_std, cond, nullptr, &d);
  const CompiledRobot& compiled = compiled_robot_for(robot_);
  ConsistentProblem p;
  p.R = lsp->r_factor().triangularView<Eigen::Upper>();
  p.z = lsp->rotated_rhs();
  p.num_base = model_.num_base;
  p.K = base_map(compiled);
  p.prior = Eigen::Map<const Eigen::VectorXd>(compiled.nominal_standard.data(), compiled.num_standard);
  p.sigma2 = d.dropped.empty() ? lsp->residual_sum_of_squares() / std::max(1.0, static_cast<double>(lsp->rows() - P))
                               : d.sigma2;
  p.start = phi;
  p.prior_relative_std = opt_.prior_std;
  p.nonnegative = nonnegative_terms(model_.names, model_.num_base);
  ConsistentSolution sol;
  if (m == "pcls") {
    // The data weigh against the prior as white noise of the WLS residual's variance. Weighed
    // by their effective information instead (sigma2 times S / n_eff, 200 on the TX40 log),
    // the prior pulled the TX40's links 1 and 2 to robot.json and joint 1's validation RMS rose
    // 1.74 -> 2.64 Nm (WLS 1.70): the autocorrelation there is model error, not noise.
    sol = consistent_least_squares(p);
    stdev = sol.params_std;
  } else {
    // The optimisers: the model is linear, so the parameters' spread is least squares' (the
    // Fisher information does not depend on where the search ends). The particle filter's
    // likelihood takes the residual's autocorrelation into account (S / n_eff).
    p.sigma2 *= streamed_autocorrelation_inflation(data, train, phi);
    sol = search_consistent(p, search_method(m), search_settings(opt_));
    stdev = data_std;
    if (details && !d.dropped.empty()) {
      // The search moves the parameters the log does not determine within its range, and those
      // the log determines only together with them move along: their spread is the posterior's
      // with robot.json's inertials as prior (the search's centre), not the data's with the
      // undetermined ones held at 0 (which understated it 4-fold on a coupled motor's Ia).
      search_prior = parameter_prior(robot_, model_, opt_.prior_std > 0 ? opt_.prior_std : kPriorRelativeStd);
      if (search_prior.usable()) {
        std::vector<int> unsupported;
        for (const int i : d.dropped)
          if (!search_prior.has[static_cast<size_t>(i)]) unsupported.push_back(i);
        map_data = {p.R, d.sigma2, unsupported, d.dropped};
      }
    }
  }
  phi = sol.params;
  if (details) {
    details->consistent = std::move(sol);
    details->data_stdev = data_std;
    details->decision = std::move(d);
  }
}

void IdentifyPipeline::final_statistics(const StackedData& data, const std::vector<char>& train,
                                        const Eigen::VectorXd& phi, Eigen::VectorXd& stdev, FitDetails& details,
                                        const MapData& map_data, const ParameterPrior& search_prior,
                                        double data_weight) const {
  details.inflation = streamed_autocorrelation_inflation(data, train, phi);
  if (map_data.R.size() > 0) {
    // The MAP estimate weighs the data as white noise (as pcls: the autocorrelation of a real log is
    // mostly model error; weighed by their effective information, TX40's joint 1 validated 2.63 Nm
    // instead of 1.73); its std are that estimate's spread with the data's noise S / n_eff times
    // the white variance (parameter_prior.hpp).
    const PriorFitStatistics st = prior_fit_statistics(search_prior.usable() ? search_prior : prior_, map_data.R,
                                                       map_data.sigma2, details.inflation, data_weight, map_data.held);
    stdev = st.stdev;
    for (const int i : map_data.unsupported) stdev[i] = std::numeric_limits<double>::quiet_NaN();
    details.data_share = st.data_share;
    details.data_stdev *= std::sqrt(details.inflation);
    return;
  }
  if (details.consistent.information_data.size() > 0) {  // pcls: the prior's part is not inflated
    consistent_covariance(details.consistent, details.inflation);
    stdev = details.consistent.params_std;
  } else {
    stdev *= std::sqrt(details.inflation);
  }
  if (details.data_stdev.size() > 0) details.data_stdev *= std::sqrt(details.inflation);
}

/// The least-squares estimate of `ls`'s data with the parameters the data do not determine held at
/// 0: decided here (determined_least_squares, its sigma2 times `inflation`) unless `forced` names
/// them. When none is dropped: lib/'s solution and statistics, bit for bit those of a fit without
/// the decision. stdev: white-noise figures, NaN on the dropped parameters; with `constrain`, the
/// sign constraints (constrain_signs) on the kept ones.
void IdentifyPipeline::least_squares(const LeastSquaresFit& ls, const std::vector<int>* forced, double inflation,
                                     bool constrain, Eigen::VectorXd& phi, Eigen::VectorXd& stdev, double* cond,
                                     std::vector<int>* held, DeterminedFit* decision) const {
  const std::vector<int> none;
  auto decide = [&](const std::vector<int>* f) {
    return determined_least_squares(ls.r_factor().triangularView<Eigen::Upper>(), ls.rotated_rhs(),
                                    ls.residual_sum_of_squares(), ls.rows(), scale_, inflation, f);
  };
  DeterminedFit d;
  if (!(forced && forced->empty())) d = decide(forced);
  Eigen::VectorXd g;
  if (d.dropped.empty() && ls.solve(phi) == UpdateStatus::ok && ls.inverse_gram_diagonal(g) == UpdateStatus::ok) {
    const double sigma2 = ls.residual_sum_of_squares() / std::max(1.0, static_cast<double>(ls.rows() - P));
    stdev = (g * sigma2).cwiseSqrt();
  } else {
    if (d.phi.size() == 0) d = decide(&none);  // lib/'s rank test refused what the decision keeps
    phi = d.phi;
    stdev = (d.gram_diag * d.sigma2).cwiseSqrt();
  }
  if (cond) *cond = condition_number(ls);
  if (constrain) constrain_signs(ls, d.dropped, phi, stdev, held);
  if (decision) *decision = std::move(d);
}

void IdentifyPipeline::process_segment(JointLog& log, Eigen::Index a, Eigen::Index b, const ButterworthLowPass& filter,
                                       const Eigen::VectorXd& band, const KeptSamples& kept, Eigen::Index k0,
                                       StackedData& out) const {
  const Eigen::Index S = b - a, n = kept.count(a, b);
  const double dt = log.sample_period();
  const bool effects = !opt_.effects.empty();
  auto keep = [&](const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::MatrixXd& to, Eigen::Index col) {
    for (Eigen::Index i = 0; i < n; ++i) to(k0 + i, col) = x[kept.edge + i * kept.step];
  };
  // Effect columns are computed from every joint's signals at the log's rate.
  Eigen::MatrixXd all_q, all_qd, all_qdd, all_v;
  if (effects) {
    all_q.resize(S, N), all_qd.resize(S, N), all_qdd.resize(S, N), all_v.resize(S, N);
  }
  const Eigen::Index C = static_cast<Eigen::Index>(coupled_.size());
  Eigen::MatrixXd motor_raw = Eigen::MatrixXd::Zero(S, C), motor_qd = Eigen::MatrixXd::Zero(S, C);
  // One joint at a time; v, once kept, holds each sign column in turn (filtered in place).
  Eigen::VectorXd xd(S), xdd(S), v(S);
  Eigen::VectorXd& series = v;
  auto filter_and_keep = [&](size_t i) {
    filter.filtfilt(series);
    keep(series, out.filtered_terms, static_cast<Eigen::Index>(i));
  };
  for (int j = 0; j < N; ++j) {
    // Friction sign from the unfiltered velocity (central differences of q, or the measured qd):
    // sgn is discontinuous, and of a filtered velocity it would switch up to a cut-off period
    // after a stop; filtering the sign column in parallel averages the noise. Inside the noise
    // band the joint is at rest: sign 0, and its filtered velocity 0.
    if (log.has_qd) {
      v = log.qd.col(j).segment(a, S);
    } else {
      v = central_difference(log.q.col(j).segment(a, S), dt);
    }
    auto x = log.q.col(j).segment(a, S);  // filtered in place
    filter.filtfilt(x);
    if (log.has_qd) {
      xd = log.qd.col(j).segment(a, S);
      filter.filtfilt(xd);
    } else {
      xd = smooth_derivative(x, dt);
    }
    if (log.has_qdd) {
      xdd = log.qdd.col(j).segment(a, S);
      filter.filtfilt(xdd);
    } else {
      xdd = smooth_derivative(xd, dt);
    }
    for (Eigen::Index s = 0; s < S; ++s) {
      if (std::abs(v[s]) < band[j]) xd[s] = 0.0;
    }
    for (Eigen::Index c = 0; c < C; ++c) {
      const double r = motor_(coupled_[static_cast<size_t>(c)], j);
      if (r == 0.0) continue;
      motor_raw.col(c) += r * v;
      motor_qd.col(c) += r * xd;
    }
    keep(xd, out.qd, j);
    keep(xdd, out.qdd, j);
    if (out.qd_raw.rows() > 0) keep(v, out.qd_raw, j);
    if (effects) all_q.col(j) = x, all_qd.col(j) = xd, all_qdd.col(j) = xdd, all_v.col(j) = v;
    for (size_t i = 0; i < filtered_.size(); ++i) {
      const FilteredTerm& f = filtered_[i];
      if (f.m != j || f.coupled) continue;
      for (Eigen::Index s = 0; s < S; ++s) {  // series is v: the Coulomb column (first) reads v in place
        series[s] = f.t == term::coulomb ? friction_sign(v[s], band[j]) : term_column(f.t, xd[s], 0.0, 0.0);
      }
      filter_and_keep(i);
    }
  }
  // Coupled motors: sign and velocity v_m = T.row(m) qd of the motor, its noise band from the
  // joints' bands.
  for (Eigen::Index c = 0; c < C; ++c) {
    const int m = coupled_[static_cast<size_t>(c)];
    const double band_m = motor_band(motor_, m, band);
    keep(motor_raw.col(c), out.motor_qd_raw, c);
    for (size_t i = 0; i < filtered_.size(); ++i) {
      const FilteredTerm& f = filtered_[i];
      if (f.m != m) continue;
      for (Eigen::Index s = 0; s < S; ++s) {
        const double sign = friction_sign(motor_raw(s, c), band_m);
        series[s] = f.t == term::coulomb ? sign : term_column(f.t, sign == 0.0 ? 0.0 : motor_qd(s, c), 0.0, 0.0);
      }
      filter_and_keep(i);
    }
  }
  if (effects) {
    Eigen::MatrixXd Et = effect_columns_over_time(opt_.effects, all_q, all_qd, all_qdd, all_v, band);
    const std::vector<bool> discontinuous = effect_columns_with_sign(opt_.effects);
    const Eigen::Index m = static_cast<Eigen::Index>(discontinuous.size());
    for (Eigen::Index c = 0; c < Et.cols(); ++c)
      if (discontinuous[static_cast<size_t>(c % m)]) filter.filtfilt(Et.col(c));
    for (Eigen::Index i = 0; i < n; ++i) {
      for (int j = 0; j < N; ++j) out.E.row((k0 + i) * N + j) = Et.row(kept.edge + i * kept.step).segment(j * m, m);
    }
  }
}

/// Per joint, kStandstillQuantile x the standard deviation of the unfiltered velocity's noise:
/// the white noise of the measured signal (white_noise_std of q, or of qd when measured) times the
/// noise gain of central differences, 1 / (dt sqrt(2)), for q.
Eigen::VectorXd IdentifyPipeline::standstill_band(
    const JointLog& log, const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments) const {
  const Eigen::VectorXd sigma = white_noise_std(log.has_qd ? log.qd : log.q, segments);
  const double gain = log.has_qd ? 1.0 : 1.0 / (log.sample_period() * std::sqrt(2.0));
  return sigma * (kStandstillQuantile * gain);
}

/// IdentifyOptions::sign_constraints on a least-squares fit of the kept parameters (not in
/// `dropped`): the dissipative and inertial terms the drive's table check requires >= 0 (Coulomb,
/// viscous, rotor inertia) held there when the unconstrained phi has them negative; stdev of the free
/// ones from the reduced problem (sigma^2 from the constrained residual), 0 on the held ones.
void IdentifyPipeline::constrain_signs(const LeastSquaresFit& ls, const std::vector<int>& dropped, Eigen::VectorXd& phi,
                                       Eigen::VectorXd& stdev, std::vector<int>* held) const {
  const std::vector<int> signed_terms = nonnegative_terms(model_.names, model_.num_base);
  std::vector<int> kept, nonnegative;
  for (int i = 0; i < P; ++i) {
    if (std::find(dropped.begin(), dropped.end(), i) != dropped.end()) continue;
    if (std::find(signed_terms.begin(), signed_terms.end(), i) != signed_terms.end())
      nonnegative.push_back(static_cast<int>(kept.size()));
    kept.push_back(i);
  }
  const auto Kn = static_cast<Eigen::Index>(kept.size());
  const Eigen::MatrixXd Rf = ls.r_factor().triangularView<Eigen::Upper>();
  Eigen::MatrixXd R(P, Kn);
  Eigen::VectorXd start(Kn);
  for (Eigen::Index k = 0; k < Kn; ++k) {
    R.col(k) = Rf.col(kept[static_cast<size_t>(k)]);
    start[k] = phi[kept[static_cast<size_t>(k)]];
  }
  const SignConstrainedSolution sol = sign_constrained_least_squares(R, ls.rotated_rhs(), nonnegative, start);
  if (held) {
    held->clear();
    for (int h : sol.held) held->push_back(kept[static_cast<size_t>(h)]);
  }
  if (sol.held.empty()) return;
  for (Eigen::Index k = 0; k < Kn; ++k) phi[kept[static_cast<size_t>(k)]] = sol.x[k];
  // Without dropped parameters the unconstrained residual is the full model's (rss) to rounding.
  const double reduced = dropped.empty() ? 0.0 : (R * start - ls.rotated_rhs()).squaredNorm();
  const double dof = std::max(1.0, static_cast<double>(ls.rows() - Kn + static_cast<long>(sol.held.size())));
  const double sigma2 = (ls.residual_sum_of_squares() + reduced + sol.residual_increase) / dof;
  for (Eigen::Index k = 0; k < Kn; ++k)
    stdev[kept[static_cast<size_t>(k)]] = std::sqrt(sol.inverse_gram_diag[k] * sigma2);
}

namespace {

/// The declared model's fit, or [W E] with effect columns appended (set_effect_columns): the final
/// fit on all samples, then its blocked cross-validation (`fold`, `folds`), the prior's weight chosen
/// by it (ols/wls with a prior), and the parameters, their verdicts and notes, into res.
/// A final fit with the data's rows weighed `data_weight` times against the prior, its folds' fits
/// and their pooled out-of-fold metrics (each sample predicted by the fit without its fold, made
/// sample by sample: no stored prediction).
struct Validated {
  Eigen::VectorXd phi, stdev;
  std::vector<Eigen::VectorXd> fold_phi;  ///< the fits without each fold
  IdentifyPipeline::FitDetails details;
  std::vector<JointMetrics> joints;
  double seconds = 0;
};

Validated validated_fit(const IdentifyPipeline& pipe, const StackedData& data, const std::vector<int>& fold, int folds,
                        const Eigen::VectorXd& tau_max, double data_weight, Progress& progress) {
  const int N = static_cast<int>(data.q.cols());
  const Eigen::Index S = data.t.size();
  const std::vector<char> all(static_cast<size_t>(S), 1);
  Validated v;
  const auto t0 = std::chrono::steady_clock::now();
  v.details.data_weight = data_weight;
  pipe.fit(data, all, v.phi, v.stdev, &v.details);
  progress.advance();
  v.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<Eigen::VectorXd>& fold_phi = v.fold_phi;
  fold_phi.resize(static_cast<size_t>(folds));
  for (int f = 0; f < folds; ++f) {
    std::vector<char> train(static_cast<size_t>(S));
    for (Eigen::Index s = 0; s < S; ++s) train[static_cast<size_t>(s)] = fold[static_cast<size_t>(s)] != f;
    Eigen::VectorXd fold_std;
    pipe.fit(data, train, fold_phi[static_cast<size_t>(f)], fold_std, nullptr, &v.details);
    progress.advance();
  }
  Eigen::MatrixXd K;
  Eigen::VectorXd tau_hat(N);
  v.joints = torque_metrics(
      data.y, N, tau_max,
      // Rows --min-speed leaves out of the fit are left out of the scores too.
      [&](Eigen::Index s, int j) {
        return fold[static_cast<size_t>(s)] >= 0 && data.fit_row[static_cast<size_t>(s * N + j)];
      },
      [&](Eigen::Index s) {
        data.regressor(s, K);
        tau_hat = K * fold_phi[static_cast<size_t>(fold[static_cast<size_t>(s)])];
        return tau_hat.data();
      });
  return v;
}

/// The note on what the parameters' std are (the posterior's, the MAP estimate's, or the white-noise
/// figures inflated by the residual's autocorrelation).
std::string std_note(const std::string& method, const IdentifyPipeline::FitDetails& final_fit) {
  char line[320];
  if (is_search_method(method) && final_fit.data_share.size() > 0)
    std::snprintf(line, sizeof line,
                  "parameter std: the posterior's spread with robot.json's inertials as prior (the search moves "
                  "what the log does not determine within its range), the data's noise %.3g times its white "
                  "variance (S / n_eff)",
                  final_fit.inflation);
  else if (final_fit.data_share.size() > 0 || final_fit.consistent.information_data.size() > 0)
    std::snprintf(line, sizeof line,
                  "parameter std: the MAP estimate's spread with the data's noise %.3g times its white "
                  "variance (the residual's autocorrelation, S / n_eff) and the prior's own",
                  final_fit.inflation);
  else
    std::snprintf(line, sizeof line,
                  "parameter std: the white-noise figures times %.3g for the residual's autocorrelation (S / n_eff)",
                  std::sqrt(final_fit.inflation));
  return line;
}

/// The validated fit of `pipe` (the final fit on all rows, the folds' fits sharing its decision; under a
/// prior, the data's weight chosen by the cross-validation) into res. Returns that data weight.
double fit_validated(const IdentifyPipeline& pipe, const StackedData& data, const TermSetModel& model,
                     const std::vector<int>& fold, int folds, const RobotDescription& robot, const IdentifyOptions& opt,
                     IdentifyResult& res) {
  const int N = model.num_joints, P = model.num_params;
  const Eigen::Index S = data.t.size();

  // Final fit on all data first: the reported parameters, and the decision of which parameters the
  // log determines, which the folds' fits then share (the validated model is the reported one).
  std::vector<char> all(static_cast<size_t>(S), 1);
  const bool map = pipe.prior().usable();
  Progress progress("identify: " + opt.method + " fit and " + std::to_string(folds) + " folds",
                    static_cast<double>((map ? 2 : 1) * (folds + 1)), "fits");
  const auto fit_and_validate = [&](double data_weight) {
    return validated_fit(pipe, data, fold, folds, robot.tau_max, data_weight, progress);
  };
  Validated chosen = fit_and_validate(1.0);
  if (map) {
    // How much the data weigh against the prior: as white noise (their rows' count), or as their
    // effective information (S / n_eff times less: the residual's autocorrelation). Which is right
    // depends on whether that autocorrelation is noise or model error, so the blocked
    // cross-validation decides: the effective weighting is kept when its out-of-fold mean squared
    // error, relative to the white one's, is lower averaged over the joints.
    Validated effective = fit_and_validate(1.0 / chosen.details.inflation);
    double ratio = 0;
    for (size_t j = 0; j < chosen.joints.size(); ++j)
      ratio += std::pow(effective.joints[j].rms / chosen.joints[j].rms, 2) / static_cast<double>(N);
    char line[300];
    std::snprintf(line, sizeof line,
                  "prior weight: the data weigh against the prior as %s (cross-validated mean squared error "
                  "%.4g times the other's; S / n_eff = %.3g)",
                  ratio < 1.0 ? "their effective information" : "white noise", ratio < 1.0 ? ratio : 1.0 / ratio,
                  chosen.details.inflation);
    if (ratio < 1.0) chosen = std::move(effective);
    res.notes.push_back(line);
  }
  const Eigen::VectorXd& phi = chosen.phi;
  const Eigen::VectorXd& stdev = chosen.stdev;
  const IdentifyPipeline::FitDetails& final_fit = chosen.details;
  res.fit_seconds = chosen.seconds;
  res.condition_number = final_fit.cond;
  res.joints = chosen.joints;
  for (int i = 0; i < P; ++i) res.params.push_back({model.names[static_cast<size_t>(i)], phi[i], stdev[i]});
  if (folds >= 2)
    for (const Eigen::VectorXd& f : chosen.fold_phi) res.fold_params.emplace_back(f.data(), f.data() + f.size());
  judge_parameters(pipe.scales(), final_fit, opt, pipe.prior(), model.names, res);
  res.notes.push_back(std_note(opt.method, final_fit));
  report_consistent(final_fit.consistent, opt, res);
  if (!final_fit.held.empty()) {
    std::string names;
    for (int i : final_fit.held) names += (names.empty() ? "" : ", ") + model.names[static_cast<size_t>(i)];
    res.notes.push_back("sign constraints: " + names +
                        " held at 0 (negative without the constraint: friction and rotor inertia cannot be)");
  }
  return final_fit.data_weight;
}

}  // namespace

namespace {

/// The validation's fold of each of the S samples (-1: training only): a time split (--validate-last)
/// or blocked k-fold cross-validation; res.validation says which. Returns the number of folds.
/// Throws InputError (folds < 2, too few samples for them, validate_last outside (0, 1)).
int assign_folds(const IdentifyOptions& opt, Eigen::Index S, double rate_hz, std::vector<int>& fold,
                 IdentifyResult& res) {
  int folds = opt.folds;
  if (opt.validate_last > 0.0) {
    if (!(opt.validate_last < 1.0)) throw InputError("--validate-last must lie in (0, 1)");
    const Eigen::Index first =
        static_cast<Eigen::Index>(std::floor((1.0 - opt.validate_last) * static_cast<double>(S)));
    for (Eigen::Index s = 0; s < S; ++s) fold[static_cast<size_t>(s)] = s >= first ? 0 : -1;
    folds = 1;
    res.validation =
        "time split: last " + std::to_string(static_cast<int>(std::lround(opt.validate_last * 100))) + "% validates";
  } else {
    if (folds < 2) throw InputError("--folds must be >= 2");
    const Eigen::Index block = std::max<Eigen::Index>(1, std::lround(opt.block_seconds * rate_hz));
    if (S < block * folds)
      throw InputError("too few samples for " + std::to_string(folds) + " folds of " +
                       std::to_string(opt.block_seconds) + " s blocks");
    for (Eigen::Index s = 0; s < S; ++s) fold[static_cast<size_t>(s)] = static_cast<int>((s / block) % folds);
    res.validation = "blocked " + std::to_string(folds) + "-fold cross-validation, " +
                     std::to_string(opt.block_seconds).substr(0, 4) + " s blocks";
  }
  return folds;
}

/// Before and after the effects: `model` (the declared terms and coupled motors) without the effect
/// terms, fitted and validated on the same rows and folds with the data weight the effects' fit
/// took, its validation RMS beside theirs per joint in a note, each joint the effects make worse
/// named with its rise (any rise, as diagnose names one: the report never hides a joint they harm).
/// data's effect columns are dropped (its W back to model's).
void note_before_after_effects(const RobotDescription& robot, const TermSetModel& model, const IdentifyOptions& opt,
                               StackedData& data, Eigen::Index declared, const std::vector<int>& fold, int folds,
                               double data_weight, IdentifyResult& res) {
  data.W.conservativeResize(Eigen::NoChange, declared);
  data.names.resize(static_cast<size_t>(declared));
  const IdentifyPipeline pipe(robot, opt, model);
  Progress progress("identify: the declared model alone, for before and after", folds + 1.0, "fits");
  const Validated alone = validated_fit(pipe, data, fold, folds, robot.tau_max, data_weight, progress);
  std::string line =
      "effects: validation RMS per joint without -> with them [Nm] (the model without its effect terms, its coupled "
      "motors kept, on the same folds):";
  std::string worse;
  for (size_t j = 0; j < alone.joints.size() && j < res.joints.size(); ++j) {
    char v[96];
    std::snprintf(v, sizeof v, "%s %d: %.4g -> %.4g", j ? "," : "", res.joints[j].joint, alone.joints[j].rms,
                  res.joints[j].rms);
    line += v;
    if (res.joints[j].rms > alone.joints[j].rms) {
      std::snprintf(v, sizeof v, "%s%d (%+.2g %%)", worse.empty() ? "" : ", ", res.joints[j].joint,
                    100.0 * (res.joints[j].rms / alone.joints[j].rms - 1.0));
      worse += v;
    }
  }
  res.notes.push_back(line);
  if (!worse.empty())
    res.notes.push_back("effects: the validation RMS rises with them on joint " + worse +
                        ": there they do not improve the model out of sample (fitted together, effects found one at "
                        "a time can trade with each other or with the model)");
}

/// Effect terms (model_effects.hpp): their columns appended to the regressor and fitted by this
/// same pipeline (the prior, the decision of what the log determines, the validation). Load
/// friction's columns need the rigid-body torque, a shape of tau_model the model's torque: both from
/// a first fit without those columns on all samples (as a drive's feed-forward computes them from
/// the model it has). That fit is the reference model a shape of tau_model reads, kept with the
/// parameters (res.tau_model_reference) for predict: refitting the variable with the parameters
/// instead would let the shape trade with the model (tried: oscillating fixed points).
void fit_with_effects(const RobotDescription& robot, const TermSetModel& model, const IdentifyOptions& opt,
                      StackedData& data, const std::vector<int>& fold, int folds, IdentifyResult& res) {
  const Eigen::Index S = data.t.size();
  const Eigen::Index declared = data.W.cols();
  std::vector<bool> use = effect_columns_without_model_torque(opt.effects);
  Eigen::VectorXd tau_rb = Eigen::VectorXd::Zero(data.y.size()), tau_model;
  if (std::find(use.begin(), use.end(), false) != use.end()) {
    set_effect_columns(data, declared, opt.effects, use, tau_rb);
    const TermSetModel first_model = with_effect_parameters(model, opt.effects, use);  // first holds a reference
    IdentifyPipeline first(robot, opt, first_model);
    first.set_shape_penalties(shape_penalties(opt.effects, use, declared));
    IdentifyPipeline::FitDetails details;
    Eigen::VectorXd phi, stdev;
    first.fit(data, std::vector<char>(static_cast<size_t>(S), 1), phi, stdev, &details);
    tau_rb = rigid_body_torque(data, phi);
    tau_model = data.W * phi;
    if (std::any_of(opt.effects.begin(), opt.effects.end(),
                    [](const ModelEffect& e) { return e.kind == EffectKind::load_friction; }))
      res.notes.push_back(
          "load friction: its rigid-body torque from a first fit without the load terms (the transmitted torque, "
          "as a drive's feed-forward computes it)");
    if (std::any_of(opt.effects.begin(), opt.effects.end(), shape_of_tau_model)) {
      // The reference in the parameters' layout: the first fit's values, 0 where it had no column.
      res.tau_model_reference.assign(phi.data(), phi.data() + declared);
      Eigen::Index k = declared;
      for (const bool u : use) res.tau_model_reference.push_back(u ? phi[k++] : 0.0);
      res.notes.push_back(
          "shapes of tau_model: their variable is the torque of a first fit without them and without load friction "
          "(the reference model, kept with the parameters as tau_model_reference)");
    }
  }
  use.assign(use.size(), true);
  set_effect_columns(data, declared, opt.effects, use, tau_rb, tau_model);
  const TermSetModel with_effects = with_effect_parameters(model, opt.effects, use);
  IdentifyPipeline effects_pipe(robot, opt, with_effects, effect_parameter_scales(data, declared, with_effects, robot));
  effects_pipe.set_shape_penalties(shape_penalties(opt.effects, use, declared));
  const double data_weight = fit_validated(effects_pipe, data, with_effects, fold, folds, robot, opt, res);
  note_before_after_effects(robot, model, opt, data, declared, fold, folds, data_weight, res);
}

/// The notes of the model's rotor inertia (not modelled, or included in a base parameter) and of
/// joints validated with R^2 < 0.
void add_model_notes(const TermSetModel& model, IdentifyResult& res) {
  const int N = model.num_joints;
  for (int j = 0; j < N; ++j) {
    if (!(model.terms & term::rotor_inertia) || model.rotor_inertia_separate[static_cast<size_t>(j)]) continue;
    const int into = model.rotor_inertia_absorbed_into[static_cast<size_t>(j)];
    if (into < 0) {  // robot.json: "rotor_inertia": false
      res.notes.push_back("Ia" + std::to_string(j + 1) +
                          ": the robot file declares no rotor inertia, so none is modelled (set \"rotor_inertia\": "
                          "true in robot.json and build again to add it)");
    } else {
      res.notes.push_back("Ia" + std::to_string(j + 1) + " is not separable from the rigid body: it is included in " +
                          model.names[static_cast<size_t>(into)]);
    }
  }
  // R^2 < 0 on data a fit never saw: the model predicts worse than the joint's mean torque. Its
  // parameters fit noise or a too short log, and are not to be used as they are.
  for (const JointMetrics& m : res.joints) {
    if (!(m.r2 < 0)) continue;
    char line[300];
    std::snprintf(line, sizeof line,
                  "joint %d: validation R^2 %.3g < 0 (RMS %.3g Nm against a measured RMS of %.3g Nm): the model "
                  "predicts unseen data worse than a constant; the log cannot carry this model (too short, too "
                  "little motion, or too many parameters for it): do not use these parameters",
                  m.joint, m.r2, m.rms, m.rms_tau);
    res.notes.push_back(line);
  }
}

}  // namespace

IdentifyResult run_identify(const RobotDescription& robot, const TermSetModel& model, JointLog&& log,
                            const IdentifyOptions& opt) {
  const int N = model.num_joints;
  if (log.joints() != N)
    throw InputError("log has " + std::to_string(log.joints()) + " joints, robot " + robot.name + " has " +
                     std::to_string(N));
  IdentifyPipeline pipe(robot, opt, model);
  // Effect terms are fitted on the dense [W E], IDIM-IV on the dense W and its simulated twin; the
  // declared model streams the regressor's rows.
  const bool iv = opt.method == "iv";
  JointLog grid;  // IDIM-IV's simulations run on the log's grid
  if (iv) grid.t = log.t, grid.segment_starts = log.segment_starts, grid.period = log.period;
  IdentifyResult res;
  res.data_source = log.source;
  res.sample_rate_hz = 1.0 / log.sample_period();
  StackedData data = pipe.prepare(std::move(log), !opt.effects.empty() || iv);  // consumes the log
  res.notes = data.notes;
  const Eigen::Index S = data.t.size();
  res.robot = robot.name;
  for (int j = 0; j < robot.num_joints; ++j)
    if (is_prismatic(robot, j)) res.prismatic_joints.push_back(j + 1);
  res.method = opt.method;
  res.model = model_spec_name({model.terms, opt.effects, opt.motors});
  res.friction_per_motor = pipe.models_coupled_motors();
  res.decimated_rate_hz = data.rate_hz;
  res.cutoff_hz = opt.cutoff_hz;
  res.samples_used = static_cast<long>(S);

  // Validation assignment: fold index per sample (-1: training only).
  std::vector<int> fold(static_cast<size_t>(S));
  const int folds = assign_folds(opt, S, data.rate_hz, fold, res);
  if (iv) {
    const PrepareLog prepare = [&pipe, &data](JointLog&& l) {
      return pipe.prepare(std::move(l), true, &data.standstill_band);
    };
    // The parameters the log determines: the WLS fit's decision (fit() fits iv's start by WLS).
    IdentifyPipeline::FitDetails details;
    Eigen::VectorXd wls_phi, wls_std;
    pipe.fit(data, std::vector<char>(static_cast<size_t>(data.t.size()), 1), wls_phi, wls_std, &details);
    // What the log does not determine is held at the robot's prior mean (0 where it has none).
    const Eigen::VectorXd held_at =
        pipe.prior().usable() ? pipe.prior().mean : Eigen::VectorXd(Eigen::VectorXd::Zero(model.num_params));
    fit_instrumental(data, grid, fold, folds, robot, opt, prepare, details.decision.dropped, held_at, res);
    judge_parameters(pipe.scales(), details, opt, pipe.prior(), model.names, res);
  } else if (!opt.effects.empty()) {
    fit_with_effects(robot, model, opt, data, fold, folds, res);
  } else {
    fit_validated(pipe, data, model, fold, folds, robot, opt, res);
  }
  add_model_notes(model, res);
  return res;
}

}  // namespace dyncal::host
