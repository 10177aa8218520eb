// One model vocabulary (issue 21): the effects `dyncal diagnose` adds are `--model` items of
// identify, diagnose and predict. Parsing names what is wrong; on simulated logs with effects the
// declared model lacks, identify with those items recovers their true coefficients; predict gives
// what identify --validate-on gives; and on the real TX40 log the effects a diagnosis report lists,
// fed back with `identify --effects`, lift the wrist as the diagnosis said they would.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"
#include "dyncal_host/identification/pipeline/identify.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/drive_table.hpp"
#include "dyncal_host/model/stacked_data.hpp"
#include "support/dyncal_cli.hpp"
#include "support/simulated_log.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace dyncal::host;
using namespace dyncal::test;

std::filesystem::path temp_dir(const std::string& name);  // below

TEST(ModelSpec, ItemsRoundTripAndNameTheirParameters) {
  const ModelSpec spec =
      parse_model_spec("eq7,rotor_inertia,stribeck:3:0.05,coupling:2-3,position_periodic:1:12,load_friction:2", 3);
  EXPECT_EQ(spec.terms, dyncal::kFrictionEq7 | dyncal::term::rotor_inertia);
  ASSERT_EQ(spec.effects.size(), 4u);
  EXPECT_EQ(spec.effects[1].kind, dyncal::EffectKind::coupling);
  EXPECT_EQ(spec.effects[1].joint, 1);
  EXPECT_EQ(spec.effects[1].joint2, 2);
  EXPECT_EQ(spec.effects[1].sign, -1);
  EXPECT_EQ(spec.effects[0].shape, 0.05);
  EXPECT_EQ(effect_param_names(spec.effects[1]), (std::vector<std::string>{"Fc2-3", "Fv2-3", "Ia2-3"}));
  EXPECT_EQ(effect_param_names(spec.effects[2]), (std::vector<std::string>{"A1_sin", "A1_cos"}));
  const ModelSpec again = parse_model_spec(model_spec_name(spec), 3);
  EXPECT_EQ(again.terms, spec.terms);
  ASSERT_EQ(again.effects.size(), spec.effects.size());
  for (size_t i = 0; i < spec.effects.size(); ++i)
    EXPECT_EQ(effect_item(again.effects[i]), effect_item(spec.effects[i]));
}

// A shape item carries its variable and distinct knots and reads back exactly; its parameters are
// its basis functions 2.. (a shape of tau_model: one fewer, no constant or linear part).
TEST(ModelSpec, ShapeItemsRoundTrip) {
  const ModelSpec spec = parse_model_spec("eq7,shape:2:sgn(qd2)*q1:-1.5/0.25/2,shape:3:tau_model3:-10/0/10/20", 3);
  ASSERT_EQ(spec.effects.size(), 2u);
  EXPECT_EQ(spec.effects[0].knots, (std::vector<double>{-1.5, -1.5, -1.5, -1.5, 0.25, 2, 2, 2, 2}));
  EXPECT_EQ(effect_param_names(spec.effects[0]),
            (std::vector<std::string>{"shape2_sgn_q1_2", "shape2_sgn_q1_3", "shape2_sgn_q1_4", "shape2_sgn_q1_5"}));
  EXPECT_EQ(effect_param_names(spec.effects[1]).size(), 4u);  // 6 B-splines less constant and line
  EXPECT_EQ(parse_model_spec(model_spec_name(spec), 3).effects[1].knots, spec.effects[1].knots);
  EXPECT_EQ(effect_item(parse_model_spec(model_spec_name(spec), 3).effects[0]), effect_item(spec.effects[0]));
  // A penalised shape: its penalty after the knots, read back exactly; refused when negative or not a number.
  const ModelSpec penalised = parse_model_spec("eq7,shape:2:q1:-1.5/0.25/2:0.0021", 3);
  EXPECT_EQ(penalised.effects[0].penalty, 0.0021);
  EXPECT_EQ(penalised.effects[0].knots, spec.effects[0].knots);
  EXPECT_EQ(parse_model_spec(model_spec_name(penalised), 3).effects[0].penalty, 0.0021);
  EXPECT_EQ(spec.effects[0].penalty, 0.0);
  EXPECT_THROW(parse_model_spec("eq7,shape:2:q1:-1.5/0.25/2:-1", 3), InputError);
  EXPECT_THROW(parse_model_spec("eq7,shape:2:q1:-1.5/0.25/2:x", 3), InputError);
}

// A diagnosis that refined the same shape twice (the same variable on the same joint, other knots)
// gives identify one shape on the union of their knots, and says so.
TEST(ModelSpec, ShapeFoundTwiceIsOneOnTheUnionOfKnots) {
  const auto dir = temp_dir("dyncal_shape_twice");
  nlohmann::json report = {{"declared_model", "eq7"}, {"effects", nlohmann::json::array()}};
  report["effects"].push_back(
      {{"kind", "shape"}, {"joints", {2}}, {"variable", "q1"}, {"knots", {-1, -1, -1, -1, 0, 1, 1, 1, 1}}});
  report["effects"].push_back({{"kind", "shape"},
                               {"joints", {2}},
                               {"variable", "q1"},
                               {"knots", {-1.2, -1.2, -1.2, -1.2, -0.5, 0.5, 1, 1, 1, 1}}});
  std::ofstream(dir / "r.json") << report.dump();
  std::vector<std::string> notes;
  const ModelSpec spec = read_diagnosed_effects((dir / "r.json").string(), 3, &notes);
  ASSERT_EQ(spec.effects.size(), 1u);
  EXPECT_EQ(spec.effects[0].knots, (std::vector<double>{-1.2, -1.2, -1.2, -1.2, -0.5, 0, 0.5, 1, 1, 1, 1}));
  ASSERT_EQ(notes.size(), 1u);
  EXPECT_NE(notes[0].find("found twice"), std::string::npos) << notes[0];
  std::filesystem::remove_all(dir);
}

