// dyncal diagnose: the greedy search. Each step evaluates every candidate of the library
// (candidates.hpp) and those beyond it (beyond_catalogue.hpp) against the model so far by blocked
// cross-validation (cross_validator.hpp) and BIC, adds the one with the largest validation gain
// among those with very strong evidence and physical parameters (the catalogue's where it explains
// as much), and stops when none qualifies.
#include "dyncal_host/diagnosis/diagnose.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <iomanip>
#include <set>
#include <sstream>
#include <utility>

#include "beyond_catalogue.hpp"
#include "candidates.hpp"
#include "cross_validator.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/parallel_tasks.hpp"
#include "dyncal_host/common/spline_basis.hpp"
#include "dyncal_host/identification/methods/butterworth.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "harmonic_fit.hpp"
#include "noise_floor.hpp"
#include "shape_search.hpp"

namespace dyncal::host {
namespace {

using detail::Candidate;
using detail::CrossValidator;
using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

/// A joint that does not move, or moves at constant velocity, carries no information.
void check_every_joint_moves(const StackedData& d) {
  for (int j = 0; j < d.q.cols(); ++j) {
    const double range = d.q.col(j).maxCoeff() - d.q.col(j).minCoeff();
    const double qd_var = (d.qd.col(j).array() - d.qd.col(j).mean()).square().mean();
    if (range < 1e-3)
      throw InputError("joint " + std::to_string(j + 1) + " does not move (range < 1 mrad): nothing to diagnose");
    if (std::sqrt(qd_var) < 1e-3 * std::max(1e-9, d.qd.col(j).cwiseAbs().maxCoeff()) || std::sqrt(qd_var) < 1e-4) {
      throw InputError("joint " + std::to_string(j + 1) +
                       " moves at constant velocity: inertia and friction cannot be told apart");
    }
  }
}

/// Effective independent samples of each joint's residual (effective_samples): the residual is
/// low-passed and carries smooth model error, so counting every sample would make BIC overconfident.
VectorXd effective_samples_per_joint(const VectorXd& residual, int N) {
  const Index S = residual.size() / N;
  VectorXd n(N);
  for (int j = 0; j < N; ++j) {
    VectorXd r(S);
    for (Index s = 0; s < S; ++s) r[s] = residual[s * N + j];
    n[j] = effective_samples(r);
  }
  return n;
}

/// What the cross-validation says of one candidate against the model so far.
struct Evidence {
  double delta_bic = 0;  ///< BIC change on the candidate's joints (negative: evidence for)
  double gain = 0;       ///< relative drop of those joints' validation RSS
  bool physical = true;  ///< its fitted parameters have physical signs
  bool collinear = false;
  bool unbounded = false;  ///< Candidate::unbounded: its ratio is not determined
};

/// The model so far: its design, names, fit and validation / training RSS per joint.
struct Model {
  MatrixXd X;
  std::vector<std::string> names;
  VectorXd phi, val, train;
  std::vector<ShapePenalty> penalties;  ///< of its penalised shapes' columns
  MatrixXd val_folds;                   ///< validation RSS per fold (folds x N)
};

/// The model's fit and validation after its design changed: the cross-validator's base set to it.
void refit(CrossValidator& cv, Model& m) {
  cv.set_base(m.X, m.penalties);
  cv.evaluate(MatrixXd(m.X.rows(), 0), m.val, m.train, &m.phi, nullptr, {}, nullptr, &m.val_folds);
}

/// The model's columns a candidate replaces (Candidate::replaces), by name.
std::vector<Index> replaced_columns(const Candidate& c, const Model& m) {
  std::vector<Index> out;
  for (const std::string& name : c.replaces)
    out.push_back(std::find(m.names.begin(), m.names.end(), name) - m.names.begin());
  return out;
}

/// The same joints, in any order (a coupling of 5 and 6, joint 6's motor coupled to joint 5).
bool same_joints(const Candidate& a, const Candidate& b) {
  std::vector<int> x = a.joints, y = b.joints;
  std::sort(x.begin(), x.end());
  std::sort(y.begin(), y.end());
  return x == y;
}

/// The candidate's evidence against the model so far. A motor's rotor inertia (coupling, coupled
/// motor) is held >= 0: where the free fit makes it negative the candidate loses that column
/// (drop_inertia: held at 0, the bounded least-squares optimum) and is weighed without it.
Evidence weigh(const CrossValidator& cv, Candidate& c, const Model& m, const VectorXd& n_eff_residual,
               const VectorXd& val_before) {
  VectorXd val, train, phi_c;
  double novelty = 1;
  detail::CandidatePenalty shape_penalty{{c.joints.empty() ? 0 : c.joints.front(), 0, 0.0, c.roughness},
                                         c.penalty_grid};
  detail::CandidatePenalty* penalty = c.penalty_grid.empty() ? nullptr : &shape_penalty;
  cv.evaluate(c.columns, val, train, &phi_c, &novelty, replaced_columns(c, m), penalty);
  c.penalty = shape_penalty.chosen;
  c.edf = shape_penalty.edf;
  if (c.inertia >= 0 && phi_c[phi_c.size() - c.columns.cols() + c.inertia] < 0) {
    c = detail::drop_inertia(std::move(c));
    cv.evaluate(c.columns, val, train, &phi_c, &novelty, replaced_columns(c, m));
  }
  Evidence e;
  e.collinear = novelty < 1e-6;
  // BIC over every joint: the joints share the rigid-body parameters, so a candidate that helps its
  // own joints and harms others pays for it (each joint's log-RSS ratio, weighted by its n_eff).
  double v0 = 0, v1 = 0, n_all = 0, harm = 0;
  VectorXd n_eff = n_eff_residual;  // a candidate beyond the catalogue: its joint's noise, not its structure
  for (int j : c.joints) n_eff[j] = std::max(n_eff[j], c.n_eff_after);
  std::vector<char> own(static_cast<size_t>(n_eff.size()), 0);
  for (int j : c.joints) own[static_cast<size_t>(j)] = 1;
  for (Index j = 0; j < n_eff.size(); ++j) {
    n_all += n_eff[j];
    e.delta_bic += n_eff[j] * std::log(std::max(1e-300, train[j]) / std::max(1e-300, m.train[j]));
    const double before = m.val[j] / std::max(1e-300, val_before[j]), after = val[j] / std::max(1e-300, val_before[j]);
    if (own[static_cast<size_t>(j)]) {
      v0 += before;  // joints weighted by their own scale
      v1 += after;
    } else {
      harm += std::max(0.0, after - before);  // another joint's validation made worse
    }
  }
  e.delta_bic += c.weighed_parameters() * std::log(n_all);
  // A candidate picked among several alternatives (the best frequency of a spectral search, ...)
  // pays for the look-elsewhere effect: 2 ln(alternatives), a Bonferroni factor in BIC units.
  e.delta_bic += 2.0 * std::log(static_cast<double>(c.searched));
  e.gain = v0 > 0 ? (v0 - v1 - harm) / v0 : 0;
  e.physical = detail::effect_spec(c.effect).physical(phi_c.tail(c.columns.cols()));
  e.unbounded = c.unbounded;
  return e;
}

/// Whether a candidate passes every check of the selection.
bool qualifies(const Evidence& e, const DiagnoseOptions& o) {
  return e.physical && !e.unbounded && !e.collinear && e.delta_bic < -o.bic_threshold && e.gain >= o.min_gain;
}

/// Parsimony: among the qualifying candidates on the same joints as `best` that add fewer
/// parameters, the one adding the fewest (then the lowest BIC) is taken instead, unless `best` is
/// better by BIC by more than the evidence threshold (a constant offset is asymmetric Coulomb
/// friction's special case on a joint that never rests: the one-parameter offset wins unless the
/// data need both; a coupled motor, which adds none, wins over an added coupling likewise).
int most_parsimonious(const std::vector<Candidate>& cands, const std::vector<Evidence>& ev, int best,
                      const DiagnoseOptions& o) {
  const Candidate& b = cands[static_cast<size_t>(best)];
  int pick = best;
  for (size_t k = 0; k < cands.size(); ++k) {
    const Candidate& c = cands[k];
    if (!same_joints(c, b) || !qualifies(ev[k], o) || c.weighed_parameters() >= b.weighed_parameters()) continue;
    if (ev[static_cast<size_t>(best)].delta_bic < ev[k].delta_bic - o.bic_threshold) continue;  // the larger is needed
    const Candidate& p = cands[static_cast<size_t>(pick)];
    if (c.weighed_parameters() < p.weighed_parameters() ||
        (c.weighed_parameters() == p.weighed_parameters() && ev[k].delta_bic < ev[static_cast<size_t>(pick)].delta_bic))
      pick = static_cast<int>(k);
  }
  return pick;
}

/// The fraction of `small`'s columns (squared norm over its joints' rows) that `large`'s columns
/// and the model's X together cannot represent (least squares on those rows).
double unexplained_fraction(const Candidate& small, const Candidate& large, const MatrixXd& X, int N) {
  const Index S = X.rows() / N, J = static_cast<Index>(small.joints.size());
  MatrixXd A(S * J, large.columns.cols() + X.cols()), B(S * J, small.columns.cols());
  for (Index s = 0; s < S; ++s)
    for (Index p = 0; p < J; ++p) {
      const Index row = s * N + small.joints[static_cast<size_t>(p)];
      A.row(s * J + p) << large.columns.row(row), X.row(row);
      B.row(s * J + p) = small.columns.row(row);
    }
  const MatrixXd fit = A.colPivHouseholderQr().solve(B);
  return (B - A * fit).squaredNorm() / std::max(1e-300, B.squaredNorm());
}

/// Other kinds on the same joints the data cannot tell from the chosen one: physical and
/// identifiable, and either within 2 of its BIC change (Kass and Raftery: "not worth more than a
/// bare mention") or nesting it — larger, representing its columns up to less than one effective
/// sample's share (1 / n_eff of their norm, so no sample of the log can tell), and removing as much
/// validation error (within 1 %): parsimony's losers, such as asymmetric Coulomb friction for an
/// offset on a joint that never rests.
std::vector<std::string> indistinguishable(const std::vector<Candidate>& cands, const std::vector<Evidence>& ev,
                                           int chosen, const MatrixXd& X, const VectorXd& n_eff) {
  const Candidate& c = cands[static_cast<size_t>(chosen)];
  const Evidence& e = ev[static_cast<size_t>(chosen)];
  const int N = static_cast<int>(n_eff.size());
  double n_min = INFINITY;
  for (int j : c.joints) n_min = std::min(n_min, n_eff[j]);
  std::vector<std::string> out;
  for (size_t k = 0; k < cands.size(); ++k) {
    const Candidate& a = cands[k];
    if (static_cast<int>(k) == chosen || a.effect == c.effect || !same_joints(a, c)) continue;
    if (!ev[k].physical || ev[k].unbounded || ev[k].collinear) continue;
    const bool close = std::abs(ev[k].delta_bic - e.delta_bic) < 2.0;
    const bool nested = !close && c.replaces.empty() && a.replaces.empty() && a.columns.cols() > c.columns.cols() &&
                        ev[k].gain >= e.gain - 0.01 && unexplained_fraction(c, a, X, N) < 1.0 / n_min;
    if (!close && !nested) continue;
    std::ostringstream s;
    s << std::setprecision(4) << effect_name(a.effect) << " (BIC change " << ev[k].delta_bic << ", validation RSS -"
      << std::setprecision(3) << 100 * ev[k].gain << " %)";
    out.push_back(s.str());
  }
  return out;
}

/// The strongest rejected candidate of each kind (smallest BIC change) and why it was rejected, among
/// `weighed` (each candidate with its evidence: the catalogue's and those beyond it, not copied).
std::vector<RejectedCandidate> strongest_rejected(
    const std::vector<std::pair<const Candidate*, const Evidence*>>& weighed, double bic_threshold) {
  std::vector<RejectedCandidate> out;
  for (const detail::EffectSpec& spec : detail::effect_specs()) {
    const std::pair<const Candidate*, const Evidence*>* top = nullptr;
    for (const auto& w : weighed)
      if (w.first->effect == spec.effect && (!top || w.second->delta_bic < top->second->delta_bic)) top = &w;
    if (!top) continue;
    const Candidate& c = *top->first;
    const Evidence& e = *top->second;
    RejectedCandidate rc{c.effect, {}, e.delta_bic, e.gain, ""};
    for (int j : c.joints) rc.joints.push_back(j + 1);
    std::ostringstream why;
    why << std::setprecision(3);
    if (!e.physical)
      why << "unphysical sign of its parameter (BIC change " << rc.delta_bic << ")";
    else if (e.unbounded)
      why << "ratio unbounded: " << c.detail
          << " reaches the end of the searched 1/5..5 or ends at the estimate (BIC change " << rc.delta_bic << ")";
    else if (rc.delta_bic >= -bic_threshold)
      why << "BIC change " << rc.delta_bic << " (needs < " << -bic_threshold << ")";
    else
      why << "validation RSS does not drop (gain " << 100 * rc.validation_gain << " %)";
    rc.reason = why.str();
    out.push_back(rc);
  }
  return out;
}

/// Two load torques for load-dependent friction, from the rigid-body parameters of the declared
/// model's fit: the torque the gear transmits, Y(q, qd, qdd) phi (a real gearbox's friction grows
/// with it, inertial part included), and the load the joint holds, h(q, qd) = Y(q, qd, 0) phi
/// (gravity and velocity products: what a model without an algebraic loop, such as the simulated
/// drive, applies). The candidate takes whichever explains the residual better.
std::vector<std::pair<std::string, VectorXd>> load_torques(const StackedData& d, const VectorXd& phi) {
  VectorXd phi_rb = phi;
  phi_rb.tail(phi.size() - d.num_base).setZero();
  return {{"load: transmitted rigid-body torque", d.W * phi_rb},
          {"load: gravity and velocity-product torque", d.W_load * phi_rb}};
}

/// The traces the plots show: kept samples, predictions before and after, the residual spectrum.
DiagnoseTraces traces(const StackedData& d, const VectorXd& before, const VectorXd& after, int max_cycles) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  DiagnoseTraces tr;
  tr.t = d.t;
  tr.q = d.q;
  tr.qd = d.qd;
  tr.tau.resize(S, N);
  tr.tau_before.resize(S, N);
  tr.tau_after.resize(S, N);
  for (Index s = 0; s < S; ++s)
    for (int j = 0; j < N; ++j) {
      tr.tau(s, j) = d.y[s * N + j];
      tr.tau_before(s, j) = before[s * N + j];
      tr.tau_after(s, j) = after[s * N + j];
    }
  tr.spectrum = MatrixXd::Zero(max_cycles, N);
  for (int j = 0; j < N; ++j)
    for (int k = 1; k <= max_cycles; ++k) {
      const std::optional<double> power =
          detail::harmonic_rss_reduction(d.q, j, k, [&](Index s) { return d.y[s * N + j] - before[s * N + j]; });
      if (power) tr.spectrum(k - 1, j) = *power / static_cast<double>(S);
    }
  return tr;
}

/// e_T_abs and e_T_abs_std of joint j (beside survey Sec. 5.1's e_T): mean and standard deviation of |tau - tau_hat| /
/// tau_max over the out-of-fold predictions (rows in the fit only, as the validation RSS).
void torque_indices(const StackedData& d, int j, double tau_max, const VectorXd& pred, double& mean, double& stdev) {
  const int N = static_cast<int>(d.q.cols());
  double sa = 0, sa2 = 0, n_rows = 0;
  for (Index s = 0; s < d.t.size(); ++s) {
    const Index r = s * N + j;
    if (!d.fit_row[r]) continue;
    const double a = std::abs(d.y[r] - pred[r]) / tau_max;
    sa += a;
    sa2 += a * a;
    n_rows += 1;
  }
  mean = sa / std::max(1.0, n_rows);
  stdev = std::sqrt(std::max(0.0, sa2 / std::max(1.0, n_rows) - mean * mean));
}

/// Per joint: validation and training RMS, R², e_T_abs and e_T_abs_std before and after the effects.
std::vector<DiagnoseJoint> joint_metrics(const StackedData& d, const RobotDescription& robot, const Model& before,
                                         const Model& after, const VectorXd& oof_before, const VectorXd& oof_after) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  std::vector<DiagnoseJoint> out;
  for (int j = 0; j < N; ++j) {
    DiagnoseJoint m;
    m.joint = j + 1;
    double sy = 0, syy = 0;
    for (Index s = 0; s < S; ++s) {
      sy += d.y[s * N + j];
      syy += d.y[s * N + j] * d.y[s * N + j];
    }
    const double n = static_cast<double>(S), ss_tot = syy - sy * sy / n;
    m.rms_tau = std::sqrt(syy / n);
    m.rms_train_before = std::sqrt(before.train[j] / n);
    m.rms_train_after = std::sqrt(after.train[j] / n);
    m.rms_validation_before = std::sqrt(before.val[j] / n);
    m.rms_validation_after = std::sqrt(after.val[j] / n);
    m.r2_validation_before = 1 - before.val[j] / ss_tot;
    m.r2_validation_after = 1 - after.val[j] / ss_tot;
    torque_indices(d, j, robot.tau_max[j], oof_before, m.e_T_abs_before, m.e_T_abs_std_before);
    torque_indices(d, j, robot.tau_max[j], oof_after, m.e_T_abs_after, m.e_T_abs_std_after);
    out.push_back(m);
  }
  return out;
}

