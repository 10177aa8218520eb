#pragma once
// OnlineModel for one generated robot (online_model.hpp); included by the robots' registration
// units (host_sim/robots/robot_calibration.cpp.in) only.

#include <memory>
#include <utility>

#include "dyncal/causal_differentiator.hpp"
#include "dyncal/effect_terms.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal_host/calibration/online_model.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

/// Online path and verification of IdentificationModel<Robot, Terms>.
template <class Robot, unsigned Terms>
struct OnlineModelRun {
  static constexpr int N = Robot::kNumJoints;
  using Model = IdentificationModel<Robot, Terms>;
  static constexpr int P = Model::kNumParams;
  using ParamVec = Eigen::Matrix<double, P, 1>;
  using Vec = Eigen::Matrix<double, N, 1>;

  /// The online path: lib/ KF and RLS updated with each sample as it arrives from the drive.
  struct Online {
    std::unique_ptr<KalmanFilter<double, P, N>> kf = std::make_unique<KalmanFilter<double, P, N>>();
    std::unique_ptr<RlsForgetting<double, P, N>> rls = std::make_unique<RlsForgetting<double, P, N>>();
    CausalDifferentiator<double, N> diff;
    typename Model::template Regressor<double> K;
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
      Model::regressor(q, qd, qdd, Vec::Zero().eval(), K);
      for (int j = 0; j < N; ++j) {  // stiction band: as the batch fit, relative to the joint's speed limit
        if (std::abs(qd[j]) >= min_speed * qd_max[j]) continue;
        K.row(j).setZero();
        tau[j] = 0.0;
      }
      const UpdateStatus a = kf->update(K, tau, Vec::Ones());
      const UpdateStatus b = rls->update(K, tau);
      ++updates;
      if (a != UpdateStatus::ok || b != UpdateStatus::ok) ++rejected;
    }
    void finish(CalibrateResult& r) const {
      r.phi_kf.assign(kf->estimate().data(), kf->estimate().data() + P);
      r.phi_rls.assign(rls->estimate().data(), rls->estimate().data() + P);
      r.online_updates = updates;
      r.online_rejected = rejected;
    }
  };

  static void online(const Eigen::VectorXd& qd_max, const CalibrateOptions& o, SampleSink& sink) {
    auto st = std::make_shared<Online>();
    const ParamVec p0 = ParamVec::Constant(o.identify.p0);
    st->kf->reset(ParamVec::Zero(), p0);
    st->rls->reset(ParamVec::Zero(), p0, o.rls_mu);
    if (st->diff.reset(1.0 / o.sample_rate_hz, o.online_cutoff_hz) != UpdateStatus::ok) {
      throw InputError("online cut-off must be below half the sample rate");
    }
    st->qd_max = qd_max;
    st->min_speed = o.identify.min_speed_fraction;
    sink.push = [st](const port::DriveSample& s) { st->push(s); };
    sink.finish = [st](CalibrateResult& r) { st->finish(r); };
  }

  static VerificationErrors verify(const JointLog& log, const std::vector<double>& phi_v,
                                   const std::vector<EffectTerm>& effects, double cutoff) {
    ParamVec phi;
    for (int i = 0; i < P; ++i) phi[i] = phi_v[static_cast<size_t>(i)];
    for (const EffectTerm& e : effects) {
      if (!effect_term_valid(e, N)) throw InputError("verification: an effect term is not valid for this robot");
    }
    CausalDifferentiator<double, N> diff;
    diff.reset(log.sample_period(), cutoff);
    typename Model::template Regressor<double> K;
    Vec se = Vec::Zero(), st = Vec::Zero();
    long n = 0;
    for (Eigen::Index s = 0; s < log.samples(); ++s) {
      Vec q, qd, qdd, tau;
      if (diff.update(log.q.row(s).transpose(), log.tau.row(s).transpose(), q, qd, qdd, tau) != UpdateStatus::ok)
        continue;
      Model::regressor(q, qd, qdd, Vec::Zero().eval(), K);
      Vec tau_hat = K * phi;
      if (!effects.empty()) {  // as the drive's feed-forward applies a table's effect terms
        const Vec tau_rb = K.template leftCols<Robot::kNumBase>() * phi.template head<Robot::kNumBase>();
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

/// Registers the online model of `Robot` for the built term sets First..First+3.
template <class Robot, int First, int... I>
bool register_online_model_of(std::integer_sequence<int, I...>) {
  OnlineModel m;
  ((m.online[First + I] = &OnlineModelRun<Robot, built_term_set(First + I)>::online,
    m.verify[First + I] = &OnlineModelRun<Robot, built_term_set(First + I)>::verify),
   ...);
  return register_online_model(Robot::kName, m);
}

}  // namespace dyncal::host
