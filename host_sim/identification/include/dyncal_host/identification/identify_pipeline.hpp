#pragma once
// The identification pipeline for one generated robot and one term set (host side).

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/butterworth.hpp"
#include "dyncal_host/identification/compiled_robot.hpp"
#include "dyncal_host/identification/consistent_least_squares.hpp"
#include "dyncal_host/identification/effect_model.hpp"
#include "dyncal_host/identification/identify.hpp"
#include "dyncal_host/identification/prediction.hpp"
#include "dyncal_host/identification/signal.hpp"
#include "dyncal_host/identification/stacked_data.hpp"
#include "dyncal_host/identification/standard_parameters.hpp"

namespace dyncal::host {

template <class Robot, unsigned Terms>
class IdentifyPipeline {
 public:
  using Model = IdentificationModel<Robot, Terms>;
  static constexpr int N = Robot::kNumJoints;
  static constexpr int P = Model::kNumParams;
  using JointVec = Eigen::Matrix<double, N, 1>;
  using ParamVec = Eigen::Matrix<double, P, 1>;

  IdentifyPipeline(const RobotDescription& robot, const IdentifyOptions& options)
      : robot_(robot),
        opt_(options),
        motor_(options.friction_per_joint ? Eigen::Matrix<double, N, N>::Identity() : motor_map(robot)) {
    for (int m = 0; m < N; ++m) {
      for (int j = 0; j < N; ++j) {
        if (j != m && motor_(m, j) != 0.0) {
          coupled_.push_back(m);
          break;
        }
      }
    }
  }

