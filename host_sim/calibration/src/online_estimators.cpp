#include "dyncal_host/calibration/online_estimators.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <string>
#include <utility>

#include "dyncal/causal_differentiator.hpp"
#include "dyncal/robot_model.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/pipeline/recursive_fit.hpp"

namespace dyncal::host {
namespace {

/// The online path and the verification of a model of N joints.
template <int N>
struct OnlineOfJoints {
  using Vec = Eigen::Matrix<double, N, 1>;
  using Regressor = Eigen::Matrix<double, N, Eigen::Dynamic>;

  struct Online {
    const TermSetModel* model = nullptr;
    std::unique_ptr<RecursiveFit> kf, rls;
    CausalDifferentiator<double, N> diff;
    Regressor K;
    Vec qd_max;
    double min_speed = 0;
    long updates = 0, rejected = 0;

    void push(const port::DriveSample& sample) {
      Vec q_in, tau_in, q, qd, qdd, tau;
      for (int j = 0; j < N; ++j) {
        q_in[j] = sample.q[j];
        tau_in[j] = sample.tau[j];
      }
      if (diff.update(q_in, tau_in, q, qd, qdd, tau) != UpdateStatus::ok) return;
      model->regressor(q.data(), qd.data(), qdd.data(), K.data());
      for (int j = 0; j < N; ++j) {  // stiction band: as the batch fit, relative to the joint's speed limit
        if (std::abs(qd[j]) >= min_speed * qd_max[j]) continue;
        K.row(j).setZero();
        tau[j] = 0.0;
      }
      const Vec ones = Vec::Ones();  // KF: unit measurement variance; RLS: unit weights (Eq. 23)
      const UpdateStatus a = kf->update(K.data(), tau.data(), ones.data());
      const UpdateStatus b = rls->update(K.data(), tau.data(), ones.data());
      ++updates;
      if (a != UpdateStatus::ok || b != UpdateStatus::ok) ++rejected;
    }
    void finish(CalibrateResult& r) const {
      const Eigen::VectorXd phi_kf = kf->estimate(), phi_rls = rls->estimate();
      r.phi_kf.assign(phi_kf.data(), phi_kf.data() + phi_kf.size());
      r.phi_rls.assign(phi_rls.data(), phi_rls.data() + phi_rls.size());
      r.online_updates = updates;
      r.online_rejected = rejected;
    }
  };

  static void start(const TermSetModel& m, const Eigen::VectorXd& qd_max, const CalibrateOptions& o, SampleSink& sink) {
    auto st = std::make_shared<Online>();
    st->model = &m;
    UpdateStatus status = UpdateStatus::ok;
    st->kf = make_kalman_filter(m, o.identify.p0, &status);
    if (!st->kf) throw InputError(std::string("online KF: initial covariance refused (") + to_string(status) + ")");
    st->rls = make_rls(m, o.identify.p0, o.rls_mu, &status);
    if (!st->rls)
      throw InputError(std::string("online RLS: initial covariance or mu refused (") + to_string(status) + ")");
    if (st->diff.reset(1.0 / o.sample_rate_hz, o.online_cutoff_hz) != UpdateStatus::ok) {
      throw InputError("online cut-off must be below half the sample rate");
    }
    st->K.resize(N, m.num_params);
    st->qd_max = qd_max;
    st->min_speed = o.identify.min_speed_fraction;
    sink.push = [st](const port::DriveSample& s) { st->push(s); };
    sink.finish = [st](CalibrateResult& r) { st->finish(r); };
  }

  static VerificationErrors verify(const TermSetModel& m, const JointLog& log, const std::vector<double>& phi_v,
                                   const std::vector<EffectTerm>& effects, double cutoff) {
    const int P = m.num_params, B = m.num_base;
    const Eigen::Map<const Eigen::VectorXd> phi(phi_v.data(), P);
    for (const EffectTerm& e : effects) {
      if (!effect_term_valid(e, N)) throw InputError("verification: an effect term is not valid for this robot");
    }
    CausalDifferentiator<double, N> diff;
    diff.reset(log.sample_period(), cutoff);
    Regressor K(N, P);
    Vec se = Vec::Zero(), st = Vec::Zero();
    long n = 0;
    for (Eigen::Index s = 0; s < log.samples(); ++s) {
      Vec q, qd, qdd, tau;
      if (diff.update(log.q.row(s).transpose(), log.tau.row(s).transpose(), q, qd, qdd, tau) != UpdateStatus::ok)
        continue;
      m.regressor(q.data(), qd.data(), qdd.data(), K.data());
      Vec tau_hat = K * phi;
      if (!effects.empty()) {  // as the drive's feed-forward applies a table's effect terms
        const Vec tau_rb = K.leftCols(B) * phi.head(B);
        add_effect_torques(effects.data(), static_cast<int>(effects.size()), q, qd, qdd, tau_rb, tau_hat);
      }
      se += (tau - tau_hat).cwiseAbs2();
      st += tau.cwiseAbs2();
      ++n;
    }
    VerificationErrors e;
    for (int j = 0; j < N; ++j) {
      e.rms[j] = std::sqrt(se[j] / static_cast<double>(std::max(1L, n)));
      e.rms_tau[j] = std::sqrt(st[j] / static_cast<double>(std::max(1L, n)));
    }
    return e;
  }
};

template <int... I>
constexpr auto start_by_joints(std::integer_sequence<int, I...>) {
  using Fn = void (*)(const TermSetModel&, const Eigen::VectorXd&, const CalibrateOptions&, SampleSink&);
  return std::array<Fn, sizeof...(I)>{&OnlineOfJoints<I + 1>::start...};
}
template <int... I>
constexpr auto verify_by_joints(std::integer_sequence<int, I...>) {
  using Fn = VerificationErrors (*)(const TermSetModel&, const JointLog&, const std::vector<double>&,
                                    const std::vector<EffectTerm>&, double);
  return std::array<Fn, sizeof...(I)>{&OnlineOfJoints<I + 1>::verify...};
}

void check_model(const TermSetModel& m, const char* what) {
  if (m.num_joints < 1 || m.num_joints > kMaxRobotJoints || !m.regressor)
    throw InputError(std::string(what) + ": the robot's identification model is not compiled in this build");
}

}  // namespace

void start_online_estimators(const TermSetModel& model, const Eigen::VectorXd& qd_max, const CalibrateOptions& options,
                             SampleSink& sink) {
  check_model(model, "online estimators");
  static constexpr auto by_joints = start_by_joints(std::make_integer_sequence<int, kMaxRobotJoints>());
  by_joints[static_cast<size_t>(model.num_joints - 1)](model, qd_max, options, sink);
}

VerificationErrors verify_parameters(const TermSetModel& model, const JointLog& log, const std::vector<double>& phi,
                                     const std::vector<EffectTerm>& effects, double cutoff) {
  check_model(model, "verification");
  if (phi.size() < static_cast<size_t>(model.num_params))
    throw InputError("verification: " + std::to_string(phi.size()) + " parameters for a model of " +
                     std::to_string(model.num_params));
  static constexpr auto by_joints = verify_by_joints(std::make_integer_sequence<int, kMaxRobotJoints>());
  return by_joints[static_cast<size_t>(model.num_joints - 1)](model, log, phi, effects, cutoff);
}

}  // namespace dyncal::host
