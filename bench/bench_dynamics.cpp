// Generated er20 regressors against orocos-kdl's RNE on the same arm, and lib/ updater costs.
#include <benchmark/benchmark.h>

#include <kdl/chain.hpp>
#include <kdl/chainidsolver_recursive_newton_euler.hpp>
#include <memory>
#include <random>
#include <vector>

#include "dyncal/friction_tracker.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal/kalman_filter.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/payload_estimator.hpp"
#include "dyncal/rls_forgetting.hpp"
#include "dyncal/streaming_least_squares.hpp"
#include "dyncal/table_check.hpp"

namespace {

using Robot = dyncal::generated::er20::Robot;
using Vec = Eigen::Matrix<double, 6, 1>;
constexpr unsigned kTerms = dyncal::kFrictionEq7 | dyncal::term::rotor_inertia | dyncal::term::offset;
using Model = dyncal::IdentificationModel<Robot, kTerms>;
constexpr int P = Model::kNumParams;

struct States {
  std::vector<Vec> q, qd, qdd;
  States() {
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-2.0, 2.0);
    for (int i = 0; i < 64; ++i) {
      Vec a, b, c;
      for (int j = 0; j < 6; ++j) {
        a[j] = u(rng);
        b[j] = u(rng);
        c[j] = u(rng);
      }
      q.push_back(a);
      qd.push_back(b);
      qdd.push_back(c);
    }
  }
};
const States kStates;

void BM_StandardRegressor(benchmark::State& state) {
  Eigen::Matrix<double, 6, 60> Y;
  size_t i = 0;
  for (auto _ : state) {
    Robot::standard_regressor(kStates.q[i & 63], kStates.qd[i & 63], kStates.qdd[i & 63], Y);
    benchmark::DoNotOptimize(Y.data());
    ++i;
  }
}
BENCHMARK(BM_StandardRegressor);

void BM_BaseRegressor(benchmark::State& state) {
  Eigen::Matrix<double, 6, Robot::kNumBase> Yb;
  size_t i = 0;
  for (auto _ : state) {
    Robot::base_regressor(kStates.q[i & 63], kStates.qd[i & 63], kStates.qdd[i & 63], Yb);
    benchmark::DoNotOptimize(Yb.data());
    ++i;
  }
}
BENCHMARK(BM_BaseRegressor);

void BM_BaseRegressorWithFriction(benchmark::State& state) {
  Model::Regressor<double> K;
  const Vec zero = Vec::Zero();
  size_t i = 0;
  for (auto _ : state) {
    Model::regressor(kStates.q[i & 63], kStates.qd[i & 63], kStates.qdd[i & 63], zero, K);
    benchmark::DoNotOptimize(K.data());
    ++i;
  }
}
BENCHMARK(BM_BaseRegressorWithFriction);

void BM_InverseDynamics(benchmark::State& state) {
  Eigen::Matrix<double, 60, 1> phi;
  for (int k = 0; k < 60; ++k) phi[k] = dyncal::generated::er20::kNominalStandard[k];
  Vec tau;
  size_t i = 0;
  for (auto _ : state) {
    Robot::inverse_dynamics(kStates.q[i & 63], kStates.qd[i & 63], kStates.qdd[i & 63], phi, tau);
    benchmark::DoNotOptimize(tau.data());
    ++i;
  }
}
BENCHMARK(BM_InverseDynamics);

void BM_MassMatrix(benchmark::State& state) {
  Eigen::Matrix<double, 60, 1> phi;
  for (int k = 0; k < 60; ++k) phi[k] = dyncal::generated::er20::kNominalStandard[k];
  Eigen::Matrix<double, 6, 6> M;
  size_t i = 0;
  for (auto _ : state) {
    Robot::mass_matrix(kStates.q[i & 63], phi, M);
    benchmark::DoNotOptimize(M.data());
    ++i;
  }
}
BENCHMARK(BM_MassMatrix);