// A coupled motor is a row of the motor-velocity map, not columns: it parses, prints back exactly
// and replaces its motor's row (over robot.json's, and over the identity with friction per joint).
TEST(ModelSpec, CoupledMotorIsARowOfTheMotorMap) {
  const ModelSpec spec = parse_model_spec("eq7,rotor_inertia,coupled_motor:3-2:0.35,coupled_motor:1+2", 3);
  ASSERT_EQ(spec.motors.size(), 2u);
  EXPECT_TRUE(spec.effects.empty());
  EXPECT_EQ(spec.motors[0].motor, 2);
  EXPECT_EQ(spec.motors[0].with, 1);
  EXPECT_EQ(spec.motors[0].ratio, -0.35);
  EXPECT_EQ(spec.motors[1].ratio, 1.0);
  EXPECT_EQ(coupled_motor_item(spec.motors[1]), "coupled_motor:1+2");
  const ModelSpec again = parse_model_spec(model_spec_name(spec), 3);
  ASSERT_EQ(again.motors.size(), 2u);
  EXPECT_EQ(again.motors[0].ratio, -0.35);
  const RobotDescription tx40 = load_robot(default_robots_dir(), "tx40");
  const Eigen::MatrixXd declared = motor_velocity_map(tx40, true, {});
  EXPECT_EQ(declared(5, 4), tx40.transmission(5, 4) / tx40.transmission(5, 5));  // motor 6 on q6 + q5
  EXPECT_TRUE(motor_velocity_map(tx40, false, {}).isIdentity(0.0));
  const Eigen::MatrixXd diagnosed = motor_velocity_map(tx40, false, {{5, 4, 0.9}});
  Eigen::MatrixXd expected = Eigen::MatrixXd::Identity(6, 6);
  expected(5, 4) = 0.9;
  EXPECT_EQ(diagnosed, expected);
  EXPECT_EQ(motor_velocity_map(tx40, true, {{5, 3, -0.5}})(5, 4), 0.0);  // the model's row replaces robot.json's
}

TEST(ModelSpec, BadItemsNameWhatIsWrong) {
  const std::map<std::string, std::string> cases = {
      {"eq7,stribeck:3", "velocity scale"},
      {"eq7,stribeck:1:-1", "velocity scale"},
      {"eq7,stribeck:4:0.1", "is not 1..3"},
      {"eq7,friction:1", "unknown effect"},
      {"eq7,coupling:2+2", "with itself"},
      {"eq7,coupling:2", "coupling:I+J"},
      {"eq7,offset,offset:1", "already gives every joint an offset"},
      {"eq7,position_periodic:1:2,position_periodic:1:2", "the same effect twice"},
      {"eq7,velocity_power:1:3", "takes no shape"},
      {"eq7,nonsense", "unknown model term"},
      {"eq7,coupled_motor:2+2", "with its own joint"},
      {"eq7,coupled_motor:2", "coupled_motor:M+J"},
      {"eq7,coupled_motor:3+4", "coupled_motor:M+J"},
      {"eq7,coupled_motor:3+1:-2", "positive number"},
      {"eq7,coupled_motor:3+1,coupled_motor:3-2", "coupled twice"},
      {"rigid_body,coupled_motor:3+1", "has none"},
      {"eq7,shape:2", "expected shape:J:VARIABLE"},
      {"eq7,shape:2:q9:0/1", "shape variable 'q9'"},
      {"eq7,shape:2:tau_model1:0/1", "reads tau_model2 only"},
      {"eq7,shape:2:sgn(qd1)*t:0/1", "sgn(qd2)*X"},
      {"eq7,shape:2:q1:1/0", "knots must be finite, increasing"},
      {"eq7,shape:2:q1:0/x", "knot 'x' is not a number"},
      {"eq7,shape:2:q1:0/1,shape:2:q1:0/2", "the same effect twice"},
  };
  for (const auto& [model, needle] : cases) {
    SCOPED_TRACE(model);
    try {
      parse_model_spec(model, 3);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  }
}

/// The effects the simulated arm has and its declared (Eq. 7) model lacks: a position ripple of
/// joint 2 (3 cycles per revolution) and a motor turning with q1 - q2 whose Coulomb and viscous
/// friction act on both joints (no rotor inertia: its true Ia is 0).
struct TrueEffects {
  double a_sin, a_cos, fc, fv;
  ExtraTorque torque() const {
    return [*this](const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd&, Eigen::VectorXd& tau) {
      tau[1] += a_sin * std::sin(3 * q[1]) + a_cos * std::cos(3 * q[1]);
      const double v = qd[0] - qd[1], f = fc * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0)) + fv * v;
      tau[0] += f;
      tau[1] -= f;
    };
  }
};

TrueEffects true_effects(const RobotDescription& robot) {
  const double scale = std::min(robot.tau_max[0], robot.tau_max[1]);
  return {0.03 * robot.tau_max[1], -0.02 * robot.tau_max[1], 0.02 * scale, 0.01 * scale / robot.qd_max[0]};
}

/// diagnose with the Eq. 7 model declared and at most `max_effects` steps, its report printed.
DiagnoseResult diagnose_eq7(const RobotDescription& robot, const JointLog& log, int max_effects) {
  DiagnoseOptions o;
  o.identify.terms = dyncal::kFrictionEq7;
  o.max_effects = max_effects;
  const DiagnoseResult r = diagnose(robot, log, o);
  print_diagnose_report(std::cout, r);
  return r;
}

class EffectModel : public ::testing::TestWithParam<const char*> {};