  /// Filtering, differentiation, regressor, parallel filtering and decimation (Gautier 1997), each
  /// segment of `log` (on a uniform grid, uniform_grid.hpp) on its own: nothing is filtered or
  /// differentiated across a segment boundary, and one cut-off period is dropped at both ends of
  /// every segment, where differentiation and filtering are one-sided.
  StackedData prepare(const JointLog& log) const {
    const double fs = 1.0 / log.sample_period();
    const ButterworthLowPass filter(opt_.filter_order, opt_.cutoff_hz, fs);
    int d = opt_.decimate > 0 ? opt_.decimate : static_cast<int>(std::floor(fs / (25.0 * opt_.cutoff_hz)));
    d = std::max(d, 1);
    const Eigen::Index edge = static_cast<Eigen::Index>(std::ceil(fs / opt_.cutoff_hz));
    const auto segments = log.segments();
    const JointVec band = standstill_band(log, segments);
    StackedData out;
    out.rate_hz = fs / d;
    out.cutoff_hz = opt_.cutoff_hz;
    out.num_base = Robot::kNumBase;
    for (int i = 0; i < P; ++i) out.names.push_back(param_name(i));
    // Samples kept: every d-th of each segment's interior.
    std::vector<std::pair<size_t, Eigen::Index>> kept_rows;  // (segment, row in it)
    long short_segments = 0;
    for (size_t g = 0; g < segments.size(); ++g) {
      const Eigen::Index len = segments[g].second - segments[g].first;
      if (len <= 2 * edge) {
        ++short_segments;
        continue;
      }
      for (Eigen::Index s = edge; s < len - edge; s += d) kept_rows.emplace_back(g, s);
    }
    const Eigen::Index kept = static_cast<Eigen::Index>(kept_rows.size());
    if (kept * N <= 2 * P) {
      throw InputError("too few samples (" + std::to_string(log.samples()) + ", " + std::to_string(kept) +
                       " after filtering and decimation) for " + std::to_string(P) + " parameters");
    }
    if (short_segments > 0)
      out.notes.push_back(std::to_string(short_segments) + " segment(s) not longer than two cut-off periods (" +
                          std::to_string(2 * edge) + " samples) left out: filtering would only see their ends");
    out.W.resize(kept * N, P);
    if (opt_.load_regressor) out.W_load.resize(kept * N, P);
    const Eigen::Index num_effect_cols = effect_column_count(opt_.effects);
    out.E.resize(kept * N, num_effect_cols);
    out.y.resize(kept * N);
    out.t.resize(kept);
    out.q.resize(kept, N);
    out.qd.resize(kept, N);
    out.qdd.resize(kept, N);
    out.qd_raw.resize(kept, N);
    out.standstill_band = Eigen::VectorXd(band);
    Eigen::Index k = 0;
    for (size_t g = 0; g < segments.size(); ++g) {
      const auto [a, b] = segments[g];
      if (b - a <= 2 * edge) continue;
      Segment seg = process_segment(log, a, b, filter, band);
      for (; k < kept && kept_rows[static_cast<size_t>(k)].first == g; ++k) {
        const Eigen::Index s = kept_rows[static_cast<size_t>(k)].second;
        out.t[k] = log.t[a + s];
        out.q.row(k) = seg.q.row(s);
        out.qd.row(k) = seg.qd.row(s);
        out.qd_raw.row(k) = seg.qd_raw.row(s);
        out.qdd.row(k) = seg.qdd.row(s);
        for (int j = 0; j < N; ++j) {
          out.W.row(k * N + j) = seg.Kt.row(s).segment(j * P, P);
          if (opt_.load_regressor) out.W_load.row(k * N + j) = seg.Kt_load.row(s).segment(j * P, P);
          if (num_effect_cols > 0) out.E.row(k * N + j) = seg.Et.row(s).segment(j * num_effect_cols, num_effect_cols);
          out.y[k * N + j] = seg.tau(s, j);
        }
      }
    }
    // Rows of a joint moving slower than min_speed_fraction of its top speed stay out of the fit:
    // there a real joint sticks and Coulomb friction takes any value in [-Fc, Fc], which sgn(qd)
    // cannot represent. They still count in the validation metrics.
    const JointVec threshold = out.qd.cwiseAbs().colwise().maxCoeff().transpose() * opt_.min_speed_fraction;
    out.fit_row.assign(static_cast<size_t>(kept * N), 1);
    for (Eigen::Index r = 0; r < kept; ++r) {
      for (int j = 0; j < N; ++j) {
        if (std::abs(out.qd(r, j)) < threshold[j]) out.fit_row[static_cast<size_t>(r * N + j)] = 0;
      }
    }
    std::string line = "standstill: an unfiltered |qd| below " + std::to_string(kStandstillQuantile).substr(0, 4) +
                       " x its own noise counts as rest (friction sign 0); dead band [rad/s]";
    char v[32];
    for (int j = 0; j < N; ++j) {
      std::snprintf(v, sizeof v, " %.3g", band[j]);
      line += v;
    }
    const double at_rest = static_cast<double>((out.qd.array() == 0.0).count()) / static_cast<double>(kept * N);
    std::snprintf(v, sizeof v, "; %.3g %%", 100.0 * at_rest);
    out.notes.push_back(line + v + " of the joint samples at rest");
    for (const int m : coupled_) {
      std::string t = "transmission (robot.json): motor " + std::to_string(m + 1) + " turns with";
      std::string on;
      for (int j = 0; j < N; ++j) {
        if (motor_(m, j) == 0.0) continue;
        std::snprintf(v, sizeof v, " %+.4g q%d", motor_(m, j), j + 1);
        t += v;
        on += (on.empty() ? "" : ", ") + std::to_string(j + 1);
      }
      out.notes.push_back(t + "; its friction and rotor inertia terms (joint " + std::to_string(m + 1) +
                          "'s columns) act on joints " + on + " through the transmission's transpose");
    }
    return out;
  }

  /// True when a coupled motor's friction and rotor inertia act on several joints (robot.json's
  /// transmission, not --friction-per-joint).
  bool models_coupled_motors() const { return !coupled_.empty(); }