void BM_KdlRne(benchmark::State& state) {
  KDL::Chain chain;
  for (int k = 0; k < 6; ++k) {
    const auto& o = dyncal::generated::er20::kJointOrigins[k];
    const KDL::Rotation R(o.R[0], o.R[1], o.R[2], o.R[3], o.R[4], o.R[5], o.R[6], o.R[7], o.R[8]);
    const KDL::Vector p(o.p[0], o.p[1], o.p[2]);
    const double* s = &dyncal::generated::er20::kNominalStandard[10 * k];
    const double m = s[9];
    const KDL::Vector c(s[6] / m, s[7] / m, s[8] / m);
    // rotational inertia about the origin -> about the centre of mass: Ic = Io - m (|c|^2 1 - c c^T)
    const double cc = dot(c, c);
    const KDL::RotationalInertia Ic(s[0] - m * (cc - c.x() * c.x()), s[3] - m * (cc - c.y() * c.y()),
                                    s[5] - m * (cc - c.z() * c.z()), s[1] + m * c.x() * c.y(), s[2] + m * c.x() * c.z(),
                                    s[4] + m * c.y() * c.z());
    const KDL::RigidBodyInertia I(m, c, Ic);
    chain.addSegment(
        KDL::Segment(KDL::Joint("j", p, R * KDL::Vector(0, 0, 1), KDL::Joint::RotAxis), KDL::Frame(R, p), I));
  }
  KDL::ChainIdSolver_RNE rne(chain, KDL::Vector(0, 0, -9.81));
  KDL::JntArray q(6), qd(6), qdd(6), tau(6);
  KDL::Wrenches f(6, KDL::Wrench::Zero());
  size_t i = 0;
  for (auto _ : state) {
    for (int j = 0; j < 6; ++j) {
      q(j) = kStates.q[i & 63][j];
      qd(j) = kStates.qd[i & 63][j];
      qdd(j) = kStates.qdd[i & 63][j];
    }
    rne.CartToJnt(q, qd, qdd, f, tau);
    benchmark::DoNotOptimize(tau.data.data());
    ++i;
  }
}
BENCHMARK(BM_KdlRne);

// One update per iteration over 64 precomputed regressors (an update returns early only on a
// rejection; the status is checked to keep that honest).
template <class Filter, typename Scalar>
void run_filter(benchmark::State& state, Filter& f) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  std::vector<Eigen::Matrix<Scalar, 6, P>> K(64);
  const V zero = V::Zero(), r = V::Constant(Scalar(100)), tau = V::Ones();
  for (int i = 0; i < 64; ++i)
    Model::regressor<Scalar>(kStates.q[i].cast<Scalar>(), kStates.qd[i].cast<Scalar>(), kStates.qdd[i].cast<Scalar>(),
                             zero, K[i]);
  long i = 0, rejected = 0;
  for (auto _ : state) {
    if (f.update(K[i & 63], tau, r) != dyncal::UpdateStatus::ok) ++rejected;
    ++i;
  }
  state.counters["rejected"] = static_cast<double>(rejected);
}

template <typename Scalar>
void BM_KalmanUpdate(benchmark::State& state) {
  using PV = Eigen::Matrix<Scalar, P, 1>;
  auto kf = std::make_unique<dyncal::KalmanFilter<Scalar, P, 6>>();
  kf->reset(PV::Zero(), PV::Constant(Scalar(1e3)), Model::structure());
  run_filter<decltype(*kf), Scalar>(state, *kf);
}
BENCHMARK_TEMPLATE(BM_KalmanUpdate, double);
BENCHMARK_TEMPLATE(BM_KalmanUpdate, float);

template <typename Scalar>
void BM_KalmanUpdateUd(benchmark::State& state) {
  using PV = Eigen::Matrix<Scalar, P, 1>;
  auto kf = std::make_unique<dyncal::KalmanFilter<Scalar, P, 6, dyncal::UdCovariance<Scalar, P>>>();
  kf->reset(PV::Zero(), PV::Constant(Scalar(1e3)));
  run_filter<decltype(*kf), Scalar>(state, *kf);
}
BENCHMARK_TEMPLATE(BM_KalmanUpdateUd, double);

void BM_RlsUpdate(benchmark::State& state) {
  using PV = Eigen::Matrix<double, P, 1>;
  auto rls = std::make_unique<dyncal::RlsForgetting<double, P, 6>>();
  rls->reset(PV::Zero(), PV::Constant(1e3), 0.999, 0.0, Model::structure());
  run_filter<decltype(*rls), double>(state, *rls);
}
BENCHMARK(BM_RlsUpdate);