// identify with the effects as --model items recovers each true coefficient within 4 of its
// standard deviations (the autocorrelation-inflated ones identify reports), and its validation RMS
// falls to the noise on every joint, where the declared model alone leaves the effects' torque. The
// same holds for the physically consistent methods (pcls; gd, the survey's search, standing for
// ga and pf, which search the same problem), with every link's pseudo-inertia positive definite.
TEST_P(EffectModel, IdentifyRecoversTheSimulatedEffects) {
  const RobotDescription robot = test_robot(GetParam());
  const TrueEffects truth = true_effects(robot);
  const SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 17, 3, truth.torque());
  IdentifyOptions o;
  o.terms = dyncal::kFrictionEq7;
  const IdentifyResult declared = identify(robot, s.log, o);
  o.effects = parse_model_spec("position_periodic:2:3,coupling:1-2", robot.num_joints).effects;
  for (const char* method : {"wls", "pcls", "gd"}) {
    SCOPED_TRACE(method);
    o.method = method;
    const IdentifyResult r = identify(robot, s.log, o);
    EXPECT_NE(r.model.find("position_periodic:2:3,coupling:1-2"), std::string::npos) << r.model;
    const std::map<std::string, double> expected = {
        {"A2_sin", truth.a_sin}, {"A2_cos", truth.a_cos}, {"Fc1-2", truth.fc}, {"Fv1-2", truth.fv}, {"Ia1-2", 0.0}};
    int found = 0;
    for (const ParamEstimate& p : r.params) {
      const auto it = expected.find(p.name);
      if (it == expected.end()) continue;
      ++found;
      std::printf("%s %s: %s = %.5g (true %.5g, std %.3g, %.2f std)\n", GetParam(), method, p.name.c_str(), p.value,
                  it->second, p.std, (p.value - it->second) / p.std);
      EXPECT_LE(std::abs(p.value - it->second), 4 * p.std) << p.name;
    }
    EXPECT_EQ(found, 5);
    for (int j = 0; j < robot.num_joints; ++j) {
      SCOPED_TRACE("joint " + std::to_string(j + 1));
      std::printf("joint %d: validation RMS %.4g Nm with the effects, %.4g without (noise %.4g)\n", j + 1,
                  r.joints[j].rms, declared.joints[j].rms, s.sigma[j]);
      EXPECT_LT(r.joints[j].rms, 1.2 * s.sigma[j]);
    }
    if (std::string(method) == "wls") {
      EXPECT_TRUE(r.links.empty());
    } else {
      EXPECT_EQ(static_cast<int>(r.links.size()), robot.num_joints);
      for (const LinkInertial& l : r.links) EXPECT_GT(l.min_eigenvalue, 0.0) << "link " << l.link;
    }
  }
  EXPECT_GT(declared.joints[1].rms, 2 * s.sigma[1]);  // the effects matter: without them joint 2 is off
}

/// The last joint's motor also turning with the one before by `ratio` (bevel gears), with Coulomb
/// and viscous friction only (3 % of the last joint's tau_max, 1 % at its top speed) on the last joint
/// and `ratio` times on the one before: its rotor inertia is 0.
ExtraTorque friction_only_motor(const RobotDescription& robot, double ratio) {
  const int n = robot.num_joints, a = n - 2, b = n - 1;
  const double fc = 0.03 * robot.tau_max[b], fv = 0.01 * robot.tau_max[b] / robot.qd_max[b];
  return [=](const Eigen::VectorXd&, const Eigen::VectorXd& qd, const Eigen::VectorXd&, Eigen::VectorXd& tau) {
    const double v = qd[b] + ratio * qd[a], f = fc * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0)) + fv * v;
    tau[b] += f;
    tau[a] += ratio * f;
  };
}

// A coupled motor of a ratio other than 1 (issue 22): the last joint's motor also turns with the
// one before by r = 0.35 (bevel gears), its Coulomb and viscous friction on the last joint and r
// times on the one before. diagnose, told nothing, names a coupling of those two joints first, with
// a 95 % ratio interval that holds the truth (in its pair order, q_a + r' q_b: r' = 1 / 0.35), and
// brings both joints' validation RMS to the noise; no joint ends more than 10 % worse.
TEST_P(EffectModel, DiagnoseFindsACouplingOfAnyRatio) {
  const RobotDescription robot = test_robot(GetParam());
  const int n = robot.num_joints, a = n - 2, b = n - 1;
  const double ratio = 0.35;
  const ExtraTorque coupled = friction_only_motor(robot, ratio);
  const SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 23, 3, coupled);
  const DiagnoseResult r = diagnose_eq7(robot, s.log, DiagnoseOptions{}.max_effects);
  ASSERT_FALSE(r.effects.empty());
  const DiagnosedEffect& e = r.effects[0];
  EXPECT_EQ(e.kind, Effect::coupling);
  EXPECT_EQ(e.joints, (std::vector<int>{a + 1, b + 1}));
  EXPECT_EQ(e.sign, 1.0);
  EXPECT_LE(e.shape_interval.first, 1 / ratio);
  EXPECT_GE(e.shape_interval.second, 1 / ratio);
  std::printf("%s: ratio %.4g, 95 %% %.4g..%.4g (true %.4g)\n", GetParam(), e.shape, e.shape_interval.first,
              e.shape_interval.second, 1 / ratio);
  for (const DiagnoseJoint& j : r.joints) {
    SCOPED_TRACE("joint " + std::to_string(j.joint));
    EXPECT_LE(j.rms_validation_after, 1.1 * j.rms_validation_before);
    if (j.joint == a + 1 || j.joint == b + 1) {
      EXPECT_LT(j.rms_validation_after, 1.2 * s.sigma[j.joint - 1]);
    }
  }
}

// One sign rule for a motor's inertia (issue 43): a coupled motor with friction only (its true rotor
// inertia is 0), on three noise seeds. The free fit of the coupling's inertia comes out negative on
// all three; diagnose holds it >= 0 in the selection (a negative free fit is refitted with the
// inertia at 0, the bounded least-squares optimum), so the coupling is still found first on the right joints with its
// true ratio inside its interval, and no diagnosed effect has a negative inertia or friction. (Refusing such a
// candidate instead, tried at issue 43's first stop, chose a wrong coupled motor on arm3.)
TEST(EffectModelArm3, DiagnosedMotorInertiaIsNeverNegative) {
  const RobotDescription robot = test_robot("arm3");
  const int n = robot.num_joints, a = n - 2, b = n - 1;
  const double ratio = 0.35;
  const ExtraTorque coupled = friction_only_motor(robot, ratio);
  int held = 0;
  for (unsigned seed : {23u, 41u, 43u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, seed, 3, coupled);
    DiagnoseOptions o;
    o.identify.terms = dyncal::kFrictionEq7;
    const DiagnoseResult r = diagnose(robot, s.log, o);
    ASSERT_FALSE(r.effects.empty());
    const DiagnosedEffect& e = r.effects[0];
    EXPECT_EQ(e.kind, Effect::coupling);
    EXPECT_EQ(e.joints, (std::vector<int>{a + 1, b + 1}));
    EXPECT_LE(e.shape_interval.first, 1 / ratio);
    EXPECT_GE(e.shape_interval.second, 1 / ratio);
    for (const DiagnosedEffect& x : r.effects) {
      if (x.kind != Effect::coupling && x.kind != Effect::coupled_motor) continue;
      held += x.inertia_held;
      for (size_t k = 0; k < x.params.size(); ++k) {
        const std::string& name = x.param_names[k];
        std::printf("seed %u: %s %s = %.4g%s\n", seed, effect_name(x.kind), name.c_str(), x.params[k],
                    x.inertia_held ? " (inertia held at 0)" : "");
        EXPECT_GE(x.params[k], 0.0) << name;
      }
    }
  }
  std::printf("inertia held at 0 on %d of 3 logs\n", held);
  EXPECT_GE(held, 1);  // the bound is exercised, not only satisfied by chance
}

