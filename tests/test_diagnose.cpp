// dyncal diagnose: on the real TX40 logs it finds the wrist coupling without being told; on
// simulated-drive data it names an undeclared effect on the right joint, and adds nothing when
// there is none.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <random>

#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/spline_basis.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "support/test_paths.hpp"

namespace {

using namespace dyncal::host;

TEST(Diagnose, Tx40FindsTheWristCouplingAndLiftsJoint5) {
  const auto robot = load_robot(default_robots_dir(), "tx40");
  const auto log = read_tx40_log(dyncal::test::tx40_data(), robot.transmission, robot.joint_offsets);
  DiagnoseOptions o;
  o.identify.terms = parse_model("eq7");
  o.identify.friction_per_joint = true;  // the coupling robot.json declares left out: found from the data
  o.max_effects = 3;
  const auto r = diagnose(robot, log, o);
  print_diagnose_report(std::cout, r);
  ASSERT_FALSE(r.effects.empty());
  // The first effect: motor 6 turns with q6 + r q5 in place of joint 6's own motor (the TX40's
  // coupled wrist, r = 1 by its gearing), its friction and inertia shared by joints 5 and 6; r found
  // with a closed interval that holds 1, well inside the searched 1/5..5.
  const DiagnosedEffect& e = r.effects[0];
  EXPECT_EQ(e.kind, Effect::coupled_motor);
  EXPECT_EQ(e.joints, (std::vector<int>{6, 5}));
  EXPECT_GT(e.sign, 0);
  EXPECT_LE(e.shape_interval.first, 1.0);
  EXPECT_GE(e.shape_interval.second, 1.0);
  EXPECT_GT(e.shape_interval.first, 0.5);
  EXPECT_LT(e.shape_interval.second, 2.0);
  std::printf("ratio %.3f, 95 %% %.3f..%.3f\n", e.shape, e.shape_interval.first, e.shape_interval.second);
  EXPECT_LT(r.joints[4].r2_validation_before, 0.7);
  EXPECT_GE(r.joints[4].r2_validation_after, 0.9);
  EXPECT_GE(r.joints[5].r2_validation_after, 0.9);
  // The plots a person looks at: four SVG files per joint, drawn by gnuplot.
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_plots_" + std::to_string(getpid()));
  const auto files = write_diagnose_plots(r, dir.string());
  EXPECT_EQ(files.size(), 24u);
  for (const auto& f : files) {
    ASSERT_TRUE(std::filesystem::exists(f)) << f;
    EXPECT_GT(std::filesystem::file_size(f), 2000u) << f;
  }
  std::filesystem::remove_all(dir);
}

/// A log recorded from the simulated drive in process: `seconds` of the default excitation.
JointLog simulated_log(const Scenario& s, const RobotDescription& robot, double seconds) {
  const std::string table = std::filesystem::temp_directory_path() / ("dyncal_diag_" + std::to_string(getpid()));
  std::filesystem::remove(table);
  SimulatedDrive d(robot, s, table);
  d.trajectory = default_excitation(robot, 0.1, 5, 4, 11, nullptr);
  d.periods = static_cast<int>(std::ceil(seconds * 0.1));
  d.sample_rate_hz = 500;
  d.start();
  std::vector<dyncal::port::DriveSample> samples;
  while (d.state() == dyncal::modbus_map::DriveState::playing) {
    d.step();
    for (const auto& x : d.ring()) samples.push_back(x);
    if (!d.ring().empty()) d.ack(d.ring().back().seq + 1);
  }
  EXPECT_EQ(d.fault(), dyncal::modbus_map::DriveFault::none);
  JointLog log;
  const Eigen::Index S = static_cast<Eigen::Index>(samples.size());
  log.t.resize(S);
  log.q.resize(S, 6);
  log.tau.resize(S, 6);
  for (Eigen::Index k = 0; k < S; ++k) {
    log.t[k] = samples[static_cast<size_t>(k)].seq / 500.0;
    for (int j = 0; j < 6; ++j) {
      log.q(k, j) = samples[static_cast<size_t>(k)].q[j];
      log.tau(k, j) = samples[static_cast<size_t>(k)].tau[j];
    }
  }
  return log;
}

DiagnoseOptions sim_options() {
  DiagnoseOptions o;
  o.identify.terms = parse_model("eq7,rotor_inertia");
  o.identify.min_speed_fraction = 0.02;  // the simulated joints stick at reversals
  o.max_effects = 2;
  return o;
}

TEST(Diagnose, NamesUndeclaredCoggingOnTheRightJoint) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  Scenario s = default_scenario(robot);
  s.effects[1].cogging_amplitude = 15.0;  // Nm, against 10 Nm torque noise
  s.effects[1].cogging_cycles = 12;
  const auto r = diagnose(robot, simulated_log(s, robot, 20), sim_options());
  print_diagnose_report(std::cout, r);
  ASSERT_FALSE(r.effects.empty());
  EXPECT_EQ(r.effects[0].kind, Effect::position_periodic);
  EXPECT_EQ(r.effects[0].joints, (std::vector<int>{2}));
  EXPECT_NE(r.effects[0].explanation.find("12 cycles per revolution"), std::string::npos) << r.effects[0].explanation;
  EXPECT_LE(r.joints[1].rms_validation_after, 0.5 * r.joints[1].rms_validation_before);
}