/// Per-joint residual standard deviation [Nm] of a fit with `p` parameters from its training RSS
/// and the joints' fitted rows (identify's WLS weights, stacked_data.hpp: joint_noise_std).
VectorXd residual_std_per_joint(const StackedData& d, const VectorXd& train_rss, Index p) {
  const int N = static_cast<int>(train_rss.size());
  VectorXd n = VectorXd::Zero(N);
  for (Index r = 0; r < d.y.size(); ++r)
    if (d.fit_row[r]) n[r % N] += 1;
  return joint_noise_std(train_rss, n, p);
}

/// Folds as in identify: blocks of block_seconds dealt to the folds in turn. Throws InputError when
/// the log is too short for two blocks per fold.
std::vector<int> blocked_folds(Index S, double rate_hz, const IdentifyOptions& io) {
  const Index block = std::max<Index>(1, std::lround(io.block_seconds * rate_hz));
  if (S < block * io.folds * 2) throw InputError("too few samples for a diagnosis (" + std::to_string(S) + ")");
  std::vector<int> fold(static_cast<size_t>(S));
  for (Index s = 0; s < S; ++s) fold[s] = static_cast<int>((s / block) % io.folds);
  return fold;
}

/// A candidate that would be chosen (gain above best_score) but for a ratio the data do not bound
/// is named in a note, once per kind and joints (`noted`), not added.
void note_unbounded(const std::vector<Candidate>& cands, const std::vector<Evidence>& ev, double best_score,
                    const DiagnoseOptions& o, std::set<std::string>& noted, std::vector<std::string>& notes) {
  int unbounded = -1;
  for (size_t c = 0; c < cands.size(); ++c) {
    Evidence e = ev[c];
    if (!e.unbounded) continue;
    e.unbounded = false;
    if (qualifies(e, o) && e.gain > best_score && (unbounded < 0 || e.gain > ev[static_cast<size_t>(unbounded)].gain))
      unbounded = static_cast<int>(c);
  }
  if (unbounded < 0) return;
  const Candidate& u = cands[static_cast<size_t>(unbounded)];
  std::ostringstream note;
  note << std::setprecision(3) << effect_name(u.effect) << " on joints " << u.joints[0] + 1 << " and "
       << u.joints[1] + 1 << " would explain the most (validation RSS -"
       << 100 * ev[static_cast<size_t>(unbounded)].gain << " %), but its ratio is not bounded by the data (" << u.detail
       << ": the interval reaches the end of the searched 1/5..5 or ends at the estimate): not added; what is "
          "added after it may be standing in for it";
  const std::string key =
      std::string(effect_name(u.effect)) + " " + std::to_string(u.joints[0]) + " " + std::to_string(u.joints[1]);
  if (noted.insert(key).second) notes.push_back(note.str());
}