  /// Fits on the samples with train[s] true. Writes phi and parameter standard deviations; with
  /// pcls, the consistent solution into *consistent if given.
  void fit(const StackedData& data, const std::vector<char>& train, ParamVec& phi, ParamVec& stdev,
           double* cond = nullptr, ConsistentSolution* consistent = nullptr) const {
    const Eigen::Index S = data.t.size();
    auto ls = std::make_unique<StreamingLeastSquares<double, P>>();
    for (Eigen::Index s = 0; s < S; ++s) {
      if (!train[s]) continue;
      for (int j = 0; j < N; ++j) {
        if (data.fit_row[s * N + j]) check(ls->add_row(data.W.row(s * N + j).transpose(), data.y[s * N + j]));
      }
    }
    if (ls->solve(phi) != UpdateStatus::ok) {
      throw InputError("the data do not excite every parameter of the model (regressor rank deficient): " +
                       std::string("use richer excitation or a smaller model"));
    }
    // Per-joint residual variance of the OLS fit (Gautier's WLS weights; KF/RLS noise).
    JointVec ss = JointVec::Zero(), n = JointVec::Zero();
    for (Eigen::Index s = 0; s < S; ++s) {
      if (!train[s]) continue;
      for (int j = 0; j < N; ++j) {
        if (!data.fit_row[s * N + j]) continue;
        const double e = data.y[s * N + j] - data.W.row(s * N + j).dot(phi);
        ss[j] += e * e;
        n[j] += 1;
      }
    }
    const JointVec sigma = joint_noise_std(ss, n, P);
    const std::string& m = opt_.method;
    if (m == "ols") {
      ls_statistics(*ls, stdev, cond);
    } else if (m == "wls" || m == "pcls") {
      ls->reset();
      for (Eigen::Index s = 0; s < S; ++s) {
        if (!train[s]) continue;
        for (int j = 0; j < N; ++j) {
          if (data.fit_row[s * N + j])
            check(ls->add_row(data.W.row(s * N + j).transpose(), data.y[s * N + j], 1.0 / sigma[j]));
        }
      }
      if (ls->solve(phi) != UpdateStatus::ok) throw InputError("weighted regressor rank deficient");
      if (m == "wls") {
        ls_statistics(*ls, stdev, cond);
      } else {  // pcls: the WLS solution starts the consistent fit of the same weighted data
        ConsistentProblem p;
        p.R = ls->r_factor().template triangularView<Eigen::Upper>();
        p.z = ls->rotated_rhs();
        p.num_base = Robot::kNumBase;
        p.K = base_map();
        const CompiledRobot& compiled = compiled_robot_for(robot_);
        p.prior = Eigen::Map<const Eigen::VectorXd>(compiled.nominal_standard.data(), Robot::kNumStandard);
        p.sigma2 = ls->residual_sum_of_squares() / std::max(1.0, static_cast<double>(ls->rows() - P));
        p.start = phi;
        ConsistentSolution sol = consistent_least_squares(p);
        phi = sol.params;
        stdev = sol.params_std;
        if (cond) *cond = condition_number(*ls);
        if (consistent) *consistent = std::move(sol);
      }
    } else if (m == "kf") {
      auto kf = std::make_unique<KalmanFilter<double, P, N>>();
      check(kf->reset(ParamVec::Zero(), ParamVec::Constant(opt_.p0)));
      const JointVec r = sigma.cwiseAbs2();
      run_recursive(*kf, data, train, [&](auto& f, const auto& K, const auto& tau) { return f.update(K, tau, r); });
      recursive_result(*kf, *ls, phi, stdev, cond);
    } else if (m == "rls") {
      auto rls = std::make_unique<RlsForgetting<double, P, N>>();
      check(rls->reset(ParamVec::Zero(), ParamVec::Constant(opt_.p0), opt_.rls_mu));
      const JointVec w = sigma.cwiseInverse();
      run_recursive(*rls, data, train, [&](auto& f, const auto& K, const auto& tau) { return f.update(K, tau, w); });
      recursive_result(*rls, *ls, phi, stdev, cond);
    } else {
      throw InputError("unknown method '" + m + "' (expected wls, ols, kf, rls or pcls)");
    }
    stdev *= std::sqrt(autocorrelation_inflation(data, train, data.y - data.W * phi));
  }

  static std::string param_name(int i) {
    const ParamInfo info = Model::info(i);
    if (info.kind == ParamKind::base) return Robot::base_param_name(info.base_index);
    return std::string(term_name(info.term)) + std::to_string(info.joint);
  }