// Parsimony (issue 22): a constant offset on arm3's joint 2, which never rests, is asymmetric
// Coulomb friction's special case (1 = 2 [qd > 0] - sgn qd wherever the joint moves): on this log
// both remove the same validation error (98.4 %). The one-parameter offset is chosen, and the report
// names asymmetric friction as indistinguishable. Positions are exact here: with a 20-bit encoder,
// the samples of a reversal inside the standstill band (where the model's Coulomb torque is 0 and
// the simulated one is not) let the asymmetric candidate explain part of that too, and it then wins
// by BIC (-306 against -294) — a real difference on such a log, not a tie.
TEST(EffectModelArm3, DiagnosePrefersTheSmallerOfNestedEffectsAndSaysSo) {
  const RobotDescription robot = test_robot("arm3");
  const double offset = 0.03 * robot.tau_max[1];
  const ExtraTorque extra = [&](const Eigen::VectorXd&, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                Eigen::VectorXd& tau) { tau[1] += offset; };
  const SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 29, 3, extra, 0.0);
  const DiagnoseResult r = diagnose_eq7(robot, s.log, 1);
  ASSERT_EQ(r.effects.size(), 1u);
  EXPECT_EQ(r.effects[0].kind, Effect::offset);
  EXPECT_EQ(r.effects[0].joints, (std::vector<int>{2}));
  EXPECT_NEAR(r.effects[0].params[0], offset, 0.05 * offset);
  bool named = false;
  for (const auto& a : r.effects[0].alternatives) named = named || a.find("asymmetric_friction") == 0;
  EXPECT_TRUE(named) << "asymmetric friction not named as indistinguishable";
}

// Stribeck friction's velocity scale (issue 22): joint 1 given Fs - Fc = 3 % of tau_max with a
// velocity scale of 5 % of its top speed. diagnose names a Stribeck effect on joint 1 first, with
// the velocity scale and Fs - Fc within 10 % of the truth (the scale refined with the joint's own
// Coulomb and viscous columns refitted; scored against the declared model's residual alone it came
// out about 30 % low), and cuts joint 1's validation RMS in excess of the noise by at least half.
// The interval is printed, not asserted: it reflects the noise only.
TEST_P(EffectModel, DiagnoseFindsStribeckFrictionWithItsVelocityScale) {
  const RobotDescription robot = test_robot(GetParam());
  const double dfs = 0.03 * robot.tau_max[0], qds = 0.05 * robot.qd_max[0];
  const ExtraTorque extra = [&](const Eigen::VectorXd&, const Eigen::VectorXd& qd, const Eigen::VectorXd&,
                                Eigen::VectorXd& tau) {
    const double z = qd[0] / qds;
    tau[0] += dfs * (qd[0] > 0 ? 1.0 : (qd[0] < 0 ? -1.0 : 0.0)) * std::exp(-z * z);
  };
  const SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 37, 3, extra);
  const DiagnoseResult r = diagnose_eq7(robot, s.log, 1);
  ASSERT_EQ(r.effects.size(), 1u);
  const DiagnosedEffect& e = r.effects[0];
  EXPECT_EQ(e.kind, Effect::stribeck);
  EXPECT_EQ(e.joints, (std::vector<int>{1}));
  std::printf("%s: qds %.4g, 95 %% %.4g..%.4g (true %.4g); Fs - Fc %.4g (true %.4g)\n", GetParam(), e.shape,
              e.shape_interval.first, e.shape_interval.second, qds, e.params[0], dfs);
  EXPECT_NEAR(e.shape, qds, 0.1 * qds);
  EXPECT_NEAR(e.params[0], dfs, 0.1 * dfs);
  const DiagnoseJoint& j1 = r.joints[0];
  const double excess_before = j1.rms_validation_before - s.sigma[0],
               excess_after = j1.rms_validation_after - s.sigma[0];
  EXPECT_LE(excess_after, 0.5 * excess_before) << j1.rms_validation_before << " -> " << j1.rms_validation_after;
}

INSTANTIATE_TEST_SUITE_P(TestRobots, EffectModel, ::testing::Values("arm3", "cobot7"));

std::filesystem::path temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