/// What weighted least squares weighs each joint by (Gautier: 1 / sigma_j), as a note.
std::string wls_note(const VectorXd& weights) {
  std::ostringstream note;
  note << std::setprecision(3) << "weighted least squares (Gautier): joint j's rows weighted by 1/sigma_j, sigma = [";
  for (Index j = 0; j < weights.size(); ++j) note << (j ? ", " : "") << 1.0 / weights[j];
  note << "] Nm from the declared model's OLS residual, re-estimated after each effect";
  return note.str();
}

/// The declared model's parameters in the final fit m, by name: a declared column a coupled motor
/// replaced is 0 (its value is the motor's term).
std::vector<double> declared_params(const Model& declared, const Model& m) {
  std::vector<double> out;
  for (const std::string& name : declared.names) {
    const auto it = std::find(m.names.begin(), m.names.end(), name);
    out.push_back(it == m.names.end() ? 0.0 : m.phi[it - m.names.begin()]);
  }
  return out;
}

/// Each candidate weighed on its own against model m (each task writes its own slot:
/// parallel_tasks.hpp), in the library's order, as one thread would.
std::vector<Evidence> weigh_all(const CrossValidator& cv, std::vector<Candidate>& cands, const Model& m,
                                const VectorXd& n_eff, const VectorXd& declared_val, int step) {
  std::vector<Evidence> ev(cands.size());
  std::vector<ParallelTask> weighing;
  for (size_t c = 0; c < cands.size(); ++c)
    weighing.push_back({1.0, [&, c] { ev[c] = weigh(cv, cands[c], m, n_eff, declared_val); }});
  run_parallel(std::move(weighing), default_jobs(), "diagnose: step " + std::to_string(step + 1) + ", weighing",
               "candidates");
  return ev;
}

