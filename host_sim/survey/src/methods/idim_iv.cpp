#include "dyncal_host/survey/methods/idim_iv.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <cstdio>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/butterworth.hpp"
#include "dyncal_host/identification/methods/instrumental_iteration.hpp"
#include "dyncal_host/identification/methods/signal.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Model7 = IdentificationModel<Robot, kFrictionEq7>;
constexpr int P7 = Model7::kNumParams;
using Vec6 = Eigen::Matrix<double, 6, 1>;

/// Stacked Eq. 7 regressor (6 S x 48) of states given as S x 6 matrices.
Eigen::MatrixXd stacked(const Eigen::MatrixXd& q, const Eigen::MatrixXd& qd, const Eigen::MatrixXd& qdd) {
  Eigen::MatrixXd W(6 * q.rows(), P7);
  Model7::Regressor<double> K;
  for (Eigen::Index s = 0; s < q.rows(); ++s) {
    Model7::regressor(Vec6(q.row(s).transpose()), Vec6(qd.row(s).transpose()), Vec6(qdd.row(s).transpose()),
                      Vec6::Zero().eval(), K);
    W.middleRows(6 * s, 6) = K;
  }
  return W;
}

Eigen::VectorXd stacked_torque(const Eigen::MatrixXd& tau) {
  Eigen::VectorXd y(6 * tau.rows());
  for (Eigen::Index s = 0; s < tau.rows(); ++s) y.segment<6>(6 * s) = tau.row(s).transpose();
  return y;
}

/// Each joint's rows weighted by 1 / sigma_j (Table 7 noise): the joints' torques differ in scale.
void weight_rows(Eigen::MatrixXd& W, Eigen::VectorXd& y, const std::array<double, 6>& sigma) {
  for (Eigen::Index i = 0; i < W.rows(); ++i) {
    const double w = 1.0 / sigma[static_cast<size_t>(i % 6)];
    W.row(i) *= w;
    y[i] *= w;
  }
}

/// Parallel decimation (Gautier's; survey Sec. 3.1): the torque and every regressor column
/// low-passed by the same zero-phase filter (fourth-order Butterworth at 0.8 times the Nyquist
/// frequency after decimation), then every `factor`-th sample kept. The same linear filter on both
/// sides keeps tau = W phi; it removes the noise above the band the excitation lives in. Stacked
/// rows (6 per sample, joint-minor) of W and y in place; y may be null (instruments).
void parallel_decimation(Eigen::MatrixXd& W, Eigen::VectorXd* y, double sample_rate_hz, int factor) {
  if (factor <= 1) return;
  const Eigen::Index S = W.rows() / 6, kept = (S + factor - 1) / factor, P = W.cols();
  const ButterworthLowPass filter(4, 0.8 * 0.5 * sample_rate_hz / factor, sample_rate_hz);
  Eigen::MatrixXd Wd(6 * kept, P);
  Eigen::VectorXd yd(6 * kept);
  for (Eigen::Index j = 0; j < 6; ++j) {
    Eigen::MatrixXd block(S, P + 1);  // joint j's rows: its regressor columns and its torque
    for (Eigen::Index s = 0; s < S; ++s) {
      block.row(s).head(P) = W.row(6 * s + j);
      block(s, P) = y ? (*y)[6 * s + j] : 0.0;
    }
    filter.filtfilt(block);
    for (Eigen::Index k = 0; k < kept; ++k) {
      Wd.row(6 * k + j) = block.row(k * factor).head(P);
      yd[6 * k + j] = block(k * factor, P);
    }
  }
  W = Wd;
  if (y) *y = yd;
}

/// The weighted least-squares system of the measured states: K (6 S x 48) and tau (6 S).
void measured_system(const RunData& d, const IdimIvOptions& o, const MethodSettings& settings, Eigen::MatrixXd& K,
                     Eigen::VectorXd& y) {
  Eigen::MatrixXd q, qd, qdd;
  measured_states(d, o, q, qd, qdd);
  K = stacked(q, qd, qdd);
  y = stacked_torque(d.tau);
  parallel_decimation(K, &y, d.sample_rate_hz, o.decimation);
  weight_rows(K, y, settings.sigma);
}

}  // namespace