// A parameter file with effect terms predicts another log as identify --validate-on does (one
// computation), and a file whose model names an effect of a joint the robot lacks is refused.
TEST(EffectModelCli, ParameterFileWithEffectsPredictsAnotherLog) {
  const RobotDescription robot = test_robot("arm3");
  const TrueEffects truth = true_effects(robot);
  const auto dir = temp_dir("dyncal_effects");
  write_csv_log((dir / "a.csv").string(),
                simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 31, 3, truth.torque()).log);
  const SimulatedLog b = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 32, 4, truth.torque());
  write_csv_log((dir / "b.csv").string(), b.log);
  const std::string robots = std::string(" --robot arm3 --robots-dir ") + dyncal::test::source_dir() + "/tests/robots";
  ASSERT_EQ(run_dyncal("identify" + robots + " --model eq7,position_periodic:2:3,coupling:1-2 --data " +
                       (dir / "a.csv").string() + " --validate-on " + (dir / "b.csv").string() + " --report " +
                       (dir / "rep.json").string() + " --params " + (dir / "p.json").string()),
            0);
  ASSERT_EQ(run_dyncal("predict" + robots + " --data " + (dir / "b.csv").string() + " --params " +
                       (dir / "p.json").string() + " --report " + (dir / "pred.json").string()),
            0);
  const nlohmann::json rep = read_json(dir / "rep.json"), pred = read_json(dir / "pred.json");
  for (int j = 0; j < robot.num_joints; ++j) {
    const double via_predict = pred["joints"][j]["rms_validation"].get<double>();
    EXPECT_DOUBLE_EQ(rep["other_logs"][0]["joints"][j]["rms_validation"].get<double>(), via_predict);
    EXPECT_LT(via_predict, 1.2 * b.sigma[j]) << "joint " << j + 1;
  }
  nlohmann::json bad = read_json(dir / "p.json");
  bad["model"] = "rigid_body,coulomb,viscous,position_periodic:4:3,coupling:1-2";
  std::ofstream(dir / "bad.json") << bad.dump();
  EXPECT_EQ(run_dyncal("predict" + robots + " --data " + (dir / "b.csv").string() + " --params " +
                       (dir / "bad.json").string()),
            2);
  EXPECT_EQ(run_dyncal("identify" + robots + " --model eq7,stribeck:2 --data " + (dir / "a.csv").string()), 2);
  EXPECT_EQ(run_dyncal("identify" + robots + " --method kf --model eq7,offset:1 --data " + (dir / "a.csv").string()),
            2);
  std::filesystem::remove_all(dir);
}

// A shape as a model term (issue 71): identify fits a spline of the neighbour's position that the
// arm has (cable drag: a tanh of q1 on joint 2) and reaches the noise on another log, where the
// declared model alone does not; predict applies it to that log exactly as identify's validation
// did. A shape of tau_model reads the reference model the parameter file keeps: predict equals
// identify's validation with it, and refuses a file without it.
TEST(EffectModelCli, ShapeIsFittedByIdentifyAndAppliedByPredict) {
  const RobotDescription robot = test_robot("arm3");
  const double a = 0.04 * robot.tau_max[1];
  const ExtraTorque drag = [a](const Eigen::VectorXd& q, const Eigen::VectorXd&, const Eigen::VectorXd&,
                               Eigen::VectorXd& tau) { tau[1] += a * std::tanh(q[0] / 0.3); };
  const auto dir = temp_dir("dyncal_shape");
  write_csv_log((dir / "a.csv").string(), simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 31, 3, drag).log);
  const SimulatedLog b = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 32, 4, drag);
  write_csv_log((dir / "b.csv").string(), b.log);
  const std::string robots = std::string(" --robot arm3 --robots-dir ") + dyncal::test::source_dir() + "/tests/robots";
  const auto identify_and_predict = [&](const std::string& model, const std::string& tag) {
    EXPECT_EQ(run_dyncal("identify" + robots + " --model " + model + " --data " + (dir / "a.csv").string() +
                         " --validate-on " + (dir / "b.csv").string() + " --report " +
                         (dir / (tag + ".rep.json")).string() + " --params " + (dir / (tag + ".p.json")).string()),
              0);
    EXPECT_EQ(run_dyncal("predict" + robots + " --data " + (dir / "b.csv").string() + " --params " +
                         (dir / (tag + ".p.json")).string() + " --report " + (dir / (tag + ".pred.json")).string()),
              0);
    const nlohmann::json rep = read_json(dir / (tag + ".rep.json")), pred = read_json(dir / (tag + ".pred.json"));
    for (int j = 0; j < robot.num_joints; ++j)
      EXPECT_DOUBLE_EQ(rep["other_logs"][0]["joints"][j]["rms_validation"].get<double>(),
                       pred["joints"][j]["rms_validation"].get<double>())
          << tag << " joint " << j + 1;
    return pred["joints"][1]["rms_validation"].get<double>();
  };
  const double declared = identify_and_predict("eq7", "declared");
  const double shaped = identify_and_predict("eq7,shape:2:q1:-3/-1.5/-0.6/-0.2/0.2/0.6/1.5/3", "shape");
  EXPECT_GT(declared, 2.0 * b.sigma[1]);
  EXPECT_LT(shaped, 1.2 * b.sigma[1]);
  identify_and_predict("eq7,shape:2:tau_model2:-40/-10/0/10/40", "tau_model");
  nlohmann::json bare = read_json(dir / "tau_model.p.json");
  ASSERT_TRUE(bare.contains("tau_model_reference"));
  bare.erase("tau_model_reference");
  std::ofstream(dir / "bare.json") << bare.dump();
  EXPECT_EQ(run_dyncal("predict" + robots + " --data " + (dir / "b.csv").string() + " --params " +
                       (dir / "bare.json").string()),
            2);
  std::filesystem::remove_all(dir);
}

