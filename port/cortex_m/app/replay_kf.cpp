// Firmware application: the same lib/ code as the host — generated er20 regressor, identification
// model (base parameters + Eq. 7 friction), Kalman filter (survey Eq. 19) — run over a block of
// drive samples, float on the Cortex-M4F and double on the M7. The samples are synthesised on the
// target from the er20 model with its nominal parameters and set friction (noise-free), so the
// check is self-contained: the identified model must predict fresh samples to 1e-3 of their RMS.
#include "dyncal/fourier_trajectory.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal_cortex_m/instruction_counter.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "er20/robot.hpp"

#ifndef DYNCAL_FW_SCALAR
#define DYNCAL_FW_SCALAR float
#endif

namespace {

using Scalar = DYNCAL_FW_SCALAR;
using Robot = dyncal::generated::er20::Robot;
using Model = dyncal::IdentificationModel<Robot, dyncal::kFrictionEq7>;
constexpr int P = Model::kNumParams;
using Vec = Eigen::Matrix<Scalar, 6, 1>;
using ParamVec = Eigen::Matrix<Scalar, P, 1>;
namespace sh = dyncal::cortex_m;

// Static storage: no heap, no large stack frames.
dyncal::KalmanFilter<Scalar, P, 6> g_kf;
Model::Regressor<Scalar> g_K;
dyncal::FourierTrajectory<Scalar, 6, 5> g_traj;
ParamVec g_truth;

void true_parameters() {
  Eigen::Matrix<Scalar, Robot::kNumStandard, 1> phi;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi[i] = Scalar(dyncal::generated::er20::kNominalStandard[i]);
  Eigen::Matrix<Scalar, Robot::kNumBase, 1> phi_b;
  dyncal::generated::er20::standard_to_base(phi, phi_b);
  g_truth.setZero();
  g_truth.template head<Robot::kNumBase>() = phi_b;
  const Scalar fc[6] = {60, 55, 50, 12, 10, 8}, fv[6] = {45, 42, 40, 8, 7, 5};  // robots/er20/robot.json
  for (int j = 0; j < 6; ++j) {
    g_truth[Model::column(dyncal::term::coulomb, j)] = fc[j];
    g_truth[Model::column(dyncal::term::viscous, j)] = fv[j];
  }
}

void trajectory() {
  // A fixed, well-exciting Fourier trajectory (Eq. 27, L = 5, f_f = 0.1 Hz).
  g_traj.f_f = Scalar(0.1);
  g_traj.harmonics = 5;
  for (int j = 0; j < 6; ++j) {
    for (int l = 0; l < 5; ++l) {
      g_traj.a(j, l) = Scalar(0.3) * Scalar(((j * 7 + l * 3) % 5) - 2) / Scalar(l + 1);
      g_traj.b(j, l) = Scalar(0.3) * Scalar(((j * 3 + l * 5) % 7) - 3) / Scalar(l + 2);
    }
  }
}

void sample(Scalar t, Vec& tau) {
  Vec q, qd, qdd;
  g_traj.evaluate(t, q, qd, qdd);
  Model::regressor(q, qd, qdd, Vec::Zero().eval(), g_K);
  tau.noalias() = g_K * g_truth;
}

}  // namespace

int main() {
  true_parameters();
  trajectory();
  if (g_kf.reset(ParamVec::Zero(), ParamVec::Constant(Scalar(1e4)), Model::structure()) != dyncal::UpdateStatus::ok) return 2;
  const Vec r = Vec::Constant(Scalar(1));  // 1 Nm^2: a drive torque channel; see UdCovariance for tiny r
  const int samples = 2000;  // 20 s at 100 Hz
  int rejected = 0;
  using Counter = dyncal::cortex_m::InstructionCounter;
  Counter::start();
  std::uint32_t ticks_sample = 0, ticks_update = 0;
  for (int k = 0; k < samples; ++k) {
    Vec tau;
    const std::uint32_t t0 = Counter::ticks();
    sample(Scalar(k) / Scalar(100), tau);  // trajectory, generated regressor, tau = K phi
    const std::uint32_t t1 = Counter::ticks();
    const dyncal::UpdateStatus st = g_kf.update(g_K, tau, r);
    const std::uint32_t t2 = Counter::ticks();
    ticks_sample += Counter::elapsed(t0, t1);
    ticks_update += Counter::elapsed(t1, t2);
    if (st != dyncal::UpdateStatus::ok) ++rejected;
  }
  // Prediction on fresh samples (the second period, shifted by half a sample).
  Scalar se = 0, st = 0;
  for (int k = 0; k < 500; ++k) {
    Vec tau;
    sample(Scalar(10) + (Scalar(k) + Scalar(0.5)) / Scalar(50), tau);
    se += (tau - g_K * g_kf.estimate()).squaredNorm();
    st += tau.squaredNorm();
  }
  const Scalar rel = std::sqrt(se / st);
  sh::write("dyncal firmware replay (KF, ");
  sh::write(sizeof(Scalar) == 4 ? "float" : "double");
  sh::write("): ");
  sh::write_int(samples);
  sh::write(" samples, ");
  sh::write_int(P);
  sh::write(" parameters, ");
  sh::write_int(rejected);
  sh::write(" rejected; relative prediction RMS on fresh samples ");
  sh::write_float(static_cast<double>(rel), 3);
  sh::write("\n  estimates Fc1 Fv1 Fc6 Fv6: ");
  for (unsigned t : {dyncal::term::coulomb, dyncal::term::viscous}) {
    sh::write_float(static_cast<double>(g_kf.estimate()[Model::column(t, 0)]), 5);
    sh::write(" ");
  }
  for (unsigned t : {dyncal::term::coulomb, dyncal::term::viscous}) {
    sh::write_float(static_cast<double>(g_kf.estimate()[Model::column(t, 5)]), 5);
    sh::write(" ");
  }
  sh::write("\n  instructions per sample (qemu -icount, +-40): trajectory + regressor + K phi ");
  sh::write_int(static_cast<long long>(ticks_sample) * Counter::kInstructionsPerTick / samples);
  sh::write(", KF update ");
  sh::write_int(static_cast<long long>(ticks_update) * Counter::kInstructionsPerTick / samples);
  sh::write("\n");
  return (rejected == 0 && rel < Scalar(1e-3)) ? 0 : 1;
}