 private:
  /// Motor velocities in joint units, v = T qd: T = diag(N)^-1 N of robot.json's transmission N
  /// (q_motor = N q), so that an uncoupled motor's row is its joint's unit row and a coupled
  /// motor's row says how much each joint turns it (TX40 motor 6: q5 + q6). Identity without a
  /// transmission or with a zero gear ratio.
  static Eigen::Matrix<double, N, N> motor_map(const RobotDescription& robot) {
    Eigen::Matrix<double, N, N> T = Eigen::Matrix<double, N, N>::Identity();
    if (robot.transmission.rows() != N || robot.transmission.cols() != N) return T;
    for (int m = 0; m < N; ++m) {
      const double d = robot.transmission(m, m);
      if (d == 0.0) return Eigen::Matrix<double, N, N>::Identity();
      T.row(m) = robot.transmission.row(m) / d;
    }
    return T;
  }

  /// phi_b = K phi (num_base x num_standard), the generated standard_to_base as a matrix (built once).
  static const Eigen::MatrixXd& base_map() {
    static const Eigen::MatrixXd K = [] {
      Eigen::MatrixXd m(Robot::kNumBase, Robot::kNumStandard);
      for (int i = 0; i < Robot::kNumStandard; ++i) {
        Eigen::Matrix<double, Robot::kNumStandard, 1> e = Eigen::Matrix<double, Robot::kNumStandard, 1>::Zero();
        e[i] = 1.0;
        Eigen::Matrix<double, Robot::kNumBase, 1> b;
        Robot::standard_to_base(e, b);
        m.col(i) = b;
      }
      return m;
    }();
    return K;
  }

  /// One segment filtered and differentiated, its regressor over time (column j * P + c holds
  /// K(j, c) at every sample) filtered in parallel.
  struct Segment {
    Eigen::MatrixXd q, qd, qdd, tau, Kt, Kt_load;
    Eigen::MatrixXd Et;      ///< effect columns over time (column j * m + c), filtered in parallel
    Eigen::MatrixXd qd_raw;  ///< the unfiltered velocity (central differences of q, or the measured qd)
  };