// A shape diagnose finds carries its pointwise 95 % band (the jackknife over the folds): on arm3 with
// cable drag on joint 2 (a tanh of q1 that no table kind names), at the simulation's noise and at
// four times it, the shape found is of q1 and the true drag, centred as the curve is (shape_curve),
// lies inside the band at >= 90 % of the curve's points, while the band stays narrow against the
// drag (median half-width under a quarter of its span). The trajectory is one on which diagnose
// names q1 at both noise levels: on others (seeds 3, 4, 5 and 7 of the designed excitation) it took
// q3, qd1 or a sign product for some of them, which explained the joint as well on that log.
TEST(EffectModelCli, DiagnosedShapeCarriesABandThatHoldsTheTruth) {
  constexpr unsigned kTrajectory = 6;
  const RobotDescription robot = test_robot("arm3");
  const double a = 0.04 * robot.tau_max[1], width = 0.3;
  const ExtraTorque drag = [a, width](const Eigen::VectorXd& q, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                      Eigen::VectorXd& tau) { tau[1] += a * std::tanh(q[0] / width); };
  const auto dir = temp_dir("dyncal_shape_band");
  const std::string robots = std::string(" --robot arm3 --robots-dir ") + dyncal::test::source_dir() + "/tests/robots";
  double median_half[2] = {0, 0};
  for (int level = 0; level < 2; ++level) {
    SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 31, kTrajectory, drag);
    if (level == 1) {
      // Four times the noise: tau_a + k (tau_a - tau_b), two logs of the same motion that differ in
      // their noise only, has noise of std sqrt((1 + k)^2 + k^2) = 4.02 times theirs at k = 2.3.
      const SimulatedLog b = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 32, kTrajectory, drag);
      s.log.tau += 2.3 * (s.log.tau - b.log.tau);
    }
    const std::string log = (dir / ("l" + std::to_string(level) + ".csv")).string();
    write_csv_log(log, s.log);
    const std::string report = (dir / ("d" + std::to_string(level) + ".json")).string();
    ASSERT_EQ(run_dyncal("diagnose" + robots + " --model eq7 --data " + log + " --report " + report), 0);
    const nlohmann::json d = read_json(report);
    const nlohmann::json* shape = nullptr;
    for (const auto& e : d["effects"])
      if (e["kind"] == "shape" && e["joints"][0] == 2) shape = &e;
    ASSERT_NE(shape, nullptr) << d["effects"].dump();
    EXPECT_EQ((*shape)["variable"], "q1");
    const auto x = (*shape)["curve"]["x"].get<std::vector<double>>();
    const auto y = (*shape)["curve"]["y"].get<std::vector<double>>();
    const auto lo = (*shape)["curve"]["y_lo"].get<std::vector<double>>();
    const auto hi = (*shape)["curve"]["y_hi"].get<std::vector<double>>();
    ASSERT_EQ(lo.size(), x.size());
    ASSERT_EQ(hi.size(), x.size());
    std::vector<double> truth(x.size()), half(x.size());
    double mean = 0;
    for (size_t k = 0; k < x.size(); ++k)
      mean += (truth[k] = a * std::tanh(x[k] / width)) / static_cast<double>(x.size());
    int inside = 0;
    for (size_t k = 0; k < x.size(); ++k) {
      truth[k] -= mean;
      half[k] = 0.5 * (hi[k] - lo[k]);
      EXPECT_LE(lo[k], y[k]);
      EXPECT_GE(hi[k], y[k]);
      inside += std::abs(truth[k] - y[k]) <= half[k];
    }
    std::nth_element(half.begin(), half.begin() + static_cast<std::ptrdiff_t>(half.size() / 2), half.end());
    median_half[level] = half[half.size() / 2];
    const double span = *std::max_element(truth.begin(), truth.end()) - *std::min_element(truth.begin(), truth.end());
    std::printf("noise x%d: truth inside the band at %d of %zu points, median half-width %.4g Nm, drag span %.4g Nm\n",
                level ? 4 : 1, inside, x.size(), median_half[level], span);
    EXPECT_GE(inside, static_cast<int>(0.9 * static_cast<double>(x.size())));
    EXPECT_LT(median_half[level], 0.25 * span);
  }
  std::filesystem::remove_all(dir);
}

// The noise floor (docs/diagnose.md "How much is left") is what a model lacking nothing leaves: on a
// log simulated with the declared model's own terms and white torque noise, the declared model's
// validation RMS on every joint lies inside the floor's 95 % interval, and that interval is narrow
// (within -+15 % of the floor; seeds 41-46 checked). With an offset the model lacks, the offset
// added removes the whole excess: the interval of the share it removed holds 1.
TEST(EffectModelCli, NoiseFloorHoldsACompleteModelsValidationError) {
  const RobotDescription robot = test_robot("arm3");
  const auto dir = temp_dir("dyncal_noise_floor");
  const SimulatedLog s = simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 41, 6, {});
  const std::string log = (dir / "l.csv").string(), report = (dir / "d.json").string();
  write_csv_log(log, s.log);
  ASSERT_EQ(run_dyncal(std::string("diagnose --robot arm3 --robots-dir ") + dyncal::test::source_dir() +
                       "/tests/robots --model eq7 --data " + log + " --report " + report),
            0);
  const nlohmann::json d = read_json(report);
  EXPECT_TRUE(d["effects"].empty()) << d["effects"].dump();
  for (const auto& j : d["joints"]) {
    const double rms = j["rms_validation_before"].get<double>(), floor = j["rms_noise_floor"].get<double>();
    const auto interval = j["rms_noise_floor_interval"].get<std::vector<double>>();
    std::printf("joint %d: validation RMS %.5g, noise floor %.5g (%.5g..%.5g)\n", j["joint"].get<int>(), rms, floor,
                interval[0], interval[1]);
    EXPECT_GE(rms, interval[0]) << j.dump();
    EXPECT_LE(rms, interval[1]) << j.dump();
    EXPECT_GT(interval[0], 0.85 * floor);
    EXPECT_LT(interval[1], 1.15 * floor);
  }
  // An offset on joint 2 that the declared model lacks: the offset the diagnosis adds removes all of
  // its excess, so the share's interval holds 1 and joint 2's share left holds 0.
  const double offset = 0.03 * robot.tau_max[1];
  const ExtraTorque shift = [offset](const Eigen::VectorXd&, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                     Eigen::VectorXd& tau) { tau[1] += offset; };
  write_csv_log(log, simulate(robot, uniform_times(500.0, 40.0), MotionClock{}, 41, 6, shift).log);
  ASSERT_EQ(run_dyncal(std::string("diagnose --robot arm3 --robots-dir ") + dyncal::test::source_dir() +
                       "/tests/robots --model eq7 --data " + log + " --report " + report),
            0);
  const nlohmann::json e = read_json(report);
  ASSERT_EQ(e["effects"].size(), 1u) << e["effects"].dump();
  EXPECT_EQ(e["effects"][0]["kind"], "offset");
  const auto share = e["effects"][0]["excess_share_interval"].get<std::vector<double>>();
  const auto left = e["joints"][1]["excess_left_interval"].get<std::vector<double>>();
  std::printf("offset: excess share %.4g (%.4g..%.4g), joint 2's left %.4g (%.4g..%.4g)\n",
              e["effects"][0]["excess_share"].get<double>(), share[0], share[1],
              e["joints"][1]["excess_left"].get<double>(), left[0], left[1]);
  EXPECT_LE(share[0], e["effects"][0]["excess_share"].get<double>());
  EXPECT_GE(share[1], 1.0);
  EXPECT_LE(left[0], 0.0);
  std::filesystem::remove_all(dir);
}