// One undeclared effect at a time: named first, on the right joint(s), and the affected joint's
// validation RMS drops by at least half... of its model-error part: the measured torque carries
// Table 7 noise that no model removes, so the test compares RMS above the noise floor.
struct EffectCase {
  const char* name;
  std::function<void(Scenario&)> apply;
  const char* kind;
  std::vector<int> joints;
};

class DiagnoseEffect : public ::testing::TestWithParam<int> {};

const std::vector<EffectCase>& effect_cases() {
  static const std::vector<EffectCase> cases = {
      {"stribeck",
       [](Scenario& s) {
         s.friction[2].model = FrictionModel::eq4;
         s.friction[2].Fs = 110;
       },
       "stribeck",
       {3}},
      {"load_friction", [](Scenario& s) { s.effects[1].load_friction = 0.08; }, "load_friction", {2}},
      {"rotor_inertia", [](Scenario& s) { s.effects[3].rotor_inertia = 3.0; }, "rotor_inertia", {4}},
      {"offset", [](Scenario& s) { s.effects[4].offset = 4.0; }, "offset", {5}},
      {"coupling",
       [](Scenario& s) {
         s.couplings.push_back({4, 5, 1.0, 6.0, 4.0});
       },
       "coupling",
       {5, 6}},
      {"drift",
       [](Scenario& s) {
         s.effects[0].viscous_drift = 1.0;
         s.effects[0].drift_time_constant = 8.0;
       },
       "drift",
       {1}},
  };
  return cases;
}

