// Excitation design (dyncal excite): the criterion against an independent SVD, the optimiser
// against its own random start, every limit on a grid ten times finer than the design's, and the
// trajectory file's round trip and refusals.
#include <gtest/gtest.h>

#include <Eigen/SVD>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/identification_model.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/excitation/excitation.hpp"

namespace {

using namespace dyncal::host;
using Vec6 = Eigen::Matrix<double, 6, 1>;

const RobotDescription& er20() {
  static const RobotDescription r = load_robot(default_robots_dir(), "er20");
  return r;
}

TEST(Excite, ConditionNumberEqualsTheSvdOfTheScaledRegressor) {
  ExciteOptions o;
  o.max_evaluations = 1;  // the best random start only
  const ExciteResult r = design_excitation(er20(), o);
  using Model = dyncal::IdentificationModel<dyncal::generated::er20::Robot, dyncal::kFrictionEq7>;
  const int grid = o.grid;
  Eigen::MatrixXd W(6 * grid, Model::kNumParams);
  Model::Regressor<double> K;
  for (int k = 0; k < grid; ++k) {
    Vec6 q, qd, qdd;
    r.trajectory.evaluate(r.trajectory.period() * k / grid, q, qd, qdd);
    Model::regressor(q, qd, qdd, Vec6::Zero().eval(), K);
    W.middleRows(6 * k, 6) = K;
  }
  for (Eigen::Index i = 0; i < W.cols(); ++i) W.col(i).normalize();
  const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(W).singularValues();
  EXPECT_NEAR(r.cond, sv[0] / sv[sv.size() - 1], 1e-6 * r.cond);
}

TEST(Excite, OptimiserLowersCondAndKeepsEveryLimit) {
  for (FrictionModel m : {FrictionModel::eq7, FrictionModel::eq4}) {
    ExciteOptions o;
    o.model = m;
    o.max_evaluations = 1500;
    const ExciteResult r = design_excitation(er20(), o);
    EXPECT_LT(r.cond, 0.8 * r.start_cond);  // at least 20 % better than the best random start
    // limit_use samples 2 000 points per period (the design 200): between the design's points the
    // motion may overshoot its margin slightly, never a limit.
    for (int j = 0; j < 6; ++j) {
      for (double use : {r.position_use[j], r.velocity_use[j], r.acceleration_use[j]}) {
        EXPECT_LE(use, o.margin * 1.02) << "joint " << j + 1;
        EXPECT_GT(use, 0.0);
      }
      // Each joint uses one of its limits to the margin (the scaling is tight).
      EXPECT_NEAR(std::max({r.position_use[j], r.velocity_use[j], r.acceleration_use[j]}), o.margin, 0.02 * o.margin);
    }
  }
}

TEST(Excite, TrajectoryFileRoundTripsAndBadFilesAreRefused) {
  ExciteOptions o;
  o.max_evaluations = 50;
  const ExciteResult r = design_excitation(er20(), o);
  const nlohmann::json j = trajectory_to_json(er20(), r.trajectory);
  const auto back = trajectory_from_json(er20(), j);
  EXPECT_EQ(back.f_f, r.trajectory.f_f);
  EXPECT_EQ(back.harmonics, r.trajectory.harmonics);
  EXPECT_EQ(back.q0, r.trajectory.q0);
  EXPECT_EQ(back.a.leftCols(5), r.trajectory.a.leftCols(5));
  EXPECT_EQ(back.b.leftCols(5), r.trajectory.b.leftCols(5));
  auto refused = [&](nlohmann::json bad, const std::string& needle) {
    try {
      trajectory_from_json(er20(), bad);
      ADD_FAILURE() << "accepted: " << needle;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  nlohmann::json bad = j;
  bad.erase("a");
  refused(bad, "missing 'a'");
  bad = j;
  bad["robot"] = "tx40";
  refused(bad, "for robot 'tx40'");
  bad = j;
  bad["b"][2].erase(0);
  refused(bad, "joint 3 need 5 coefficients");
  bad = j;
  bad["q0"][1] = "x";
  refused(bad, "q0 of joint 2 is not a number");
  bad = j;
  for (auto& v : bad["a"][3]) v = v.get<double>() * 2;  // twice the amplitude: past a limit
  for (auto& v : bad["b"][3]) v = v.get<double>() * 2;
  refused(bad, "joint 4 exceeds");
}

TEST(Excite, RejectsBadOptions) {
  ExciteOptions o;
  o.harmonics = 9;
  EXPECT_THROW(design_excitation(er20(), o), InputError);
  o = ExciteOptions{};
  o.margin = 1.5;
  EXPECT_THROW(design_excitation(er20(), o), InputError);
}

}  // namespace
