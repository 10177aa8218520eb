// The default fit's prior (parameter_prior.hpp, issue 68): on simulated logs of an arm whose
// robot.json inertials (the CAD prior) are off its truth by up to 30 % and whose log leaves many
// parameters undetermined (a short, slow log with the last joint held still), the default WLS fit is
// the MAP estimate: its cross-validated RMS is that of a fit that keeps every parameter (lib/'s
// Kalman filter with a vague start, the reference the issue measured), no parameter a prior covers is
// held at 0, and the posterior intervals of those the log does not determine contain the truth.
// With --prior-std 0 the old rule (held at 0) is back and says why.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "dyncal_host/identification/methods/identifiability.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "support/simulated_log.hpp"

namespace {

using namespace dyncal::host;
using dyncal::test::MotionClock;
using dyncal::test::test_robot;
using dyncal::test::uniform_times;

struct ArmOffItsCad {
  dyncal::test::SimulatedLog sim;
  Eigen::VectorXd truth_base;  ///< the simulated arm's base parameters
};

/// cobot7 whose every standard parameter is its robot.json value times a factor uniform in
/// [0.7, 1.3] (seeded), logged 24 s at 200 Hz at half the designed speed with joint 7 held still.
ArmOffItsCad arm_off_its_cad(const RobotDescription& robot, unsigned seed) {
  const CompiledRobot& c = compiled_robot_for(robot);
  const Eigen::VectorXd nominal = Eigen::Map<const Eigen::VectorXd>(c.nominal_standard.data(), c.num_standard);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> factor(-0.3, 0.3);
  Eigen::VectorXd delta(nominal.size());
  for (Eigen::Index i = 0; i < delta.size(); ++i) delta[i] = factor(rng) * nominal[i];
  const dyncal::test::ExtraTorque off = [&c, delta](const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                                    const Eigen::VectorXd& qdd, Eigen::VectorXd& tau) {
    tau += c.inverse_dynamics(q, qd, qdd, delta);  // linear in the parameters
  };
  MotionClock slow;
  slow.rate = 0.5;
  ArmOffItsCad out{dyncal::test::simulate(robot, uniform_times(200.0, 24.0), slow, seed, 3, off,
                                          dyncal::test::kEncoderStep, {robot.num_joints - 1}),
                   c.standard_to_base(nominal + delta)};
  return out;
}

IdentifyOptions options(const char* method, double prior_std = 0.5) {
  IdentifyOptions o;
  o.method = method;
  o.terms = dyncal::kFrictionEq7;
  o.prior_std = prior_std;
  return o;
}

TEST(ParameterPrior, TheDefaultFitTakesThePriorWhereTheLogIsSilentAndValidatesAsAKeepAllFit) {
  const RobotDescription robot = test_robot("cobot7");
  const int B = compiled_robot_for(robot).num_base;
  for (const unsigned seed : {1u, 2u}) {
    SCOPED_TRACE(seed);
    const ArmOffItsCad arm = arm_off_its_cad(robot, seed);
    const IdentifyResult map = identify(robot, arm.sim.log, options("wls"));
    const IdentifyResult keep_all = identify(robot, arm.sim.log, options("kf"));
    const IdentifyResult at_zero = identify(robot, arm.sim.log, options("wls", 0.0));
    std::printf("seed %u, CV RMS [Nm] per joint: MAP / keep-all (KF) / held at 0\n", seed);
    for (size_t j = 0; j < map.joints.size(); ++j) {
      std::printf("  joint %zu: %.4g / %.4g / %.4g\n", j + 1, map.joints[j].rms, keep_all.joints[j].rms,
                  at_zero.joints[j].rms);
      EXPECT_LE(map.joints[j].rms, 1.01 * keep_all.joints[j].rms) << "joint " << j + 1;
    }
    // Every base parameter the log does not determine comes from the prior, with its posterior std
    // and data share, and its 95 % interval holds the simulated arm's value (most of them: 95 %
    // intervals of ~20 parameters; at least 80 % is a check that cannot pass by luck at 50 %).
    int undetermined = 0, covered = 0;
    for (int i = 0; i < B; ++i) {
      const ParamEstimate& p = map.params[static_cast<size_t>(i)];
      if (p.verdict != Verdict::not_determined) continue;
      SCOPED_TRACE(p.name);
      ++undetermined;
      EXPECT_EQ(p.basis, "prior");
      ASSERT_TRUE(std::isfinite(p.std));
      EXPECT_GT(p.std, 0.0);
      EXPECT_GE(p.data_share, 0.0);
      EXPECT_LE(p.data_share, 1.0);
      covered += std::abs(p.value - arm.truth_base[i]) <= kVerdictZ * p.std;
    }
    std::printf("  %d base parameters from the prior, %d of them with the truth in their 95 %% interval\n",
                undetermined, covered);
    EXPECT_GE(undetermined, 5);  // the generator does leave the log silent on some
    EXPECT_GE(covered, (8 * undetermined + 9) / 10);
    // Joint 7's friction has no prior: held at 0 and named.
    bool named = false;
    for (const auto& n : map.notes) named = named || n.find("without a prior") != std::string::npos;
    EXPECT_TRUE(named);
    // --prior-std 0: the undetermined base parameters are held at 0 again, and the note says why.
    int held = 0;
    for (int i = 0; i < B; ++i) held += at_zero.params[static_cast<size_t>(i)].basis == "held at 0";
    EXPECT_GT(held, 0);
    bool why = false;
    for (const auto& n : at_zero.notes) why = why || n.find("no prior: --prior-std 0") != std::string::npos;
    EXPECT_TRUE(why);
  }
}

// robot.json's friction list is the prior of the friction the log does not determine (issue 68:
// an undetermined parameter comes from the robot's data, never from an arbitrary 0): cobot7 told a
// nominal friction 30 % above the simulated arm's, on the log whose joint 7 is held still. Joint
// 7's Fc and Fv come from that prior (basis "prior", data share near 0), their 95 % intervals hold
// the simulated values, and no note names them as held at 0; joint 1's, which the log determines,
// are the data's and closer to the truth than the prior.
TEST(ParameterPrior, RobotJsonFrictionIsThePriorOfFrictionTheLogDoesNotDetermine) {
  RobotDescription robot = test_robot("cobot7");
  const Eigen::VectorXd Fc = 0.02 * robot.tau_max, Fv = (0.01 * robot.tau_max).cwiseQuotient(robot.qd_max);
  robot.friction.assign(static_cast<size_t>(robot.num_joints), NominalFriction{});
  for (int j = 0; j < robot.num_joints; ++j) {
    robot.friction[static_cast<size_t>(j)].Fc = 1.3 * Fc[j];
    robot.friction[static_cast<size_t>(j)].beta = 1.3 * Fv[j];
  }
  const ArmOffItsCad arm = arm_off_its_cad(robot, 1);
  const IdentifyResult r = identify(robot, arm.sim.log, options("wls"));
  auto param = [&](const std::string& name) {
    for (const ParamEstimate& p : r.params)
      if (p.name == name) return p;
    ADD_FAILURE() << "no " << name;
    return ParamEstimate{};
  };
  const int last = robot.num_joints - 1;
  for (const auto& [name, truth] : {std::pair<std::string, double>{"Fc7", Fc[last]}, {"Fv7", Fv[last]}}) {
    SCOPED_TRACE(name);
    const ParamEstimate p = param(name);
    std::printf("%s = %.4g +- %.3g (truth %.4g, prior %.4g), basis %s, data share %.3g\n", name.c_str(), p.value, p.std,
                truth, 1.3 * truth, p.basis.c_str(), p.data_share);
    EXPECT_EQ(p.verdict, Verdict::not_determined);
    EXPECT_EQ(p.basis, "prior");
    ASSERT_TRUE(std::isfinite(p.std));
    EXPECT_LE(std::abs(p.value - truth), kVerdictZ * p.std);
    EXPECT_LT(p.data_share, 0.5);
  }
  for (const auto& n : r.notes) {
    if (n.find("without a prior") == std::string::npos) continue;
    EXPECT_EQ(n.find("Fc7"), std::string::npos) << n;
    EXPECT_EQ(n.find("Fv7"), std::string::npos) << n;
  }
  const ParamEstimate fc1 = param("Fc1");
  std::printf("Fc1 = %.4g +- %.3g (truth %.4g, prior %.4g), data share %.3g\n", fc1.value, fc1.std, Fc[0], 1.3 * Fc[0],
              fc1.data_share);
  EXPECT_NE(fc1.verdict, Verdict::not_determined);
  EXPECT_LT(std::abs(fc1.value - Fc[0]), 0.3 * Fc[0]);
  EXPECT_GT(fc1.data_share, 0.5);
}

}  // namespace
