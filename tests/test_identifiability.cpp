// Which parameters a log determines (identifiability.hpp): the decision on a synthetic least-squares
// problem against batch least squares on the kept columns, and identify on simulated logs of a
// test robot whose trajectory leaves a joint still (its friction and the inertials only it moves
// are then not determined): they are named, held at 0, never printed as free numbers, and --strict
// refuses the log.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cstdio>
#include <random>
#include <sstream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/identifiability.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/reports/identify_report.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "support/simulated_log.hpp"

namespace {

using namespace dyncal::host;
using dyncal::test::MotionClock;
using dyncal::test::test_robot;
using dyncal::test::uniform_times;

bool contains(const std::vector<int>& v, int x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

// Five columns: two well excited, a pair that differ by less than the noise can resolve (one of
// them is undetermined, its effect in the other), and a column of zeros (no information at all).
TEST(DeterminedLeastSquares, DropsWhatTheNoiseHidesAndFitsTheRestAsBatchLeastSquares) {
  const Eigen::Index rows = 2000;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd A(rows, 5);
  for (Eigen::Index r = 0; r < rows; ++r) {
    A(r, 0) = normal(rng), A(r, 1) = normal(rng), A(r, 2) = normal(rng);
    A(r, 3) = A(r, 2) + 1e-4 * normal(rng);
    A(r, 4) = 0.0;
  }
  const Eigen::VectorXd truth = (Eigen::VectorXd(5) << 1.0, -2.0, 0.5, 0.5, 0.0).finished();
  Eigen::VectorXd y = A * truth;
  for (Eigen::Index r = 0; r < rows; ++r) y[r] += 0.1 * normal(rng);
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(A);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(5).triangularView<Eigen::Upper>();
  const Eigen::VectorXd qty = qr.householderQ().transpose() * y;
  const Eigen::VectorXd z = qty.head(5);
  const double rss = qty.tail(rows - 5).squaredNorm();
  const Eigen::VectorXd scale = Eigen::VectorXd::Ones(5);

  const DeterminedFit fit = determined_least_squares(R, z, rss, static_cast<long>(rows), scale);
  ASSERT_EQ(fit.dropped.size(), 2u);
  EXPECT_TRUE(contains(fit.dropped, 4));
  EXPECT_TRUE(contains(fit.dropped, 2) != contains(fit.dropped, 3));
  const int pair_dropped = contains(fit.dropped, 2) ? 2 : 3, pair_kept = 5 - pair_dropped;
  for (size_t d = 0; d < fit.dropped.size(); ++d) {
    if (fit.dropped[d] == 4) {
      EXPECT_TRUE(fit.absorbed_into[d].empty());  // too little excited: no column explains it
    } else {
      ASSERT_FALSE(fit.absorbed_into[d].empty());
      EXPECT_EQ(fit.absorbed_into[d].front(), pair_kept);
    }
  }
  // The kept parameters: batch least squares on their columns, the combination in the kept one.
  const Eigen::MatrixXd Ak = (Eigen::MatrixXd(rows, 3) << A.col(0), A.col(1), A.col(pair_kept)).finished();
  const Eigen::VectorXd ref = Ak.colPivHouseholderQr().solve(y);
  EXPECT_NEAR(fit.phi[0], ref[0], 1e-10);
  EXPECT_NEAR(fit.phi[1], ref[1], 1e-10);
  EXPECT_NEAR(fit.phi[pair_kept], ref[2], 1e-10);
  EXPECT_NEAR(fit.phi[pair_kept], 1.0, 0.05);  // 0.5 + 0.5: the pair's sum
  EXPECT_EQ(fit.phi[pair_dropped], 0.0);
  const double sigma2 = (y - Ak * ref).squaredNorm() / static_cast<double>(rows - 3);
  EXPECT_NEAR(fit.sigma2, sigma2, 1e-12 * sigma2);
  const Eigen::VectorXd gram = (Ak.transpose() * Ak).inverse().diagonal();
  EXPECT_NEAR(fit.stdev[0], std::sqrt(sigma2 * gram[0]), 1e-9);
  EXPECT_TRUE(std::isnan(fit.stdev[pair_dropped]));
  for (int i : {0, 1, pair_kept}) EXPECT_LE(kVerdictZ * fit.stdev[i], scale[i]);
  // The folds refit the same model when told what was dropped.
  const DeterminedFit forced = determined_least_squares(R, z, rss, static_cast<long>(rows), scale, 1.0, &fit.dropped);
  EXPECT_EQ(forced.dropped, fit.dropped);
  EXPECT_LT((forced.phi - fit.phi).norm(), 1e-12);
  // A larger physical scale for the pair: the data then determine each to within it.
  Eigen::VectorXd loose = scale;
  loose[2] = loose[3] = 1e4;
  EXPECT_EQ(determined_least_squares(R, z, rss, static_cast<long>(rows), loose).dropped, std::vector<int>{4});
}

TEST(Verdict, ThresholdsAreTheStatedFractionsOfTheScale) {
  EXPECT_EQ(verdict_of(0.1 / kVerdictZ, 1.0), Verdict::determined);
  EXPECT_EQ(verdict_of(0.2 / kVerdictZ, 1.0), Verdict::poorly_determined);
  EXPECT_EQ(verdict_of(1.0 / kVerdictZ, 1.0), Verdict::poorly_determined);
  EXPECT_EQ(verdict_of(1.01 / kVerdictZ, 1.0), Verdict::not_determined);
  EXPECT_EQ(verdict_of(std::nan(""), 1.0), Verdict::not_determined);
}

IdentifyOptions wls_eq7() {
  IdentifyOptions o;
  o.method = "wls";
  o.terms = dyncal::kFrictionEq7;
  return o;
}

int index_of(const IdentifyResult& r, const std::string& name) {
  for (size_t i = 0; i < r.params.size(); ++i)
    if (r.params[i].name == name) return static_cast<int>(i);
  return -1;
}

// arm3 with its last joint held still: Fc3, Fv3 have no excitation at all, and nothing is printed
// as a free number that its own data do not fix.
TEST(Identifiability, AJointHeldStillLeavesItsParametersNamedAndHeld) {
  const RobotDescription robot = test_robot("arm3");
  const auto still = dyncal::test::simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 5, 3, {},
                                            dyncal::test::kEncoderStep, {2});
  const IdentifyResult r = identify(robot, still.log, wls_eq7());
  for (const char* name : {"Fc3", "Fv3"}) {
    SCOPED_TRACE(name);
    const int i = index_of(r, name);
    ASSERT_GE(i, 0);
    EXPECT_EQ(r.params[static_cast<size_t>(i)].verdict, Verdict::not_determined);
    EXPECT_EQ(r.params[static_cast<size_t>(i)].basis, "held at 0");
    EXPECT_EQ(r.params[static_cast<size_t>(i)].value, 0.0);
  }
  std::string note;
  for (const auto& n : r.notes)
    if (n.rfind("not determined by this log", 0) == 0) note = n;
  std::printf("%s\n", note.c_str());
  EXPECT_NE(note.find("Fc3 (too little excited)"), std::string::npos) << note;
  EXPECT_NE(note.find("Fv3 (too little excited)"), std::string::npos) << note;
  for (const auto& p : r.params) {
    SCOPED_TRACE(p.name);
    ASSERT_GT(p.scale, 0.0);
    if (p.verdict != Verdict::not_determined) {
      EXPECT_LE(kVerdictZ * p.std, p.scale);
    }
  }
  // The text report prints no number for them but 0 and what it rests on.
  std::ostringstream text;
  print_identify_report(text, r);
  std::printf("%s", text.str().c_str());
  EXPECT_NE(text.str().find("not determined (held at 0)"), std::string::npos);
  // Still validated to the noise on the joints that move (the dropped columns are all zero).
  for (int j = 0; j < 2; ++j) EXPECT_LT(r.joints[static_cast<size_t>(j)].rms, 1.15 * still.sigma[j]);

  // The same trajectory with every joint moving determines them.
  const auto moving = dyncal::test::simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 5, 3);
  const IdentifyResult m = identify(robot, moving.log, wls_eq7());
  for (const char* name : {"Fc3", "Fv3"})
    EXPECT_EQ(m.params[static_cast<size_t>(index_of(m, name))].verdict, Verdict::determined) << name;