  Segment process_segment(const JointLog& log, Eigen::Index a, Eigen::Index b, const ButterworthLowPass& filter,
                          const JointVec& band) const {
    const Eigen::Index S = b - a;
    const double dt = log.sample_period();
    Segment g;
    g.q = log.q.middleRows(a, S);
    filter.filtfilt(g.q);
    if (log.has_qd) {
      g.qd = log.qd.middleRows(a, S);
      filter.filtfilt(g.qd);
    } else {
      g.qd = smooth_derivative(g.q, dt);
    }
    if (log.has_qdd) {
      g.qdd = log.qdd.middleRows(a, S);
      filter.filtfilt(g.qdd);
    } else {
      g.qdd = smooth_derivative(g.qd, dt);
    }
    // Friction sign from the unfiltered velocity (central differences of q, or the measured qd):
    // sgn is discontinuous, and of a filtered velocity it would switch up to a cut-off period after
    // a stop; the Coulomb column is then filtered in parallel, which averages the noise. Inside the
    // noise band the joint is at rest: sign 0, and its filtered velocity 0.
    g.qd_raw = log.has_qd ? Eigen::MatrixXd(log.qd.middleRows(a, S)) : central_difference(log.q.middleRows(a, S), dt);
    const Eigen::MatrixXd& v = g.qd_raw;
    Eigen::MatrixXd sign = Eigen::MatrixXd::Zero(S, N);
    for (Eigen::Index s = 0; s < S; ++s) {
      for (int j = 0; j < N; ++j) {
        if (std::abs(v(s, j)) < band[j]) {
          g.qd(s, j) = 0.0;
        } else {
          sign(s, j) = v(s, j) > 0 ? 1.0 : -1.0;
        }
      }
    }
    // Coupled motors (robot.json's transmission): their friction and rotor inertia act on every
    // joint that turns them, through the transmission's transpose: the column of motor m's term
    // in joint j's row is T(m, j) times the term at the motor's velocity v_m = T.row(m) qd (in
    // joint units), its sign from the unfiltered motor velocity with the band of its noise.
    const Eigen::Index C = static_cast<Eigen::Index>(coupled_.size());
    Eigen::MatrixXd motor_sign(S, C), motor_v(S, C), motor_a(S, C);
    for (Eigen::Index c = 0; c < C; ++c) {
      const int m = coupled_[static_cast<size_t>(c)];
      const double band_m = std::sqrt((motor_.row(m).transpose().cwiseProduct(band)).squaredNorm());
      for (Eigen::Index s = 0; s < S; ++s) {
        const double raw = motor_.row(m).dot(v.row(s)), vm = motor_.row(m).dot(g.qd.row(s));
        motor_sign(s, c) = std::abs(raw) < band_m ? 0.0 : (raw > 0 ? 1.0 : -1.0);
        motor_v(s, c) = motor_sign(s, c) == 0.0 ? 0.0 : vm;
        motor_a(s, c) = motor_.row(m).dot(g.qdd.row(s));
      }
    }
    g.tau = log.tau.middleRows(a, S);
    filter.filtfilt(g.tau);
    const JointVec zero = JointVec::Zero();
    auto regressor_over_time = [&](bool with_qdd) {
      Eigen::MatrixXd Kt(S, N * P);
      typename Model::template Regressor<double> K;
      for (Eigen::Index s = 0; s < S; ++s) {
        Model::regressor(JointVec(g.q.row(s).transpose()), JointVec(g.qd.row(s).transpose()),
                         with_qdd ? JointVec(g.qdd.row(s).transpose()) : zero, zero, K);
        for (int j = 0; j < N; ++j) {
          if (Model::column(term::coulomb, j) >= 0) K(j, Model::column(term::coulomb, j)) = sign(s, j);
        }
        for (Eigen::Index c = 0; c < C; ++c) {
          const int m = coupled_[static_cast<size_t>(c)];
          for (const unsigned t : {term::coulomb, term::viscous, term::power, term::rotor_inertia}) {
            const int col = Model::column(t, m);
            if (col < 0) continue;
            const double value = t == term::coulomb
                                     ? motor_sign(s, c)
                                     : term_column(t, motor_v(s, c), with_qdd ? motor_a(s, c) : 0.0, 0.0);
            for (int j = 0; j < N; ++j) K(j, col) = motor_(m, j) * value;
          }
        }
        for (int j = 0; j < N; ++j) Kt.row(s).segment(j * P, P) = K.row(j);
      }
      // Every column sees the low-pass once, as tau does: the columns built from the filtered q,
      // qd, qdd have had it; the sign columns (Coulomb, also of a coupled motor) and qd^(1/3),
      // built from the unfiltered velocity's sign, get it now. Filtering the smooth columns again
      // would low-pass their qdd twice against tau's once: an acceleration step (a start or stop)
      // would leave a residual at low speed that looks like Stribeck friction.
      for (int k = 0; k < N; ++k) {
        for (const unsigned t : {term::coulomb, term::power}) {
          const int col = Model::column(t, k);
          if (col < 0) continue;
          for (int j = 0; j < N; ++j) filter.filtfilt(Kt.col(j * P + col));
        }
      }
      return Kt;
    };
    g.Kt = regressor_over_time(true);
    if (opt_.load_regressor) g.Kt_load = regressor_over_time(false);
    if (!opt_.effects.empty()) {
      g.Et = effect_columns_over_time(opt_.effects, g.q, g.qd, g.qdd, v, Eigen::VectorXd(band));
      const std::vector<bool> discontinuous = effect_columns_with_sign(opt_.effects);
      const Eigen::Index m = static_cast<Eigen::Index>(discontinuous.size());
      for (Eigen::Index c = 0; c < g.Et.cols(); ++c)
        if (discontinuous[static_cast<size_t>(c % m)]) filter.filtfilt(g.Et.col(c));
    }
    return g;
  }