/// The model's design [X C], less the columns C replaces, and its names.
void add_columns(const Candidate& c, Model& m) {
  const std::vector<Index> replaced = replaced_columns(c, m);
  MatrixXd A(m.X.rows(), m.X.cols() - static_cast<Index>(replaced.size()) + c.columns.cols());
  std::vector<std::string> names;
  for (Index k = 0, col = 0; k < m.X.cols(); ++k) {
    if (std::find(replaced.begin(), replaced.end(), k) != replaced.end()) continue;
    A.col(col++) = m.X.col(k);
    names.push_back(m.names[static_cast<size_t>(k)]);
  }
  A.rightCols(c.columns.cols()) = c.columns;
  for (ShapePenalty& pen : m.penalties)  // a penalised shape's columns move left past the replaced ones
    pen.column -= std::count_if(replaced.begin(), replaced.end(), [&](Index k) { return k < pen.column; });
  if (c.penalty > 0)
    m.penalties.push_back({c.joints.front(), m.X.cols() - static_cast<Index>(replaced.size()), c.penalty, c.roughness});
  m.X = std::move(A);
  m.names = std::move(names);
  for (const auto& n : c.names) m.names.push_back(n);
}

/// The effect candidate c adds, with its parameters from the model's fit m (its columns last).
DiagnosedEffect diagnosed_effect(const Candidate& c, const Model& m, const Evidence& ev,
                                 std::vector<std::string> alternatives) {
  DiagnosedEffect e;
  e.kind = c.effect;
  for (int j : c.joints) e.joints.push_back(j + 1);
  e.param_names = c.names;
  e.inertia_held = c.inertia_held;
  for (Index k = 0; k < c.columns.cols(); ++k) e.params.push_back(m.phi[m.X.cols() - c.columns.cols() + k]);
  e.delta_bic = ev.delta_bic;
  e.shape = c.shape;
  e.shape_interval = c.shape_interval;
  e.sign = c.sign;
  e.validation_gain = ev.gain;
  e.explanation = detail::explain(c, e.params);
  e.alternatives = std::move(alternatives);
  e.variable = c.variable;
  e.knots = c.knots;
  e.penalty = c.penalty;
  e.effective_parameters = c.weighed_parameters();
  if (c.effect == Effect::shape)
    shape_curve(c.knots, e.params, shape_without_linear(c.variable), kShapeCurvePoints, e.curve_x, e.curve_y);
  return e;
}