  // --strict refuses the still log, naming what it does not determine.
  IdentifyOptions strict = wls_eq7();
  strict.strict = true;
  try {
    identify(robot, still.log, strict);
    ADD_FAILURE() << "--strict accepted a log that leaves Fc3 undetermined";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("Fc3"), std::string::npos) << e.what();
  }
}

// The recursive filters and pcls do not drop; their undetermined parameters rest on the filter's
// start and on the prior, and say so.
TEST(Identifiability, KalmanFilterAndPclsNameWhatTheirValuesRestOn) {
  const RobotDescription robot = test_robot("arm3");
  const auto still = dyncal::test::simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 5, 3, {},
                                            dyncal::test::kEncoderStep, {2});
  for (const char* method : {"kf", "pcls"}) {
    SCOPED_TRACE(method);
    IdentifyOptions o = wls_eq7();
    o.method = method;
    const IdentifyResult r = identify(robot, still.log, o);
    const ParamEstimate& fc3 = r.params[static_cast<size_t>(index_of(r, "Fc3"))];
    EXPECT_EQ(fc3.verdict, Verdict::not_determined);
    EXPECT_EQ(fc3.basis, std::string(method) == "kf" ? "start" : "prior");
  }
}

// pcls on a log that leaves inertials undetermined (arm3, joint 3 held): every link mass within a
// factor 1.5 of robot.json's (the prior; the simulated arm's truth), the validation within 5 % of
// WLS per joint, no warning. On a log whose last link is twice as heavy as robot.json says, a
// warning names that link.
TEST(Identifiability, PclsKeepsUndeterminedMassesAtThePriorAndWarnsOfALinkTheDataMove) {
  const RobotDescription robot = test_robot("arm3");
  const auto& c = dyncal::host::compiled_robot_for(robot);
  const auto still = dyncal::test::simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 5, 3, {},
                                            dyncal::test::kEncoderStep, {2});
  IdentifyOptions o = wls_eq7();
  const IdentifyResult wls = identify(robot, still.log, o);
  o.method = "pcls";
  const IdentifyResult pcls = identify(robot, still.log, o);
  ASSERT_EQ(pcls.links.size(), 3u);
  for (size_t l = 0; l < 3; ++l) {
    const double prior = c.nominal_standard[10 * l + 9];
    std::printf("link %zu: mass %.4g kg, prior %.4g kg\n", l + 1, pcls.links[l].mass, prior);
    EXPECT_LT(pcls.links[l].mass, 1.5 * prior);
    EXPECT_GT(pcls.links[l].mass, prior / 1.5);
  }
  for (size_t j = 0; j < 2; ++j) {  // joint 3 does not move: its rows are friction-free gravity only
    std::printf("joint %zu: validation RMS pcls %.4g, wls %.4g Nm\n", j + 1, pcls.joints[j].rms, wls.joints[j].rms);
    EXPECT_LE(pcls.joints[j].rms, 1.05 * wls.joints[j].rms);
  }
  for (const auto& n : pcls.notes) EXPECT_EQ(n.find("warning: pcls moved link"), std::string::npos) << n;

  // The last link twice as heavy (every standard parameter of it doubled: a consistent body).
  Eigen::VectorXd nominal = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  Eigen::VectorXd heavy = nominal;
  heavy.tail(10) *= 2.0;
  const auto extra = [&](const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                         Eigen::VectorXd& tau) {
    tau += c.inverse_dynamics(q, qd, qdd, heavy) - c.inverse_dynamics(q, qd, qdd, nominal);
  };
  const auto loaded = dyncal::test::simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 5, 3, extra);
  const IdentifyResult moved = identify(robot, loaded.log, o);
  bool warned = false;
  for (const auto& n : moved.notes) {
    if (n.find("warning: pcls moved link 3's mass") != std::string::npos) warned = true;
    if (n.find("warning") != std::string::npos) std::printf("%s\n", n.c_str());
  }
  EXPECT_TRUE(warned);
  std::printf("heavier link 3: pcls mass %.4g kg (robot.json %.4g, true %.4g)\n", moved.links[2].mass, nominal[29],
              heavy[29]);
}

}  // namespace