// The payload estimator of a drive: the payload regressor Y_b K_N at the state and the UD Kalman
// update of the load's 10 parameters (what one control-rate sample costs while it runs).
template <typename Scalar>
void BM_PayloadEstimatorUpdate(benchmark::State& state) {
  using Estimator = dyncal::PayloadEstimator<Robot, Scalar>;
  using V = typename Estimator::JointVector;
  auto est = std::make_unique<Estimator>();
  est->reset(Estimator::ParamVector::Constant(Scalar(1e3)));
  const V r = V::Constant(Scalar(0.01));
  long i = 0, rejected = 0;
  for (auto _ : state) {
    const V q = kStates.q[i & 63].cast<Scalar>(), qd = kStates.qd[i & 63].cast<Scalar>(),
            qdd = kStates.qdd[i & 63].cast<Scalar>();
    if (est->update(q, qd, qdd, Scalar(0.01) * qdd, r) != dyncal::UpdateStatus::ok) ++rejected;
    ++i;
  }
  state.counters["rejected"] = static_cast<double>(rejected);
}
BENCHMARK_TEMPLATE(BM_PayloadEstimatorUpdate, double);
BENCHMARK_TEMPLATE(BM_PayloadEstimatorUpdate, float);

// The generalised-momentum observer on a table of the nominal model (Eq. 7, Ia, offset): one
// update (mass matrix, inverse dynamics at qdd = 0, friction, the discrete step), what a drive
// running contact detection pays per control period.
template <typename Scalar>
void BM_MomentumObserverUpdate(benchmark::State& state) {
  using Observer = dyncal::MomentumObserver<Robot, Scalar>;
  using V = typename Observer::JointVector;
  Eigen::Matrix<double, Robot::kNumStandard, 1> phi_std;
  for (int i = 0; i < Robot::kNumStandard; ++i) phi_std[i] = dyncal::generated::er20::kNominalStandard[i];
  Eigen::Matrix<double, Robot::kNumBase, 1> phi_b;
  Robot::standard_to_base(phi_std, phi_b);
  Model::ParamVector<double> phi = Model::ParamVector<double>::Constant(0.1);
  phi.head<Robot::kNumBase>() = phi_b;
  dyncal::ParameterTable table;
  dyncal::make_table<Model>(phi, table);
  auto observer = std::make_unique<Observer>();
  if (observer->configure(table, V::Constant(Scalar(200)), Scalar(1e-3)) != dyncal::UpdateStatus::ok) {
    state.SkipWithError("configure refused the table");
    return;
  }
  long i = 0, rejected = 0;
  for (auto _ : state) {
    const V q = kStates.q[i & 63].cast<Scalar>(), qd = kStates.qd[i & 63].cast<Scalar>(),
            tau = kStates.qdd[i & 63].cast<Scalar>();
    if (observer->update(q, qd, tau) != dyncal::UpdateStatus::ok) ++rejected;
    ++i;
  }
  state.counters["rejected"] = static_cast<double>(rejected);
}
BENCHMARK_TEMPLATE(BM_MomentumObserverUpdate, double);
BENCHMARK_TEMPLATE(BM_MomentumObserverUpdate, float);

// The friction tracker of a calibrated drive (Eq. 4 amplitudes, qds fixed), friction torque given.
template <typename Scalar>
void BM_FrictionTrackerUpdate(benchmark::State& state) {
  using Tracker =
      dyncal::FrictionTracker<Scalar, 6, dyncal::NonlinearFrictionAmplitudes<dyncal::NonlinearFrictionModel::eq4>>;
  using V = typename Tracker::JointVector;
  auto tracker = std::make_unique<Tracker>();
  tracker->reset(Tracker::ParamVector::Constant(Scalar(0.2)), Scalar(1e3), Scalar(0.99));
  const V zero = V::Zero(), w = V::Ones();
  long i = 0, rejected = 0;
  for (auto _ : state) {
    const V qd = kStates.qd[i & 63].cast<Scalar>(), tau = kStates.qdd[i & 63].cast<Scalar>();
    if (tracker->update(qd, zero, tau, w) != dyncal::UpdateStatus::ok) ++rejected;
    ++i;
  }
  state.counters["rejected"] = static_cast<double>(rejected);
}
BENCHMARK_TEMPLATE(BM_FrictionTrackerUpdate, double);
BENCHMARK_TEMPLATE(BM_FrictionTrackerUpdate, float);

void BM_StreamingLeastSquaresSample(benchmark::State& state) {
  auto ls = std::make_unique<dyncal::StreamingLeastSquares<double, P>>();
  Eigen::Matrix<double, 6, P> K;
  const Vec zero = Vec::Zero();
  Model::regressor(kStates.q[0], kStates.qd[0], kStates.qdd[0], zero, K);
  const Vec tau = Vec::Ones();
  for (auto _ : state) benchmark::DoNotOptimize(ls->update(K, tau));
}
BENCHMARK(BM_StreamingLeastSquaresSample);

}  // namespace

BENCHMARK_MAIN();