/// The report never hides a joint the effects made worse (shared rigid-body parameters): a note each.
void note_worse_joints(DiagnoseResult& res) {
  for (const DiagnoseJoint& j : res.joints) {
    if (res.effects.empty() || !(j.rms_validation_after > j.rms_validation_before)) continue;
    std::ostringstream note;
    note << std::setprecision(4) << "joint " << j.joint << ": validation RMS rises " << j.rms_validation_before
         << " -> " << j.rms_validation_after << " Nm with the effects added";
    res.notes.push_back(note.str());
  }
}

/// The declared model's fit (unweighted): the compiled regressor W, then the declared effect terms
/// (identify's --model vocabulary) as [W E], load friction's rigid-body torque from the fit of W alone.
Model declared_fit(const StackedData& d, const std::vector<ModelEffect>& effects, CrossValidator& cv) {
  Model m{d.W, d.names, {}, {}, {}, {}, {}};
  refit(cv, m);
  if (effects.empty()) return m;
  m.X = model_design(d, effects, m.phi);
  m.penalties =
      shape_penalties(effects, std::vector<bool>(static_cast<size_t>(effect_column_count(effects)), true), d.W.cols());
  for (const ModelEffect& e : effects)
    for (const std::string& n : effect_param_names(e)) m.names.push_back(n);
  refit(cv, m);
  return m;
}

/// One stage of a greedy step: the candidates of the catalogue (or those beyond it), their evidence
/// and the one chosen (-1: none qualifies).
struct Stage {
  std::vector<Candidate> cands;
  std::vector<Evidence> ev;
  int best = -1;
};

Stage weigh_stage(const detail::CandidateContext& library, bool catalogue, const CrossValidator& cv, const Model& m,
                  const VectorXd& n_eff, const VectorXd& declared_val, int step, const DiagnoseOptions& o,
                  std::set<std::string>& unbounded_noted, std::vector<std::string>& notes,
                  const std::vector<int>& joints = {}) {
  Stage st;
  const std::string what = catalogue ? "" : " beyond the catalogue";
  st.cands = detail::candidate_library(
      library, catalogue, "diagnose: step " + std::to_string(step + 1) + ", building candidates" + what, joints);
  // Selection on validation error only: the largest relative validation gain among candidates
  // whose BIC evidence is very strong and whose parameters are physical.
  st.ev = weigh_all(cv, st.cands, m, n_eff, declared_val, step);
  double best_score = 0;
  for (size_t c = 0; c < st.cands.size(); ++c) {
    if (qualifies(st.ev[c], o) && st.ev[c].gain > best_score) {
      best_score = st.ev[c].gain;
      st.best = static_cast<int>(c);
    }
  }
  note_unbounded(st.cands, st.ev, best_score, o, unbounded_noted, notes);
  if (st.best >= 0) st.best = most_parsimonious(st.cands, st.ev, st.best, o);
  return st;
}