// A penalised shape in identify (the roughness rows in its least squares, model_effects.hpp's
// penalty): on arm3 with cable drag a tanh(q1 / 0.3) on joint 2, a 20-knot spline of q1 fitted with
// penalties rising by decades has a curve whose roughness (the integral of f''^2, from its second
// differences) falls at every step, and under the largest it is a line (its roughness under 1e-4 of
// the unpenalised fit's). Without the rows every fit would be the same. The curve's band (identify's
// folds) holds the true drag under the two lightest penalties.
TEST(EffectModelCli, PenalisedShapeSmoothsAsItsPenaltyRises) {
  const RobotDescription robot = test_robot("arm3");
  const double a = 0.04 * robot.tau_max[1], width = 0.3;
  const ExtraTorque drag = [a, width](const Eigen::VectorXd& q, const Eigen::VectorXd&, const Eigen::VectorXd&,
                                      Eigen::VectorXd& tau) { tau[1] += a * std::tanh(q[0] / width); };
  const auto dir = temp_dir("dyncal_shape_penalty");
  const SimulatedLog s = simulate(robot, uniform_times(500.0, 30.0), MotionClock{}, 31, 6, drag);
  const std::string log = (dir / "l.csv").string();
  write_csv_log(log, s.log);
  const double lo = s.log.q.col(0).minCoeff(), hi = s.log.q.col(0).maxCoeff();
  std::string knots;
  for (int k = 0; k <= 21; ++k) knots += (k ? "/" : "") + std::to_string(lo + (hi - lo) * k / 21.0);
  const std::string run = std::string("identify --robot arm3 --robots-dir ") + dyncal::test::source_dir() +
                          "/tests/robots --data " + log + " --model eq7,shape:2:q1:" + knots;
  std::vector<double> roughness;
  for (const char* penalty : {"", ":1e-7", ":1e-4", ":10"}) {
    const std::string report = (dir / "i.json").string();
    ASSERT_EQ(run_dyncal(run + penalty + " --report " + report), 0) << penalty;
    const nlohmann::json r = read_json(report);
    ASSERT_EQ(r["shapes"].size(), 1u);
    const auto x = r["shapes"][0]["curve"]["x"].get<std::vector<double>>();
    const auto y = r["shapes"][0]["curve"]["y"].get<std::vector<double>>();
    ASSERT_GE(x.size(), 3u);
    const double h = x[1] - x[0];
    double integral = 0;
    for (size_t k = 1; k + 1 < y.size(); ++k) integral += std::pow((y[k + 1] - 2 * y[k] + y[k - 1]) / (h * h), 2) * h;
    // The band (the folds' fits' jackknife) holds the true drag, centred as the curve is, where the
    // spline can follow it (the two lightest penalties).
    const auto y_lo = r["shapes"][0]["curve"]["y_lo"].get<std::vector<double>>();
    const auto y_hi = r["shapes"][0]["curve"]["y_hi"].get<std::vector<double>>();
    ASSERT_EQ(y_lo.size(), y.size());
    ASSERT_EQ(y_hi.size(), y.size());
    std::vector<double> truth(x.size());
    double mean = 0;
    for (size_t k = 0; k < x.size(); ++k)
      mean += (truth[k] = a * std::tanh(x[k] / width)) / static_cast<double>(x.size());
    int inside = 0;
    for (size_t k = 0; k < x.size(); ++k) inside += y_lo[k] <= truth[k] - mean && truth[k] - mean <= y_hi[k];
    std::printf("penalty '%s': roughness %.6g, truth inside the band at %d of %zu points\n", penalty, integral, inside,
                x.size());
    if (roughness.size() < 2) EXPECT_GE(inside, static_cast<int>(0.9 * static_cast<double>(x.size()))) << penalty;
    roughness.push_back(integral);
  }
  for (size_t k = 1; k < roughness.size(); ++k) EXPECT_LT(roughness[k], roughness[k - 1]) << k;
  EXPECT_LT(roughness.back(), 1e-4 * roughness.front());
  std::filesystem::remove_all(dir);
}

// Closing the loop on the real TX40 log: diagnose (the coupling robot.json declares left out, Eq. 7)
// writes its report; identify --effects with that report fits the same model and reaches, on
// cross-validation, what the diagnosis reported after its effects: joints 5 and 6 at R^2 >= 0.9
// (from below 0.7 on joint 5), every joint's R^2 within 0.02 of the diagnosis's.
TEST(EffectModelCli, Tx40DiagnosisReportFedBackToIdentify) {
  const auto dir = temp_dir("dyncal_tx40_effects");
  const std::string data = std::string(" --format tx40 --data ") + dyncal::test::tx40_data() + " --friction-per-joint";
  ASSERT_EQ(run_dyncal("diagnose" + data + " --model eq7 --max-effects 3 --report " + (dir / "d.json").string()), 0);
  ASSERT_EQ(run_dyncal("identify" + data + " --model eq7 --effects " + (dir / "d.json").string() + " --report " +
                       (dir / "i.json").string()),
            0);
  const nlohmann::json d = read_json(dir / "d.json"), r = read_json(dir / "i.json");
  ASSERT_FALSE(d["effects"].empty());
  std::printf("model: %s\n", r["model"].get<std::string>().c_str());
  for (int j = 0; j < 6; ++j) {
    const double via_identify = r["joints"][j]["r2_validation"].get<double>();
    const double via_diagnose = d["joints"][j]["r2_validation_after"].get<double>();
    std::printf("joint %d: R2 identify --effects %.4f, diagnose after %.4f, before %.4f\n", j + 1, via_identify,
                via_diagnose, d["joints"][j]["r2_validation_before"].get<double>());
    EXPECT_NEAR(via_identify, via_diagnose, 0.02) << "joint " << j + 1;
  }
  EXPECT_LT(d["joints"][4]["r2_validation_before"].get<double>(), 0.7);
  EXPECT_GE(r["joints"][4]["r2_validation"].get<double>(), 0.9);
  EXPECT_GE(r["joints"][5]["r2_validation"].get<double>(), 0.9);
  // Before and after: the note's "without" is what identify gives without the effect terms (its own
  // run, with the coupled motor the diagnosis found), its "with" the report's; a joint they make
  // worse is named.
  std::string motors;
  for (const auto& e : d["effects"])
    if (e["kind"] == "coupled_motor") motors += "," + e["item"].get<std::string>();
  ASSERT_EQ(run_dyncal("identify" + data + " --model eq7" + motors + " --report " + (dir / "plain.json").string()), 0);
  const nlohmann::json plain = read_json(dir / "plain.json");
  std::string note;
  for (const auto& n : r["notes"])
    if (n.get<std::string>().rfind("effects: validation RMS per joint without -> with them", 0) == 0) note = n;
  ASSERT_FALSE(note.empty());
  for (int j = 0; j < 6; ++j) {
    const std::string key = " " + std::to_string(j + 1) + ": ";
    const size_t at = note.find(key);
    ASSERT_NE(at, std::string::npos) << note;
    double without = 0, with = 0;
    ASSERT_EQ(std::sscanf(note.c_str() + at + key.size(), "%lf -> %lf", &without, &with), 2) << note;
    const double plain_rms = plain["joints"][j]["rms_validation"].get<double>();
    const double effects_rms = r["joints"][j]["rms_validation"].get<double>();
    EXPECT_NEAR(without, plain_rms, 1e-3 * plain_rms) << "joint " << j + 1;
    EXPECT_NEAR(with, effects_rms, 1e-3 * effects_rms) << "joint " << j + 1;
    bool named = false;
    for (const auto& n : r["notes"]) {
      const std::string text = n.get<std::string>();
      named = named || (text.rfind("effects: the validation RMS rises", 0) == 0 &&
                        text.find(" " + std::to_string(j + 1) + " (") != std::string::npos);
    }
    EXPECT_EQ(named, effects_rms > plain_rms) << "joint " << j + 1;
  }
  std::filesystem::remove_all(dir);
}