TEST_P(DiagnoseEffect, NamesTheEffectOnTheRightJoint) {
  const EffectCase& c = effect_cases()[static_cast<size_t>(GetParam())];
  const auto robot = load_robot(default_robots_dir(), "er20");
  Scenario s = default_scenario(robot);  // rotor inertia on every joint (a real wrist has it)
  c.apply(s);
  DiagnoseOptions o = sim_options();
  // Undeclared rotor inertia: the declared model lacks the Ia columns, so every joint with a
  // separable Ia is a candidate; the one made dominant (joint 4) must be among the effects.
  const bool ia_case = std::string(c.kind) == "rotor_inertia";
  if (ia_case) {
    o.identify.terms = parse_model("eq7");
    o.max_effects = 4;
  }
  const auto r = diagnose(robot, simulated_log(s, robot, 20), o);
  print_diagnose_report(std::cout, r);
  ASSERT_FALSE(r.effects.empty()) << c.name;
  EXPECT_EQ(std::string(effect_name(r.effects[0].kind)), c.kind) << c.name << ": " << r.effects[0].explanation;
  const bool named = std::any_of(r.effects.begin(), r.effects.end(), [&](const DiagnosedEffect& e) {
    return effect_name(e.kind) == std::string(c.kind) && e.joints == c.joints;
  });
  EXPECT_TRUE(named) << c.name << ": not named on joint(s) " << c.joints.front();
  if (!ia_case) {
    EXPECT_EQ(r.effects[0].joints, c.joints) << c.name << ": " << r.effects[0].explanation;
  }
  if (std::string(c.kind) == "load_friction") {
    // The drive applies fl |h(q, qd)| sgn(qd), h the gravity and velocity-product torque; the
    // candidate has that shape, so f1 comes out within 5 % of the set 0.08 (with the full
    // rigid-body torque in place of h it came out 7.5 % low).
    EXPECT_NEAR(r.effects[0].params[0], 0.08, 0.004);
  }
  for (int j : c.joints) {
    const auto& m = r.joints[static_cast<size_t>(j - 1)];
    const double noise = s.tau_noise_std[static_cast<size_t>(j - 1)] * 0.28;  // 20 Hz of 250 Hz bandwidth
    auto above = [&](double rms) { return std::sqrt(std::max(0.0, rms * rms - noise * noise)); };
    EXPECT_LE(above(m.rms_validation_after), 0.5 * above(m.rms_validation_before)) << c.name << " joint " << j;
  }
}

INSTANTIATE_TEST_SUITE_P(SimulatedDrive, DiagnoseEffect, ::testing::Range(0, 6),
                         [](const ::testing::TestParamInfo<int>& i) {
                           return std::string(effect_cases()[i.param].name);
                         });

// A coupled motor whose ratio lies beyond the searched 1/5..5 (motor 6 turning with q6 + 8 q5): the
// data do not bound the ratio inside the search, so no coupling or coupled motor is reported with a
// ratio at the end of its interval, a note names it unbounded, and whatever is found has
// non-negative friction (and a joint's rotor inertia positive).
TEST(Diagnose, ARatioTheSearchCannotBoundIsNotReportedAsAnEffect) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  Scenario s = default_scenario(robot);
  s.motor_map[5][4] = 8.0;
  const auto r = diagnose(robot, simulated_log(s, robot, 20), sim_options());
  print_diagnose_report(std::cout, r);
  // Named as unbounded.
  EXPECT_TRUE(std::any_of(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("its ratio is not bounded by the data") != std::string::npos;
  }));
  for (const DiagnosedEffect& e : r.effects) {
    SCOPED_TRACE(e.explanation);
    if (e.kind == Effect::coupling || e.kind == Effect::coupled_motor) {
      EXPECT_GT(e.shape_interval.second, e.shape * (1 + 1e-9));
      EXPECT_LT(e.shape_interval.first, e.shape * (1 - 1e-9));
      EXPECT_LT(e.shape_interval.second, 5.0 * (1 - 1e-9));
    }
    for (size_t k = 0; k < e.params.size(); ++k) {
      const std::string& n = e.param_names[k];
      const bool friction = n.rfind("Fc", 0) == 0 || n.rfind("Fv", 0) == 0;
      const bool coupled = e.kind == Effect::coupling || e.kind == Effect::coupled_motor;
      if (e.kind == Effect::rotor_inertia || (coupled && friction)) {
        EXPECT_GE(e.params[k], 0.0) << n;
      }
    }
  }
}

TEST(Diagnose, AddsNothingWithoutAnUndeclaredEffectOverSeeds) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  int runs_with_effects = 0;
  const int seeds = 5;
  for (int seed = 1; seed <= seeds; ++seed) {
    Scenario s = default_scenario(robot);
    s.seed = static_cast<std::uint64_t>(seed);
    const auto r = diagnose(robot, simulated_log(s, robot, 20), sim_options());
    if (!r.effects.empty()) {
      ++runs_with_effects;
      std::cout << "seed " << seed << ": false positive: " << r.effects.front().explanation << " gain "
                << r.effects.front().validation_gain << " dBIC " << r.effects.front().delta_bic << "\n";
    }
  }
  std::cout << "false-positive rate: " << runs_with_effects << " of " << seeds << " runs\n";
  EXPECT_EQ(runs_with_effects, 0);
}