/// A copy of `stage` that takes its candidates' columns ((S N) x m each, the bulk of a stage); `stage`
/// keeps the rest (for note_structured_residual), its candidates without columns.
Stage columns_moved(Stage& stage) {
  Stage out;
  out.ev = stage.ev;
  out.best = stage.best;
  for (Candidate& c : stage.cands) {
    MatrixXd columns = std::move(c.columns);
    out.cands.push_back(c);
    out.cands.back().columns = std::move(columns);
  }
  return out;
}

/// Whether the best candidate beyond the catalogue is taken instead of the catalogue's: when no
/// kind of the table qualifies, or when it acts on a joint of the table's choice and its BIC change
/// is lower by more than the evidence threshold, taken with the same n_eff as the table's (the
/// residual's; the parsimony rule's yardstick). Where a kind of the table explains as much, the
/// table's kind wins: it is smaller and has physics.
bool beyond_wins(const CrossValidator& cv, const Stage& table, Stage& beyond, const Model& m, const VectorXd& n_eff,
                 const VectorXd& declared_val, const DiagnoseOptions& o) {
  if (beyond.best < 0) return false;
  if (table.best < 0) return true;
  const Candidate& t = table.cands[static_cast<size_t>(table.best)];
  Candidate& b = beyond.cands[static_cast<size_t>(beyond.best)];  // weighed again as it is, n_eff_after aside
  if (std::find(t.joints.begin(), t.joints.end(), b.joints.front()) == t.joints.end()) return false;
  const double n_eff_after = b.n_eff_after;
  b.n_eff_after = 0;
  const Evidence e = weigh(cv, b, m, n_eff, declared_val);
  b.n_eff_after = n_eff_after;
  return e.delta_bic < table.ev[static_cast<size_t>(table.best)].delta_bic - o.bic_threshold;
}

/// The note for a delay the search chose whose 95 % interval holds 0 (delay_interval).
std::string undetermined_delay_note(const Candidate& c, double delay, std::pair<double, double> interval) {
  std::ostringstream note;
  note << std::setprecision(3) << "joint " << c.joints.front() + 1 << ": a torque delay of " << 1e3 * delay
       << " ms would pass the evidence threshold, but its 95 % interval " << 1e3 * interval.first << " .. "
       << 1e3 * interval.second << " ms holds 0 (the folds disagree on its sign): it stands in for something "
       << "else and is not added";
  return note.str();
}

/// One greedy step's choice: the catalogue's best, unless a candidate beyond it (a channel's delay,
/// a shape) wins (beyond_wins). The search beyond runs on every joint when no kind qualifies, else
/// on the chosen kind's joints only (the only place it could take the kind's place); *beyond keeps
/// it. best < 0: nothing qualifies, and res.rejected names the strongest of both.
Stage choose(const detail::CandidateContext& library, const CrossValidator& cv, const Model& m, const VectorXd& n_eff,
             const VectorXd& declared_val, int step, const DiagnoseOptions& o, std::set<std::string>& unbounded_noted,
             Stage& beyond, DiagnoseResult& res) {
  Stage st = weigh_stage(library, true, cv, m, n_eff, declared_val, step, o, unbounded_noted, res.notes);
  const std::vector<int> on = st.best >= 0 ? st.cands[static_cast<size_t>(st.best)].joints : std::vector<int>{};
  beyond = weigh_stage(library, false, cv, m, n_eff, declared_val, step, o, unbounded_noted, res.notes, on);
  if (beyond_wins(cv, st, beyond, m, n_eff, declared_val, o)) return columns_moved(beyond);
  if (st.best < 0) {
    std::vector<std::pair<const Candidate*, const Evidence*>> weighed;
    for (const Stage* stage : {&st, &beyond})
      for (size_t c = 0; c < stage->cands.size(); ++c) weighed.emplace_back(&stage->cands[c], &stage->ev[c]);
    res.rejected = strongest_rejected(weighed, o.bic_threshold);
  }
  return st;
}

/// Refines a delay just added (the last column of m.X, on joint j's rows): the column rebuilt as the
/// secant at the current estimate (delay_column) and refitted with the whole model, until the
/// estimate moves by less than 1e-3 of a sample (at most 8 times). `away` (S flags, or empty): the
/// samples where the column is 0, so that the delay is read from the others alone.
void refine_delay(const StackedData& d, const std::vector<std::pair<Index, Index>>& segments, int j, CrossValidator& cv,
                  Model& m, const std::vector<char>& away = {}) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size(), last = m.X.cols() - 1;
  for (int it = 0; it < 8; ++it) {
    const double delta = m.phi[last];
    VectorXd p(S);  // the prediction without the delay
    for (Index s = 0; s < S; ++s) p[s] = m.X.row(s * N + j).head(last).dot(m.phi.head(last));
    const VectorXd column = detail::delay_column(d.t, segments, p, delta);
    for (Index s = 0; s < S; ++s)
      m.X(s * N + j, last) = away.empty() || !away[static_cast<size_t>(s)] ? column[s] : 0.0;
    refit(cv, m);
    if (std::abs(m.phi[last] - delta) < 1e-3 / d.rate_hz) break;
  }
}

/// The delay's 95 % interval (detail::delay_interval) with the model m as refined.
std::pair<double, double> interval_of(const StackedData& d, const Model& m, const VectorXd& weights, int j,
                                      double n_eff_j, const CrossValidator& cv, const std::vector<char>& steps,
                                      double raw_period, double* step_share) {
  std::vector<double> fold_delays;
  for (const VectorXd& b : cv.fold_coefficients()) fold_delays.push_back(b[b.size() - 1]);
  return detail::delay_interval(d, m.X, m.phi, weights, j, n_eff_j, fold_delays, steps, raw_period, step_share);
}

