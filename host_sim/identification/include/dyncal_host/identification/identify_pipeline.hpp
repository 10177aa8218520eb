#pragma once
// The identification pipeline for one generated robot and one term set (host side).

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <memory>

#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/butterworth.hpp"
#include "dyncal_host/identification/identify.hpp"
#include "dyncal_host/identification/signal.hpp"
#include "dyncal_host/identification/stacked_data.hpp"

namespace dyncal::host {

template <class Robot, unsigned Terms>
class IdentifyPipeline {
 public:
  using Model = IdentificationModel<Robot, Terms>;
  static constexpr int N = Robot::kNumJoints;
  static constexpr int P = Model::kNumParams;
  using JointVec = Eigen::Matrix<double, N, 1>;
  using ParamVec = Eigen::Matrix<double, P, 1>;

  IdentifyPipeline(const RobotDescription& robot, const IdentifyOptions& options) : robot_(robot), opt_(options) {}

  /// Filtering, differentiation, regressor, parallel filtering and decimation (Gautier 1997).
  StackedData prepare(const JointLog& log) const {
    const double fs = 1.0 / log.sample_period();
    const ButterworthLowPass filter(opt_.filter_order, opt_.cutoff_hz, fs);
    Eigen::MatrixXd q = log.q;
    filter.filtfilt(q);
    Eigen::MatrixXd qd, qdd;
    if (log.has_qd) {
      qd = log.qd;
      filter.filtfilt(qd);
    } else {
      qd = central_difference(q, log.sample_period());
    }
    if (log.has_qdd) {
      qdd = log.qdd;
      filter.filtfilt(qdd);
    } else {
      qdd = central_difference(qd, log.sample_period());
    }
    Eigen::MatrixXd tau = log.tau;
    filter.filtfilt(tau);
    const Eigen::Index S = log.samples();
    // Regressor columns over time: column (j * P + c) holds K(j, c) at every sample (parallel filtering).
    const JointVec zero = JointVec::Zero();
    auto regressor_over_time = [&](bool with_qdd) {
      Eigen::MatrixXd Kt(S, N * P);
      typename Model::template Regressor<double> K;
      for (Eigen::Index s = 0; s < S; ++s) {
        Model::regressor(JointVec(q.row(s).transpose()), JointVec(qd.row(s).transpose()),
                         with_qdd ? JointVec(qdd.row(s).transpose()) : zero, zero, K);
        for (int j = 0; j < N; ++j) Kt.row(s).segment(j * P, P) = K.row(j);
      }
      filter.filtfilt(Kt);
      return Kt;
    };
    const Eigen::MatrixXd Kt = regressor_over_time(true);
    const Eigen::MatrixXd Kt_load = opt_.load_regressor ? regressor_over_time(false) : Eigen::MatrixXd();
    int d = opt_.decimate > 0 ? opt_.decimate : static_cast<int>(std::floor(fs / (25.0 * opt_.cutoff_hz)));
    d = std::max(d, 1);
    // Drop one cut-off period at each end, where differentiation and filtering are one-sided.
    const Eigen::Index edge = static_cast<Eigen::Index>(std::ceil(fs / opt_.cutoff_hz));
    if (S <= 2 * edge + 2 * P / N * d) {
      throw InputError("too few samples (" + std::to_string(S) + ") for " + std::to_string(P) + " parameters");
    }
    StackedData out;
    const Eigen::Index kept = (S - 2 * edge + d - 1) / d;
    out.W.resize(kept * N, P);
    if (opt_.load_regressor) out.W_load.resize(kept * N, P);
    out.y.resize(kept * N);
    out.t.resize(kept);
    out.rate_hz = fs / d;
    // Rows of a joint moving slower than min_speed_fraction of its top speed stay out of the fit:
    // there a real joint sticks and Coulomb friction takes any value in [-Fc, Fc], which sgn(qd)
    // cannot represent. They still count in the validation metrics.
    JointVec threshold = JointVec::Zero();
    for (Eigen::Index s = edge; s < S - edge; ++s)
      threshold = threshold.cwiseMax(JointVec(qd.row(s).transpose()).cwiseAbs());
    threshold *= opt_.min_speed_fraction;
    out.fit_row.assign(static_cast<size_t>(kept * N), 1);
    out.q.resize(kept, N);
    out.qd.resize(kept, N);
    out.qdd.resize(kept, N);
    out.cutoff_hz = opt_.cutoff_hz;
    out.num_base = Robot::kNumBase;
    for (int i = 0; i < P; ++i) out.names.push_back(param_name(i));
    for (Eigen::Index k = 0; k < kept; ++k) {
      const Eigen::Index s = edge + k * d;
      out.t[k] = log.t[s];
      out.q.row(k) = q.row(s);
      out.qd.row(k) = qd.row(s);
      out.qdd.row(k) = qdd.row(s);
      for (int j = 0; j < N; ++j) {
        out.W.row(k * N + j) = Kt.row(s).segment(j * P, P);
        if (opt_.load_regressor) out.W_load.row(k * N + j) = Kt_load.row(s).segment(j * P, P);
        out.y[k * N + j] = tau(s, j);
        if (std::abs(qd(s, j)) < threshold[j]) out.fit_row[static_cast<size_t>(k * N + j)] = 0;
      }
    }
    return out;
  }