TEST(Diagnose, BadInputGetsAClearMessage) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  JointLog log;
  const int S = 4000;
  log.t = Eigen::VectorXd::LinSpaced(S, 0.0, (S - 1) / 500.0);
  log.q = Eigen::MatrixXd::Zero(S, 6);
  log.tau = Eigen::MatrixXd::Random(S, 6);
  for (int j = 0; j < 6; ++j) log.q.col(j) = 0.5 * (log.t.array() * (j + 1)).sin();
  log.q.col(3).setConstant(0.2);  // joint 4 never moves
  try {
    diagnose(robot, log, sim_options());
    FAIL() << "no error for a joint that does not move";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("joint 4 does not move"), std::string::npos) << e.what();
  }
  JointLog short_log;  // a quarter of a second
  short_log.t = log.t.head(125);
  short_log.q = log.q.topRows(125);
  short_log.tau = log.tau.topRows(125);
  short_log.q.col(3) = 0.5 * (short_log.t.array() * 4).sin();
  try {
    diagnose(robot, short_log, sim_options());
    FAIL() << "no error for too few samples";
  } catch (const InputError& e) {  // the folds' blocks do not fit the log (checked before any work)
    EXPECT_NE(std::string(e.what()).find("need at least 2.5 s of log, this one lasts 0.25 s"), std::string::npos)
        << e.what();
  }
  log.q.col(3) = 0.3 * log.t;  // constant velocity
  try {
    diagnose(robot, log, sim_options());
    FAIL() << "no error for constant velocity";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("constant velocity"), std::string::npos) << e.what();
  }
}

}  // namespace

// The diagnosis's regression splines (host_sim/common spline_basis.hpp, issue 71): the cubic
// B-spline basis sums to 1 at every point and reproduces every cubic polynomial exactly (Marsden's
// identity), whatever the knots; a variable resting at one value gets no repeated interior knot.
TEST(DiagnoseSplines, BasisIsAPartitionOfUnityAndReproducesCubics) {
  std::mt19937 rng(71);
  std::normal_distribution<double> normal;
  Eigen::VectorXd x(2000);
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = k < 600 ? 0.3 : std::tanh(normal(rng));  // rests at 0.3
  std::vector<double> bump_error;
  for (int interior : {4, 8, 16}) {
    const std::vector<double> knots = dyncal::host::spline_knots(x, interior);
    ASSERT_GE(knots.size(), 8u);
    for (size_t k = 5; k + 4 < knots.size(); ++k) EXPECT_GT(knots[k], knots[k - 1]) << "interior knots repeat";
    const Eigen::MatrixXd B = dyncal::host::spline_basis(x, knots);
    ASSERT_EQ(B.cols(), static_cast<Eigen::Index>(knots.size()) - 4);
    EXPECT_LT((B.rowwise().sum().array() - 1.0).abs().maxCoeff(), 1e-12);
    const Eigen::VectorXd cubic = (x.array().cube() - 2 * x.array().square() + 0.5 * x.array() - 1).matrix();
    const Eigen::VectorXd fit = B * B.colPivHouseholderQr().solve(cubic);
    EXPECT_LT((fit - cubic).cwiseAbs().maxCoeff(), 1e-10) << interior << " interior knots";
    // A smooth function that is not a cubic is not reproduced exactly, but closer with more knots.
    const Eigen::VectorXd bump = (-(x.array() / 0.2).square()).exp().matrix();
    bump_error.push_back((B * B.colPivHouseholderQr().solve(bump) - bump).norm() / bump.norm());
  }
  EXPECT_GT(bump_error[2], 1e-8);
  EXPECT_LT(bump_error[1], bump_error[0]);
  EXPECT_LT(bump_error[2], bump_error[1]);
  EXPECT_TRUE(dyncal::host::spline_knots(Eigen::VectorXd::Constant(50, 1.0), 8).empty());
}