/// A delay just added (m: the model with its column, before: without it), refined (refine_delay)
/// with its 95 % interval (*interval). Where the torque's steps carry some of its information, the
/// interval is widened for them (delay_interval), and the delay is also read away from them (its
/// column 0 on their samples: a smaller share of the information, but no sampled step's phase in
/// it); the narrower of the two intervals is kept, with its estimate. When the interval holds 0 its
/// sign is not determined: it stands in for something else; it is named in a note, refused (not
/// proposed again) and m goes back to `before`. Returns whether it stays.
bool delay_determined(const StackedData& d, const Candidate& c, const Model& before, double n_eff_j,
                      const VectorXd& weights, double raw_period, CrossValidator& cv, Model& m,
                      detail::CandidateContext& library, std::pair<double, double>& interval,
                      std::vector<std::string>& notes) {
  const int j = c.joints.front();
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  VectorXd p(S);  // the model's torque on joint j before the delay
  for (Index s = 0; s < S; ++s) p[s] = before.X.row(s * N + j).dot(before.phi);
  const std::vector<char> steps = detail::torque_step_samples(d, library.segments, j, p);
  refine_delay(d, library.segments, j, cv, m);
  double step_share = 0;
  interval = interval_of(d, m, weights, j, n_eff_j, cv, steps, raw_period, &step_share);
  if (step_share >= 0.01) {
    Model away = m;  // the delay read away from the steps
    refine_delay(d, library.segments, j, cv, away, steps);
    double none = 0;
    const std::pair<double, double> away_interval =
        interval_of(d, away, weights, j, n_eff_j, cv, std::vector<char>(steps.size(), 0), raw_period, &none);
    const bool read_away = away_interval.second - away_interval.first < interval.second - interval.first;
    std::ostringstream note;
    note << std::setprecision(3) << "joint " << j + 1 << "'s delay: " << 100 * step_share
         << " % of what determines it comes from the torque's steps, each placed by its samples only to within a "
            "sample; ";
    if (read_away) {
      note << "read away from them (95 % " << 1e3 * away_interval.first << " .. " << 1e3 * away_interval.second
           << " ms), narrower than with them and widened by that share of half a sample (" << 1e3 * interval.first
           << " .. " << 1e3 * interval.second << " ms)";
      m = std::move(away);
      interval = away_interval;
    } else {
      note << "its interval is widened by that share of half a sample (" << 1e3 * step_share * 0.5 * raw_period
           << " ms), narrower than read away from them (95 % " << 1e3 * away_interval.first << " .. "
           << 1e3 * away_interval.second << " ms)";
      refit(cv, m);  // the cross-validator back on m's design
    }
    notes.push_back(note.str());
  }
  if (interval.first > 0 || interval.second < 0) return true;
  notes.push_back(undetermined_delay_note(c, m.phi[m.phi.size() - 1], interval));
  library.refused.push_back(c.names.front());
  m = before;
  refit(cv, m);
  return false;
}

/// Each joint's noise floor as an RMS (over S samples as the joint metrics) with its interval, and
/// the share of the declared model's excess validation RSS above it that is left (0 where there was
/// none: 1 - the share the effects removed) with its interval (noise_floor.hpp).
void set_noise_floors(DiagnoseResult& res, const detail::NoiseFloor& floor, const Model& declared, const Model& m,
                      Index S) {
  const VectorXd rss = floor.rss(floor.per_row), lo = floor.rss(floor.per_row_lo), hi = floor.rss(floor.per_row_hi);
  const auto rms = [S](double v) { return std::sqrt(v / static_cast<double>(S)); };
  for (size_t j = 0; j < res.joints.size(); ++j) {
    DiagnoseJoint& jm = res.joints[j];
    const Index k = static_cast<Index>(j);
    jm.rms_noise_floor = rms(rss[k]);
    jm.rms_noise_floor_interval = {rms(lo[k]), rms(hi[k])};
    const double excess = declared.val[k] - rss[k];
    jm.excess_left = excess > 0 ? std::clamp((m.val[k] - rss[k]) / excess, 0.0, 1.0) : 0.0;
    const auto removed = detail::excess_share_interval({static_cast<int>(j)}, declared.val_folds, m.val_folds, floor);
    jm.excess_left_interval = {1.0 - removed.second, 1.0 - removed.first};
  }
}

/// A note for each joint where the last search beyond the catalogue found structure it did not
/// add: a shape lowers the validation RSS by the diagnosis's min_gain and its BIC change is below -2
/// (Kass and Raftery's "positive" evidence), yet it was not added (short of the evidence threshold,
/// or no better than a kind of the table), with the variable, its validation gain and what the
/// joint has left above its noise floor. None where no shape helps.
void note_structured_residual(DiagnoseResult& res, const Stage& beyond, double min_gain) {
  for (size_t c = 0; c < beyond.cands.size(); ++c) {
    const Candidate& k = beyond.cands[c];
    const Evidence& e = beyond.ev[c];
    if (k.effect != Effect::shape || !(e.delta_bic < -2 && e.gain >= min_gain)) continue;
    const DiagnoseJoint& jm = res.joints[static_cast<size_t>(k.joints.front())];
    std::ostringstream note;
    note << std::setprecision(3) << "joint " << jm.joint << ": structured residual left, explained by " << k.variable
         << " to " << 100 * e.gain << " % of its validation RSS (BIC change " << e.delta_bic
         << ": evidence short of what the diagnosis adds at; not added); validation RMS " << jm.rms_validation_after
         << " Nm against a noise floor of " << jm.rms_noise_floor << " Nm";
    res.notes.push_back(note.str());
  }
}

}  // namespace