void measured_states(const RunData& d, const IdimIvOptions& o, Eigen::MatrixXd& q, Eigen::MatrixXd& qd,
                     Eigen::MatrixXd& qdd) {
  if (d.q_meas.rows() != d.q.rows() || d.q.rows() < 3) throw InputError("IDIM-IV: no measured positions");
  q = d.q_meas;
  if (o.filter) ButterworthLowPass(o.filter_order, o.cutoff_hz, d.sample_rate_hz).filtfilt(q);
  const double dt = 1.0 / d.sample_rate_hz;
  qd = central_difference(q, dt);
  qdd = central_difference(qd, dt);
}

Estimate pseudo_inverse_measured(const RunData& d, const MethodSettings& settings, const IdimIvOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::MatrixXd K;
  Eigen::VectorXd y;
  measured_system(d, o, settings, K, y);
  Estimate e = eq7_estimate(K.colPivHouseholderQr().solve(y), "pseudo-inverse");
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  complete_estimate(e, d, settings);
  return e;
}

Estimate idim_iv(const RunData& d, const MethodSettings& settings, const IdimIvOptions& o,
                 const ClosedLoopSimulation& simulate) {
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::MatrixXd K;
  Eigen::VectorXd y;
  measured_system(d, o, settings, K, y);
  // Each iterate's plant: the standard parameters most probable under the CAD prior given its base
  // parameters, made consistent, with non-negative friction; the first is the CAD plant with
  // IDIM-OLS's friction. Its simulated positions go through the same filter, differentiation,
  // decimation and weights as the measured ones.
  const InstrumentsOf instruments = [&](const Eigen::VectorXd& phi, bool first) -> Eigen::MatrixXd {
    const Estimate cur = eq7_estimate(phi, "IDIM-IV");
    const Eigen::VectorXd phi_std =
        nearest_consistent(first ? settings.prior.mean : standard_from_base(cur.base, settings.prior));
    std::array<double, 6> Fc{}, beta{};
    for (int j = 0; j < 6; ++j) {
      Fc[j] = std::max(0.0, cur.friction[static_cast<size_t>(2 * j)]);
      beta[j] = std::max(0.0, cur.friction[static_cast<size_t>(2 * j + 1)]);
    }
    RunData simulated;
    simulated.q = simulate(phi_std, Fc, beta);
    if (simulated.q.rows() != d.q.rows()) throw InputError("IDIM-IV: simulation length differs");
    simulated.sample_rate_hz = d.sample_rate_hz;
    simulated.q_meas = simulated.q;
    Eigen::MatrixXd qs, qds, qdds;
    measured_states(simulated, o, qs, qds, qdds);
    Eigen::MatrixXd Z = stacked(qs, qds, qdds);
    parallel_decimation(Z, nullptr, d.sample_rate_hz, o.decimation);
    Eigen::VectorXd unused = Eigen::VectorXd::Zero(Z.rows());
    weight_rows(Z, unused, settings.sigma);
    return Z;
  };
  IvIterationOptions iteration;
  iteration.max_simulations = o.max_iterations;
  iteration.tolerance = o.tolerance;
  const IvIteration it = iterate_instruments(K, y, K.colPivHouseholderQr().solve(y), instruments, iteration);
  Estimate e = eq7_estimate(it.phi, "IDIM-IV");
  e.iterations = it.simulations;
  char last[64];
  std::snprintf(last, sizeof last, "last step %.2g standard errors", it.last_step_se);
  e.note = (it.converged ? "converged, " : "not converged in " + std::to_string(it.simulations) + " iterations, ") +
           std::string(last);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace dyncal::host