  /// Per joint, kStandstillQuantile x the standard deviation of the unfiltered velocity's noise:
  /// the white noise of the measured signal (white_noise_std of q, or of qd when measured) times the
  /// noise gain of central differences, 1 / (dt sqrt(2)), for q.
  JointVec standstill_band(const JointLog& log,
                           const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments) const {
    const Eigen::VectorXd sigma = white_noise_std(log.has_qd ? log.qd : log.q, segments);
    const double gain = log.has_qd ? 1.0 : 1.0 / (log.sample_period() * std::sqrt(2.0));
    return JointVec(sigma * (kStandstillQuantile * gain));
  }

  static void check(UpdateStatus s) {
    if (s != UpdateStatus::ok) throw InputError(std::string("estimator rejected the data: ") + to_string(s));
  }

  template <class Filter, class Update>
  static void run_recursive(Filter& f, const StackedData& data, const std::vector<char>& train, Update update) {
    Eigen::Matrix<double, N, P> K;
    JointVec tau;
    for (Eigen::Index s = 0; s < data.t.size(); ++s) {
      if (!train[s]) continue;
      K = data.W.block(s * N, 0, N, P);
      tau = data.y.segment(s * N, N);
      for (int j = 0; j < N; ++j) {  // an excluded row carries no information: zero it
        if (data.fit_row[s * N + j]) continue;
        K.row(j).setZero();
        tau[j] = 0.0;
      }
      check(update(f, K, tau));
    }
  }

  // Estimate and sqrt(diag P) of a recursive filter; cond(W) from the OLS factor of the same data.
  template <class Filter>
  static void recursive_result(const Filter& f, const StreamingLeastSquares<double, P>& ls, ParamVec& phi,
                               ParamVec& stdev, double* cond) {
    phi = f.estimate();
    f.covariance().diagonal(stdev);
    stdev = stdev.cwiseSqrt();
    if (cond) *cond = condition_number(ls);
  }

  // Parameter standard deviations sigma^2 diag((W^T W)^-1), sigma^2 = RSS / (rows - P), and cond(W).
  static void ls_statistics(const StreamingLeastSquares<double, P>& ls, ParamVec& stdev, double* cond) {
    ParamVec g;
    if (ls.inverse_gram_diagonal(g) != UpdateStatus::ok) throw InputError("regressor rank deficient");
    const double sigma2 = ls.residual_sum_of_squares() / std::max(1.0, static_cast<double>(ls.rows() - P));
    stdev = (g * sigma2).cwiseSqrt();
    if (cond) *cond = condition_number(ls);
  }

  // cond(W) = cond(R): the triangular factor has the singular values of the stacked regressor.
  static double condition_number(const StreamingLeastSquares<double, P>& ls) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Eigen::MatrixXd(ls.r_factor()));
    const auto& sv = svd.singularValues();
    return sv[0] / sv[sv.size() - 1];
  }

  const RobotDescription& robot_;
  const IdentifyOptions& opt_;
  Eigen::Matrix<double, N, N> motor_;  ///< motor_map(robot_)
  std::vector<int> coupled_;           ///< motors turning with more than their own joint (0-based)
};