DiagnoseResult diagnose(const RobotDescription& robot, const JointLog& log, const DiagnoseOptions& o) {
  IdentifyOptions io = o.identify;
  if (io.terms == 0) io.terms = kFrictionEq7;
  if (io.method != "wls" && io.method != "ols")
    throw InputError("diagnose fits by wls or ols, not '" + io.method + "'");
  io.load_regressor = true;  // the load-friction candidate's load torque h(q, qd)
  const StackedData d = prepare_stacked(robot, log, io);
  const int N = robot.num_joints;
  const Index S = d.t.size();
  DiagnoseResult res;
  res.robot = robot.name;
  res.declared_model = model_spec_name({io.terms, io.effects, io.motors});
  res.method = io.method;
  res.samples = static_cast<long>(S);
  res.notes = d.notes;
  check_every_joint_moves(d);
  const std::vector<int> fold = blocked_folds(S, d.rate_hz, io);
  res.validation = "blocked " + std::to_string(io.folds) + "-fold cross-validation";

  CrossValidator cv(d, N, fold, io.folds);
  Model m = declared_fit(d, io.effects, cv);
  // Gautier's weights (wls), as identify: 1 / sigma_j from the residual of the model so far,
  // re-estimated after every effect added (a joint whose error an effect removes weighs more).
  VectorXd weights = VectorXd::Ones(N);
  auto reweigh = [&] {
    if (io.method != "wls") return;
    weights = residual_std_per_joint(d, m.train, m.X.cols()).cwiseInverse();
    cv.set_joint_weights(weights);
    refit(cv, m);
  };
  reweigh();
  if (io.method == "wls") res.notes.push_back(wls_note(weights));
  const Model declared = m;
  const VectorXd oof_before = cv.predict_out_of_fold();
  detail::CandidateContext library{
      d, o.max_cycles, load_torques(d, m.phi), {}, {}, weights, &m.X, &m.phi, {}, nullptr, {}, {}};
  // Candidate columns are filtered in time as the regressor was (the same zero-phase low-pass, at
  // the decimated rate, within each segment: a step longer than 1.5 periods starts a new one).
  const ButterworthLowPass filter(io.filter_order, io.cutoff_hz, d.rate_hz);
  if (io.cutoff_hz < 0.5 * d.rate_hz) library.filter = &filter;
  library.segments = time_segments(d);

  const detail::NoiseFloor floor = detail::noise_floor(d, d.y - declared.X * declared.phi, library.segments, io,
                                                       1.0 / log.sample_period(), fold, io.folds);
  std::set<std::string> unbounded_noted;  // one note per unbounded candidate (kind and joints)
  Stage beyond;                           // the last stage beyond the catalogue weighed
  VectorXd n_eff = VectorXd::Zero(N);
  for (int step = 0; step < o.max_effects; ++step) {
    library.model_names = m.names;
    library.residual = d.y - m.X * m.phi;
    library.joint_weights = weights;
    library.model_X = &m.X;
    library.model_phi = &m.phi;
    library.column_joints = detail::column_joint_masks(m.X, N);
    n_eff = effective_samples_per_joint(library.residual, N);
    if (step == 0) res.effective_samples_per_joint = n_eff.mean();
    Stage st = choose(library, cv, m, n_eff, declared.val, step, o, unbounded_noted, beyond, res);
    if (st.best < 0) break;
    const Candidate& c = st.cands[static_cast<size_t>(st.best)];
    std::vector<std::string> alternatives = indistinguishable(st.cands, st.ev, st.best, m.X, n_eff);
    const Model before = m;
    add_columns(c, m);
    refit(cv, m);
    std::pair<double, double> delay_95{0, 0};
    if (c.effect == Effect::torque_delay && !delay_determined(d, c, before, n_eff[c.joints.front()], weights,
                                                              log.sample_period(), cv, m, library, delay_95, res.notes))
      continue;
    res.effects.push_back(diagnosed_effect(c, m, st.ev[static_cast<size_t>(st.best)], std::move(alternatives)));
    res.effects.back().excess_share = detail::excess_share(c.joints, before.val, m.val, floor.rss(floor.per_row));
    res.effects.back().excess_share_interval =
        detail::excess_share_interval(c.joints, before.val_folds, m.val_folds, floor);
    if (c.effect == Effect::torque_delay) {
      res.effects.back().shape = m.phi[m.phi.size() - 1];
      res.effects.back().shape_interval = delay_95;
    }
    if (c.effect == Effect::shape) {
      DiagnosedEffect& e = res.effects.back();
      std::vector<std::vector<double>> folds;
      for (const VectorXd& b : cv.fold_coefficients()) {
        const VectorXd tail = b.tail(c.columns.cols());
        folds.emplace_back(tail.data(), tail.data() + tail.size());
      }
      shape_band(c.knots, shape_without_linear(c.variable), folds, e.curve_y, e.curve_lo, e.curve_hi);
    }
    reweigh();
  }

  res.declared_names = declared.names;
  res.declared_params = declared_params(declared, m);
  res.traces = traces(d, declared.X * declared.phi, m.X * m.phi, o.max_cycles);
  res.joints = joint_metrics(d, robot, declared, m, oof_before, cv.predict_out_of_fold());
  set_noise_floors(res, floor, declared, m, S);
  note_structured_residual(res, beyond, o.min_gain);
  note_worse_joints(res);
  return res;
}

}  // namespace dyncal::host
