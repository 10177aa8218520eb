// The host half of the firmware replay check: the same replay code (port/replay/replay.hpp) run in
// double over the committed drive samples must reproduce the reference estimates committed with
// them (which the Cortex-M images compare their float / double runs against), and the replay must
// make sense: the EKF with Eq. 4 friction fits the Stribeck data better than the linear Eq. 7 KF,
// and the friction tracker on the drive's own rigid-body parameters better than either.
#include <gtest/gtest.h>

#include <memory>

#include "er20_replay_data.hpp"
#include "replay.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace firmware_replay_suite {

using dyncal::replay::Updater;
namespace data = dyncal::replay::data;

template <Updater U>
void replay_matches_reference(const double* reference, double& residual, int& rejected) {
  auto est = std::make_unique<dyncal::replay::Estimator<double, U>>();
  if constexpr (U == Updater::payload) est->set_arm(data::kReferenceKf);
  auto diff = std::make_unique<dyncal::CausalDifferentiator<double, 6>>();
  ASSERT_EQ(est->reset(), dyncal::UpdateStatus::ok);
  const auto c =
      dyncal::replay::run(*est, *diff, data::kSamples, data::kCount, data::kSamplePeriod, data::kSigma, [](int) {});
  EXPECT_GT(c.accepted, data::kCount * 9 / 10);
  double difference = 0;
  dyncal::replay::compare(*est, reference, *diff, data::kSamples, data::kCount, data::kSamplePeriod, difference,
                          residual);
  // Same code, same data, double on both sides: only the compilers' rounding differs.
  EXPECT_LT(difference, 1e-8) << dyncal::replay::name(U);
  rejected = c.rejected;
}

TEST(FirmwareReplay, HostDoubleRunReproducesTheCommittedReference) {
  double r_kf = 0, r_rls = 0, r_ekf = 0, r_friction = 0;
  int x_kf = 0, x_rls = 0, x_ekf = 0, x_friction = 0;
  replay_matches_reference<Updater::kf>(data::kReferenceKf, r_kf, x_kf);
  replay_matches_reference<Updater::rls>(data::kReferenceRls, r_rls, x_rls);
  replay_matches_reference<Updater::ekf>(data::kReferenceEkf, r_ekf, x_ekf);
  replay_matches_reference<Updater::friction>(data::kReferenceFriction, r_friction, x_friction);
  double r_payload = 0;
  int x_payload = 0;
  replay_matches_reference<Updater::payload>(data::kReferencePayload, r_payload, x_payload);
  // The payload's columns on top of the KF's arm model can only reduce its residual (least squares).
  EXPECT_LE(r_payload, r_kf * (1 + 1e-9));
  std::cout << "relative residual KF " << r_kf << " RLS " << r_rls << " EKF " << r_ekf << " friction tracker "
            << r_friction << "; rejected " << x_kf << " " << x_rls << " " << x_ekf << " " << x_friction << "\n";
  EXPECT_LT(r_ekf, r_kf);
  EXPECT_LT(r_friction, r_ekf);
  EXPECT_LT(r_kf, 0.1);
}

}  // namespace firmware_replay_suite
}  // namespace