// The TX40's coupled wrist in a drive table: identify fits motor 6's friction and rotor inertia at
// the motor's velocity q6 + r q5 (robot.json's transmission, r = 1, or a coupled motor of the model,
// as diagnose finds it); drive_table_content turns them into a coupling term of the table. Applied as
// identification applies any term (lib/ effect_columns at the log's rate, filtered in parallel),
// the table's per-joint values plus that term must give the torque identify's motor model gives, up
// to the one difference of the two paths: the motor's viscous term takes the filtered velocity's
// sign in the motor model and the unfiltered one in an effect term, which differs only within a
// filter period of a reversal. A table whose coupling ratio has the wrong sign (a conversion error)
// must be far off: the check can fail.
void expect_table_gives_identifys_torque(const IdentifyOptions& o, double ratio) {
  const RobotDescription robot = load_robot(default_robots_dir(), "tx40");
  const JointLog log = read_tx40_log(dyncal::test::tx40_data(), robot.transmission, robot.joint_offsets);
  const IdentifyResult r = identify(robot, log, o);
  const ParameterSet p = parameter_set(r);
  const DriveTableContent table = drive_table_content(p, robot);
  ASSERT_EQ(table.effects.size(), 1u);
  const dyncal::EffectTerm& term = table.effects[0];
  EXPECT_EQ(term.kind, dyncal::EffectKind::coupling);
  EXPECT_EQ(term.joint, 5);
  EXPECT_EQ(term.joint2, 4);
  EXPECT_NEAR(term.sign * term.shape, ratio, 1e-6);
  for (const char* name : {"Fc6", "Fv6", "Ia6"}) {  // motor 6's own terms are the coupling term's
    const auto it = std::find(p.names.begin(), p.names.end(), name);
    ASSERT_NE(it, p.names.end()) << name;
    EXPECT_EQ(table.values[static_cast<size_t>(it - p.names.begin())], 0.0) << name;
  }
  const Eigen::VectorXd tau_host = prepare_stacked(robot, log, o).W * p.values;
  const Eigen::VectorXd values = Eigen::Map<const Eigen::VectorXd>(table.values.data(), table.values.size());
  auto table_torque = [&](int sign) {
    IdentifyOptions per_joint = o;
    per_joint.friction_per_joint = true;
    per_joint.motors.clear();
    per_joint.effects = {ModelEffect{term.kind, term.joint, term.joint2, sign, term.shape, {}, {}}};
    const StackedData d = prepare_stacked(robot, log, per_joint);
    const Eigen::Vector3d c(term.c[0], term.c[1], term.c[2]);
    return Eigen::VectorXd(d.W * values + d.E * c);
  };
  const Eigen::VectorXd tau_table = table_torque(term.sign), tau_wrong = table_torque(-term.sign);
  const Eigen::Index S = tau_host.size() / 6;
  for (int j = 4; j < 6; ++j) {
    double right = 0, wrong = 0;
    for (Eigen::Index s = 0; s < S; ++s) {
      right += std::pow(tau_table[s * 6 + j] - tau_host[s * 6 + j], 2);
      wrong += std::pow(tau_wrong[s * 6 + j] - tau_host[s * 6 + j], 2);
    }
    right = std::sqrt(right / static_cast<double>(S));
    wrong = std::sqrt(wrong / static_cast<double>(S));
    std::printf("joint %d: table vs identify's motor model RMS %.4g Nm (wrong ratio sign %.4g), validation RMS %.4g\n",
                j + 1, right, wrong, r.joints[j].rms);
    EXPECT_LT(right, 0.05 * r.joints[j].rms);
    EXPECT_GT(wrong, r.joints[j].rms);
  }
}

TEST(DriveTable, CoupledMotorTermGivesIdentifysTorque) {
  IdentifyOptions o;  // identify's defaults: wls, eq7 + rotor inertia + offset, friction per motor
  o.terms = parse_model("eq7,rotor_inertia,offset");
  expect_table_gives_identifys_torque(o, 1.0);
}

TEST(DriveTable, DiagnosedCoupledMotorTermGivesIdentifysTorque) {
  IdentifyOptions o;  // robot.json's coupling left out, the model's coupled motor (diagnose's ratio) in
  const ModelSpec spec = parse_model_spec("eq7,rotor_inertia,offset,coupled_motor:6+5:0.921", 6);
  o.terms = spec.terms;
  o.motors = spec.motors;
  o.friction_per_joint = true;
  expect_table_gives_identifys_torque(o, 0.921);
}

}  // namespace