  /// Fits on the samples with train[s] true. Writes phi and parameter standard deviations.
  void fit(const StackedData& data, const std::vector<char>& train, ParamVec& phi, ParamVec& stdev,
           double* cond = nullptr) const {
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
    const JointVec dof = (n.array() - static_cast<double>(P) / N).max(1.0).matrix();
    const JointVec sigma = ss.cwiseQuotient(dof).cwiseSqrt().cwiseMax(1e-12);
    const std::string& m = opt_.method;
    if (m == "ols") {
      ls_statistics(*ls, stdev, cond);
    } else if (m == "wls") {
      ls->reset();
      for (Eigen::Index s = 0; s < S; ++s) {
        if (!train[s]) continue;
        for (int j = 0; j < N; ++j) {
          if (data.fit_row[s * N + j])
            check(ls->add_row(data.W.row(s * N + j).transpose(), data.y[s * N + j], 1.0 / sigma[j]));
        }
      }
      if (ls->solve(phi) != UpdateStatus::ok) throw InputError("weighted regressor rank deficient");
      ls_statistics(*ls, stdev, cond);
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
      throw InputError("unknown method '" + m + "' (expected ols, wls, kf or rls)");
    }
  }

  static std::string param_name(int i) {
    const ParamInfo info = Model::info(i);
    if (info.kind == ParamKind::base) return Robot::base_param_name(info.base_index);
    return std::string(term_name(info.term)) + std::to_string(info.joint);
  }

 private:
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
  const Eigen::Index S = data.t.size();
  IdentifyResult res;
  res.robot = robot.name;
  res.method = opt.method;
  res.model = model_name(Terms);
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
  for (int j = 0; j < N; ++j) {
    double se = 0, st = 0, sum_tau = 0, sum_abs = 0, sum_abs2 = 0;
    long n = 0;
    for (Eigen::Index s = 0; s < S; ++s) {
      if (std::isnan(pred[s * N + j])) continue;
      const double y = data.y[s * N + j];
      sum_tau += y;
      ++n;
    }
    const double mean_tau = sum_tau / static_cast<double>(n);
    for (Eigen::Index s = 0; s < S; ++s) {
      if (std::isnan(pred[s * N + j])) continue;
      const double y = data.y[s * N + j];
      const double e = y - pred[s * N + j];
      se += e * e;
      st += (y - mean_tau) * (y - mean_tau);
      const double a = std::abs(e) / robot.tau_max[j];
      sum_abs += a;
      sum_abs2 += a * a;
    }
    JointMetrics m;
    m.joint = j + 1;
    m.rms = std::sqrt(se / static_cast<double>(n));
    m.rms_tau = std::sqrt((st + static_cast<double>(n) * mean_tau * mean_tau) / static_cast<double>(n));
    m.relative_rms = m.rms / m.rms_tau;
    m.r2 = 1.0 - se / st;
    m.e_T = sum_abs / static_cast<double>(n);
    m.e_T_std = std::sqrt(std::max(0.0, sum_abs2 / static_cast<double>(n) - m.e_T * m.e_T));
    res.joints.push_back(m);
  }
  // Final fit on all data: reported parameters.
  std::vector<char> all(static_cast<size_t>(S), 1);
  const auto t0 = std::chrono::steady_clock::now();
  pipe.fit(data, all, phi, stdev, &res.condition_number);
  res.fit_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  for (int i = 0; i < P; ++i) res.params.push_back({Pipe::param_name(i), phi[i], stdev[i]});
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
