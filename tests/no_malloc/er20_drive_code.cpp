// test_no_malloc: the er20's generated code (identification regressor, standard regressor, mass
// matrix, inverse dynamics) and what a drive runs per sample and per flash (payload estimator,
// parameter table encode / decode / check, momentum observer, direct residual, centred slope,
// friction uncertainty, contact threshold) allocate nothing.
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <memory>

#include "dyncal/centred_slope.hpp"
#include "dyncal/contact_threshold.hpp"
#include "dyncal/direct_residual.hpp"
#include "dyncal/friction_uncertainty.hpp"
#include "dyncal/momentum_observer.hpp"
#include "dyncal/payload_estimator.hpp"
#include "dyncal/table_check.hpp"
#include "no_malloc/allocation_counter.hpp"
#include "no_malloc/er20_model.hpp"

namespace {

using namespace dyncal::test::no_malloc;  // the er20 model (er20_model.hpp)

template <typename Scalar>
struct Workspace {
  Eigen::Matrix<Scalar, 6, P> K;
  Eigen::Matrix<Scalar, 6, Er20::kNumStandard> Y;
  Eigen::Matrix<Scalar, Er20::kNumStandard, 1> phi_std;
  Eigen::Matrix<Scalar, 6, 6> M;
  dyncal::PayloadEstimator<Er20, Scalar> payload;
  dyncal::MomentumObserver<Er20, Scalar> observer;
  dyncal::DirectResidual<Er20, Scalar> direct;
  dyncal::CentredSlope<Scalar, 6> slope;
  dyncal::FrictionUncertainty<Scalar, 6> uncertainty;
  dyncal::ParameterTable table;
  std::uint8_t table_bytes[dyncal::kTableMaxBytes];
};

template <typename Scalar>
void run_drive_code(Workspace<Scalar>& w) {
  using V = Eigen::Matrix<Scalar, 6, 1>;
  using PV = Eigen::Matrix<Scalar, P, 1>;
  const PV truth = dyncal::test::er20_truth<kTerms>().template cast<Scalar>();
  for (int i = 0; i < Er20::kNumStandard; ++i) w.phi_std[i] = Scalar(dyncal::generated::er20::kNominalStandard[i]);
  using Payload = dyncal::PayloadEstimator<Er20, Scalar>;
  ASSERT_EQ(w.payload.reset(Payload::ParamVector::Constant(Scalar(1e2))), dyncal::UpdateStatus::ok);
  JointVec qd_, q_, qdd_;
  for (int i = 0; i < 300; ++i) {
    dyncal::test::fourier_state(0.01 * i, q_, qd_, qdd_);
    const V q = q_.cast<Scalar>(), qd = qd_.cast<Scalar>(), qdd = qdd_.cast<Scalar>();
    const V zero = V::Zero();
    Model::regressor(q, qd, qdd, zero, w.K);
    Er20::standard_regressor(q, qd, qdd, w.Y);
    Er20::mass_matrix(q, w.phi_std, w.M);
    V tau;
    Er20::inverse_dynamics(q, qd, qdd, w.phi_std, tau);
    tau.noalias() = w.K * truth;
    ASSERT_EQ(w.payload.update(q, qd, qdd, Scalar(0.01) * tau, V::Ones()), dyncal::UpdateStatus::ok);
  }
  // Parameter table: build, encode, decode, check (what a drive does on a flash).
  dyncal::make_table<Model>(truth, w.table);
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(w.table, w.table_bytes, dyncal::kTableMaxBytes, &size), dyncal::TableStatus::ok);
  ASSERT_EQ(dyncal::decode_table(w.table_bytes, size, w.table), dyncal::TableStatus::ok);
  ASSERT_EQ(dyncal::check_table<Model>(w.table), dyncal::TableStatus::ok);
  // The momentum observer on that table and a contact threshold (what a drive does per sample and
  // once per commit).
  ASSERT_EQ(w.observer.configure(w.table, V::Constant(Scalar(100)), Scalar(0.01)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.direct.configure(w.table, V::Constant(Scalar(100)), Scalar(0.01)), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.slope.reset(1, Scalar(0.01), 6), dyncal::UpdateStatus::ok);
  ASSERT_EQ(w.uncertainty.reset(Scalar(100), Scalar(0.01), 6), dyncal::UpdateStatus::ok);
  for (int i = 0; i < 50; ++i) {
    dyncal::test::fourier_state(0.01 * i, q_, qd_, qdd_);
    V sq, sqd, sqdd, stau;
    Eigen::Matrix<int, 6, 1> still = Eigen::Matrix<int, 6, 1>::Zero();
    const auto ss = w.slope.update(q_.cast<Scalar>(), V::Constant(Scalar(i)), sq, sqd, sqdd, stau, still);
    ASSERT_TRUE(ss == dyncal::UpdateStatus::ok || ss == dyncal::UpdateStatus::not_ready);
    V weight;
    ASSERT_EQ(w.uncertainty.update(qd_.cast<Scalar>(), still, weight), dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.observer.update(q_.cast<Scalar>(), qd_.cast<Scalar>(), V::Constant(Scalar(i))),
              dyncal::UpdateStatus::ok);
    ASSERT_EQ(w.direct.update(q_.cast<Scalar>(), qd_.cast<Scalar>(), qd_.cast<Scalar>(), qdd_.cast<Scalar>(),
                              V::Constant(Scalar(i))),
              dyncal::UpdateStatus::ok);
  }
  ASSERT_TRUE(std::isfinite(dyncal::contact_threshold(Scalar(1), Scalar(0.5), Scalar(0.001), 6, Scalar(1e-5))));
}

TEST(NoMalloc, Er20GeneratedCodeAndDriveCodeAllocateNothing) {
  EXPECT_EQ(dyncal::test::allocations_in_double_and_float<Workspace>([](auto& w) { run_drive_code(w); }), 0);
}

}  // namespace