/// Runs the whole `identify` job for one robot and term set.
template <class Robot, unsigned Terms>
IdentifyResult run_identify(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& opt) {
  using Pipe = IdentifyPipeline<Robot, Terms>;
  constexpr int N = Pipe::N;
  constexpr int P = Pipe::P;
  if (log.joints() != N)
    throw InputError("log has " + std::to_string(log.joints()) + " joints, robot " + robot.name + " has " +
                     std::to_string(N));
  Pipe pipe(robot, opt);
  const StackedData data = pipe.prepare(log);
  IdentifyResult res;
  res.notes = data.notes;
  const Eigen::Index S = data.t.size();
  res.robot = robot.name;
  res.method = opt.method;
  res.model = model_name(Terms);
  res.friction_per_motor = pipe.models_coupled_motors();
  res.data_source = log.source;
  res.sample_rate_hz = 1.0 / log.sample_period();
  res.decimated_rate_hz = data.rate_hz;
  res.cutoff_hz = opt.cutoff_hz;
  res.samples_used = static_cast<long>(S);

  // Validation assignment: fold index per sample (-1: training only).
  std::vector<int> fold(static_cast<size_t>(S));
  int folds = opt.folds;
  if (opt.validate_last > 0.0) {
    if (!(opt.validate_last < 1.0)) throw InputError("--validate-last must lie in (0, 1)");
    const Eigen::Index first =
        static_cast<Eigen::Index>(std::floor((1.0 - opt.validate_last) * static_cast<double>(S)));
    for (Eigen::Index s = 0; s < S; ++s) fold[s] = s >= first ? 0 : -1;
    folds = 1;
    res.validation =
        "time split: last " + std::to_string(static_cast<int>(std::lround(opt.validate_last * 100))) + "% validates";
  } else {
    if (folds < 2) throw InputError("--folds must be >= 2");
    const Eigen::Index block = std::max<Eigen::Index>(1, std::lround(opt.block_seconds * data.rate_hz));
    if (S < block * folds)
      throw InputError("too few samples for " + std::to_string(folds) + " folds of " +
                       std::to_string(opt.block_seconds) + " s blocks");
    for (Eigen::Index s = 0; s < S; ++s) fold[s] = static_cast<int>((s / block) % folds);
    res.validation = "blocked " + std::to_string(folds) + "-fold cross-validation, " +
                     std::to_string(opt.block_seconds).substr(0, 4) + " s blocks";
  }
  if (!opt.effects.empty()) {
    // Effect terms (model_effects.hpp): [W E] fitted at run time, validated the same way.
    fit_effect_model(data, opt.effects, fold, folds, robot, opt, res);
    res.model = model_spec_name({Terms, opt.effects});
  } else {
    Eigen::VectorXd pred = Eigen::VectorXd::Constant(S * N, std::nan(""));
    typename Pipe::ParamVec phi, stdev;
    for (int f = 0; f < folds; ++f) {
      std::vector<char> train(static_cast<size_t>(S));
      for (Eigen::Index s = 0; s < S; ++s) train[s] = fold[s] != f;
      pipe.fit(data, train, phi, stdev);
      for (Eigen::Index s = 0; s < S; ++s) {
        if (fold[s] != f) continue;
        pred.segment(s * N, N) = data.W.block(s * N, 0, N, P) * phi;
      }
    }
    // Metrics from the pooled out-of-fold residuals.
    res.joints = torque_metrics(data.y, pred, N, robot.tau_max);
    // Final fit on all data: reported parameters.
    std::vector<char> all(static_cast<size_t>(S), 1);
    const auto t0 = std::chrono::steady_clock::now();
    ConsistentSolution consistent;
    pipe.fit(data, all, phi, stdev, &res.condition_number, &consistent);
    res.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    for (int i = 0; i < P; ++i) res.params.push_back({Pipe::param_name(i), phi[i], stdev[i]});
    {
      char line[200];
      std::snprintf(line, sizeof line,
                    "parameter std: the white-noise figures times %.3g for the residual's autocorrelation (S / n_eff)",
                    std::sqrt(autocorrelation_inflation(data, all, data.y - data.W * phi)));
      res.notes.push_back(line);
    }
    for (size_t l = 0; l < consistent.min_eigenvalue.size(); ++l) {
      const std::array<double, 10> v = physical_parameters(consistent.standard.data() + 10 * l);
      res.links.push_back({static_cast<int>(l) + 1,
                           v[0],
                           {v[1], v[2], v[3]},
                           {v[4], v[5], v[6], v[7], v[8], v[9]},
                           consistent.min_eigenvalue[l]});
    }
  }
  for (int j = 0; j < N; ++j) {
    if (!(Terms & term::rotor_inertia) || Robot::rotor_inertia_separate(j)) continue;
    if (Robot::rotor_inertia_absorbed_into(j) < 0) {  // robot.json: "rotor_inertia": false
      res.notes.push_back("Ia" + std::to_string(j + 1) +
                          ": the robot file declares no rotor inertia, so none is modelled (set \"rotor_inertia\": "
                          "true in robot.json and build again to add it)");
    } else {
      res.notes.push_back("Ia" + std::to_string(j + 1) + " is not separable from the rigid body: it is included in " +
                          Robot::base_param_name(Robot::rotor_inertia_absorbed_into(j)));
    }
  }
  return res;
}

}  // namespace dyncal::host
