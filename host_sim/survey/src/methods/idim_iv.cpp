#include "dyncal_host/survey/methods/idim_iv.hpp"

#include <Eigen/Dense>
#include <chrono>
#include <cstdio>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/pipeline/butterworth.hpp"
#include "dyncal_host/identification/pipeline/signal.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"

namespace dyncal::host {
namespace {

using Robot = dyncal::generated::er20::Robot;
using Model7 = IdentificationModel<Robot, kFrictionEq7>;
constexpr int P7 = Model7::kNumParams;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using PV = Eigen::Matrix<double, P7, 1>;

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

/// The length of `step` in standard errors of the instrumental-variable estimate phi (Eq. 17) of
/// the weighted system y = K phi with instruments Z: sqrt(step^T C^-1 step / P), C = s^2 (Z^T K)^-1
/// Z^T Z (K^T Z)^-1 its covariance, s^2 = |y - K phi|^2 / (rows - P); step^T C^-1 step = |P_Z K
/// step|^2 / s^2 (P_Z the projection onto Z's columns). The rows' errors are taken independent:
/// filtered, differentiated positions make them correlated, so s^2 / rows understates the variance
/// and the step's length in standard errors is, if anything, overstated (a stricter test).
double step_in_standard_errors(const Eigen::MatrixXd& K, const Eigen::MatrixXd& Z, const Eigen::VectorXd& y,
                               const PV& phi, const PV& step) {
  const double P = static_cast<double>(K.cols());
  const double s2 = (y - K * phi).squaredNorm() / (static_cast<double>(K.rows()) - P);
  const Eigen::VectorXd k_step = K * step;
  const Eigen::VectorXd projected = Z * Z.colPivHouseholderQr().solve(k_step);
  return std::sqrt(projected.squaredNorm() / s2 / P);
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
  // The first instruments come from the CAD plant with IDIM-OLS's friction: OLS on noisy positions
  // underestimates the inertias (errors in variables), and a plant lighter than the real one can
  // make the drive's fixed-gain loop unstable in simulation.
  PV phi = K.colPivHouseholderQr().solve(y);
  int iterations = 0;
  bool converged = false, relax = false;
  double previous_step = INFINITY, last_step_se = INFINITY;
  while (iterations < o.max_iterations && !converged) {
    // The plant of this iterate: consistent standard parameters and non-negative friction.
    const Estimate cur = eq7_estimate(phi, "IDIM-IV");
    const Eigen::VectorXd phi_std =
        nearest_consistent(iterations == 0 ? settings.prior.mean : standard_from_base(cur.base, settings.prior));
    std::array<double, 6> Fc{}, beta{};
    for (int j = 0; j < 6; ++j) {
      Fc[j] = std::max(0.0, cur.friction[static_cast<size_t>(2 * j)]);
      beta[j] = std::max(0.0, cur.friction[static_cast<size_t>(2 * j + 1)]);
    }
    RunData simulated;
    simulated.q = simulate(phi_std, Fc, beta);
    ++iterations;
    if (simulated.q.rows() != d.q.rows()) throw InputError("IDIM-IV: simulation length differs");
    // Instruments: the simulated positions through the same filter and differentiation as the measured ones.
    simulated.sample_rate_hz = d.sample_rate_hz;
    simulated.q_meas = simulated.q;
    Eigen::MatrixXd qs, qds, qdds;
    measured_states(simulated, o, qs, qds, qdds);
    Eigen::MatrixXd Z = stacked(qs, qds, qdds);
    parallel_decimation(Z, nullptr, d.sample_rate_hz, o.decimation);
    Eigen::VectorXd unused = Eigen::VectorXd::Zero(Z.rows());
    weight_rows(Z, unused, settings.sigma);
    const PV next = (Z.transpose() * K).colPivHouseholderQr().solve(Z.transpose() * y);
    if (!next.allFinite()) throw InputError("IDIM-IV: the instrumental estimate is not finite");
    const double step = (next - phi).norm();
    last_step_se = step_in_standard_errors(K, Z, y, next, next - phi);
    converged = last_step_se <= o.tolerance;
    // The map from plant to estimate need not contract (on the two-period run it flipped between
    // two plants for 20 iterations): once a step fails to halve the previous one, take half steps
    // (Mann iteration), which damps such a cycle.
    if (step > 0.5 * previous_step) relax = true;
    previous_step = step;
    phi = relax ? PV(0.5 * (phi + next)) : next;
  }
  Estimate e = eq7_estimate(phi, "IDIM-IV");
  e.iterations = iterations;
  char last[64];
  std::snprintf(last, sizeof last, "last step %.2g standard errors", last_step_se);
  e.note = (converged ? "converged, " : "not converged in " + std::to_string(iterations) + " iterations, ") +
           std::string(last);
  e.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  complete_estimate(e, d, settings);
  return e;
}

}  // namespace dyncal::host