// The roughness rows give the integral of f''(x)^2 exactly, against the second differences of the
// shape's own basis on a fine grid (trapezoid rule, an independent route), for both bases and
// uneven knots; a line in x (the penalty's null space) costs nothing.
TEST(DiagnoseSplines, RoughnessRowsIntegrateTheSquaredSecondDerivative) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(-1.0, 3.0);
  Eigen::VectorXd x(400);
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = uniform(rng) * std::abs(uniform(rng));  // uneven quantiles
  const std::vector<double> knots = dyncal::host::spline_knots(x, 7);
  const double lo = knots.front(), hi = knots.back();
  const Eigen::Index points = 200001;
  const double h = (hi - lo) / static_cast<double>(points - 1);
  Eigen::VectorXd grid(points);
  for (Eigen::Index k = 0; k < points; ++k) grid[k] = lo + h * static_cast<double>(k);
  for (const bool without_linear : {false, true}) {
    const Eigen::MatrixXd L = dyncal::host::shape_roughness_rows(knots, without_linear);
    const Eigen::MatrixXd B = dyncal::host::shape_basis(grid, knots, without_linear);
    ASSERT_EQ(L.cols(), B.cols());
    for (int trial = 0; trial < 3; ++trial) {
      Eigen::VectorXd c(B.cols());
      for (Eigen::Index k = 0; k < c.size(); ++k) c[k] = uniform(rng);
      const Eigen::VectorXd f = B * c;
      double integral = 0;
      for (Eigen::Index k = 1; k + 1 < points; ++k) {
        const double f2 = (f[k + 1] - 2 * f[k] + f[k - 1]) / (h * h);
        integral += f2 * f2 * h;
      }
      EXPECT_NEAR((L * c).squaredNorm(), integral, 2e-3 * integral)
          << (without_linear ? "without" : "with") << " linear, trial " << trial;
    }
    if (!without_linear) {  // 1 - B_1(x) - ... is not a line; a + b x in the plain basis is: its cost is 0
      Eigen::MatrixXd A(grid.size(), B.cols() + 1);
      A << Eigen::VectorXd::Ones(grid.size()), B;
      const Eigen::VectorXd line = (0.3 + 1.7 * grid.array()).matrix();
      const Eigen::VectorXd coef = A.colPivHouseholderQr().solve(line);
      EXPECT_LT((L * coef.tail(B.cols())).norm(), 1e-9);
    }
  }
}

// A shape of the model's own torque leaves out its variable's constant and linear part (a linear
// part would scale every parameter): with 1 and x beside them its columns are of full rank, where
// the plain shape's columns (the first B-spline left out) and 1 already span x.
TEST(DiagnoseSplines, ShapeWithoutLinearPartSpansNoLine) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(-2.0, 5.0);
  Eigen::VectorXd x(500);
  for (Eigen::Index k = 0; k < x.size(); ++k) x[k] = uniform(rng);
  const std::vector<double> knots = dyncal::host::spline_knots(x, 6);
  for (const bool without_linear : {false, true}) {
    const Eigen::MatrixXd B = dyncal::host::shape_basis(x, knots, without_linear);
    ASSERT_EQ(B.cols(), dyncal::host::shape_basis_columns(knots, without_linear));
    Eigen::MatrixXd A(x.size(), B.cols() + 2);
    A << Eigen::VectorXd::Ones(x.size()), x, B;
    const Eigen::Index rank = A.colPivHouseholderQr().rank();
    EXPECT_EQ(rank, without_linear ? A.cols() : A.cols() - 1) << (without_linear ? "without" : "with") << " linear";
  }
}
