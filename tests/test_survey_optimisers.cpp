// The survey's optimisation methods (Sec. 3.4): the reduced objective against the residual computed
// sample by sample and against central differences, and each optimiser against the set parameters
// of noise-free simulated data, inside its ranges and physically feasible.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/survey/indices.hpp"
#include "dyncal_host/survey/methods/optimisers.hpp"
#include "dyncal_host/survey/methods/standard_parameters.hpp"
#include "dyncal_host/survey/survey_data.hpp"
#include "support/survey_fixture.hpp"

namespace {

using namespace dyncal::host;
using namespace dyncal::host::survey;
using Robot = dyncal::generated::er20::Robot;
using Vec6 = Eigen::Matrix<double, 6, 1>;

using dyncal::test::kEr20TauMax;
using dyncal::test::survey_data;
using dyncal::test::survey_settings;
const std::array<double, 6> kSigma{10, 10, 10, 1.78, 1.78, 1.78};

/// A decision vector near the set values (CAD inertials, friction 10 % off the set values).
Eigen::VectorXd near_set(FrictionModel m) {
  const auto f = set_friction(survey_data(m).scenario, m);
  Eigen::VectorXd x(kStandard + static_cast<Eigen::Index>(f.size()));
  x.head(kStandard) = cad_prior(0.2, 7).mean;
  for (size_t i = 0; i < f.size(); ++i) x[kStandard + static_cast<Eigen::Index>(i)] = 1.1 * f[i];
  return x;
}

constexpr FrictionModel kAllModels[] = {FrictionModel::eq7, FrictionModel::eq8, FrictionModel::eq9,
                                        FrictionModel::eq4, FrictionModel::eq5, FrictionModel::eq6};

TEST(SurveyObjective, MomentsEqualTheResidualComputedSampleBySample) {
  for (FrictionModel m : kAllModels) {
    SCOPED_TRACE(model_key(m));
    const SurveyData& d = survey_data(m);
    const TorqueObjective obj(d, m, kSigma);
    const Eigen::VectorXd x = near_set(m);
    const int kf = obj.friction_per_joint();
    Eigen::MatrixXd e(d.q.rows(), 6);
    Eigen::Matrix<double, 6, kStandard> Ys;
    for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
      Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                                Vec6(d.qdd.row(s).transpose()), Ys);
      const Vec6 tau = Ys * x.head(kStandard);
      for (int j = 0; j < 6; ++j) {
        e(s, j) =
            (d.tau(s, j) - tau[j] - friction_torque(m, x.data() + kStandard + kf * j, d.qd(s, j), d.tau_load(s, j))) /
            kSigma[j];
      }
    }
    std::array<double, 6> mean{}, var{};
    obj.residual_moments(x.data(), mean, var);
    double ls = 0, j25 = 0;
    for (int j = 0; j < 6; ++j) {
      const double mu = e.col(j).mean(), v = (e.col(j).array() - mu).square().mean();
      EXPECT_NEAR(mean[j], mu, 1e-9 * (1 + std::fabs(mu))) << j;
      EXPECT_NEAR(var[j], v, 1e-8 * (1 + v)) << j;
      ls += e.col(j).squaredNorm() / static_cast<double>(e.rows());
      j25 += std::fabs(mu) + 0.5 * std::sqrt(v);
    }
    EXPECT_NEAR(obj.least_squares(x.data()), ls, 1e-8 * ls);
    EXPECT_NEAR(obj.eq25(x.data(), 0.5), j25, 1e-8 * j25);
  }
}

TEST(SurveyObjective, GradientsMatchCentralDifferences) {
  for (FrictionModel m : kAllModels) {
    SCOPED_TRACE(model_key(m));
    const TorqueObjective obj(survey_data(m), m, kSigma);
    const Eigen::VectorXd x = near_set(m);
    Eigen::VectorXd g_ls(x.size()), g_25(x.size());
    obj.least_squares(x.data(), g_ls.data());
    obj.eq25(x.data(), 1.0, g_25.data());
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      if (x[i] == 0) continue;  // structural zero
      const double h = 1e-4 * std::max(std::fabs(x[i]), 1e-2);
      Eigen::VectorXd xp = x, xm = x;
      xp[i] += h;
      xm[i] -= h;
      const double fd_ls = (obj.least_squares(xp.data()) - obj.least_squares(xm.data())) / (2 * h);
      const double fd_25 = (obj.eq25(xp.data(), 1.0) - obj.eq25(xm.data(), 1.0)) / (2 * h);
      EXPECT_NEAR(g_ls[i], fd_ls, 1e-4 * (std::fabs(fd_ls) + 1e-2)) << "least squares, variable " << i;
      EXPECT_NEAR(g_25[i], fd_25, 1e-4 * (std::fabs(fd_25) + 1e-2)) << "Eq. 25, variable " << i;
    }
  }
}

TEST(SurveyObjective, FittedAmplitudesAreTheLeastSquaresOnesGivenTheRest) {
  for (FrictionModel m : kAllModels) {
    SCOPED_TRACE(model_key(m));
    const TorqueObjective obj(survey_data(m), m, kSigma);
    Eigen::VectorXd x = near_set(m);
    const Eigen::VectorXd before = x;
    std::array<double, 6> mean{}, var{}, mean_ref{}, var_ref{};
    obj.fit_amplitudes(x.data(), nullptr, nullptr, &mean, &var);
    obj.residual_moments(x.data(), mean_ref, var_ref);
    for (int j = 0; j < 6; ++j) {
      EXPECT_NEAR(mean[j], mean_ref[j], 1e-9 * (1 + std::fabs(mean_ref[j]))) << j;
      EXPECT_NEAR(var[j], var_ref[j], 1e-8 * (1 + var_ref[j])) << j;
    }
    // Clamped into bounds that exclude the optimum, the moments are still those of the result.
    {
      Eigen::VectorXd y = before, lo = before * 0.99, hi = before * 1.01;
      for (Eigen::Index i = 0; i < y.size(); ++i) {
        if (lo[i] > hi[i]) std::swap(lo[i], hi[i]);
      }
      obj.fit_amplitudes(y.data(), lo.data(), hi.data(), &mean, &var);
      obj.residual_moments(y.data(), mean_ref, var_ref);
      for (int j = 0; j < 6; ++j) {
        EXPECT_NEAR(mean[j], mean_ref[j], 1e-9 * (1 + std::fabs(mean_ref[j]))) << "clamped " << j;
        EXPECT_NEAR(var[j], var_ref[j], 1e-8 * (1 + var_ref[j])) << "clamped " << j;
      }
      for (Eigen::Index i = 0; i < y.size(); ++i) {
        EXPECT_GE(y[i], lo[i]);
        EXPECT_LE(y[i], hi[i]);
      }
    }
    Eigen::VectorXd g(x.size());
    const double ls = obj.least_squares(x.data(), g.data());
    EXPECT_LT(ls, obj.least_squares(before.data()));
    const int kf = obj.friction_per_joint();
    for (Eigen::Index i = 0; i < x.size(); ++i) {
      const bool amplitude = i >= kStandard && !is_scale_parameter(m, static_cast<int>((i - kStandard) % kf));
      if (amplitude) {
        // Stationary in every amplitude (relative to the gradient's size in a 10 % move of it).
        EXPECT_NEAR(g[i] * 0.1 * std::fabs(x[i]), 0.0, 1e-9 * ls) << "variable " << i;
      } else {
        EXPECT_EQ(x[i], before[i]) << "variable " << i;  // standard and scale parameters untouched
      }
    }
  }
}

// The Stribeck velocity's profile-likelihood interval from the joint friction scan, on Eq. 4 runs
// with the exact rigid-body torque removed: noise-free, one grid step either side of the set qds; with Table 7
// noise (seed 5), bounded around the set value where the Stribeck peak stands out, and open on both
// sides on joint 6, whose peak (Fs - Fc = 1.6 Nm) is below its 1.78 Nm noise: there the fit's qds
// (5.6 rad/s for 0.1) is not a finding, and the interval says so.
// The samplers evaluate a population joint by joint (fit_amplitudes over a batch): every vector's
// amplitudes and moments must be the single call's bit for bit, or the study's results would
// depend on how it is batched.
TEST(SurveyObjective, BatchFitEqualsOneByOneBitForBit) {
  for (FrictionModel m : kAllModels) {
    SCOPED_TRACE(model_key(m));
    const TorqueObjective obj(survey_data(m), m, kSigma);
    const SearchRanges r = search_ranges(survey_data(m), m, cad_prior(0.2, 7).mean, 0.4);
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> U(0.0, 1.0);
    std::vector<Eigen::VectorXd> batch, single, drawn;
    for (int i = 0; i < 7; ++i) {
      Eigen::VectorXd x = r.lo;
      for (Eigen::Index k = 0; k < x.size(); ++k) x[k] += U(rng) * (r.hi[k] - r.lo[k]);
      batch.push_back(x);
      single.push_back(x);
      drawn.push_back(x);
    }
    std::vector<double*> ptrs;
    for (Eigen::VectorXd& x : batch) ptrs.push_back(x.data());
    std::vector<std::array<double, 6>> means, vars;
    obj.fit_amplitudes(ptrs, r.lo.data(), r.hi.data(), &means, &vars);
    ASSERT_EQ(means.size(), batch.size());
    for (size_t i = 0; i < single.size(); ++i) {
      std::array<double, 6> mean{}, var{};
      obj.fit_amplitudes(single[i].data(), r.lo.data(), r.hi.data(), &mean, &var);
      EXPECT_TRUE(single[i] == batch[i]) << "vector " << i;
      EXPECT_EQ(mean, means[i]) << "vector " << i;
      EXPECT_EQ(var, vars[i]) << "vector " << i;
      EXPECT_FALSE(batch[i] == drawn[i]) << "vector " << i << ": no amplitude was fitted";
    }
  }
}

TEST(SurveyObjective, FrictionCountIsTheNumberOfNames) {
  for (FrictionModel m : kAllModels) {
    EXPECT_EQ(friction_count(m), static_cast<int>(friction_parameter_names(m).size())) << model_key(m);
  }
}

TEST(SurveyObjective, StribeckVelocityIntervalIsBoundedOnlyWhereTheDataDetermineIt) {
  const auto robot = load_robot(default_robots_dir(), "er20");
  for (bool noise : {false, true}) {
    SurveyDataOptions o;
    o.friction = FrictionModel::eq4;
    o.torque_noise = noise;
    o.seed = noise ? 5 : 1;
    const SurveyData d = simulate_survey_data(robot, o);
    const Eigen::VectorXd phi = set_standard();
    Eigen::MatrixXd rest(d.q.rows(), 6);
    Eigen::Matrix<double, 6, kStandard> Y;
    for (Eigen::Index s = 0; s < d.q.rows(); ++s) {
      Robot::standard_regressor(Vec6(d.q.row(s).transpose()), Vec6(d.qd.row(s).transpose()),
                                Vec6(d.qdd.row(s).transpose()), Y);
      rest.row(s) = d.tau.row(s) - (Y * phi).transpose();
    }
    int containing = 0;
    for (int j = 0; j < 6; ++j) {
      std::vector<ScaleInterval> iv;
      fit_joint_friction(FrictionModel::eq4, d.qd.col(j), d.tau_load.col(j), rest.col(j), velocity_scale_range(d, j),
                         &iv);
      ASSERT_EQ(iv.size(), 1u);
      EXPECT_EQ(iv[0].parameter, 2);
      const double set = d.scenario.friction[static_cast<size_t>(j)].qds;
      if (!noise) {  // the best grid point and its two neighbours
        EXPECT_NEAR(std::log(iv[0].best / set), 0.0, std::log(1.08)) << j;  // one grid step
        EXPECT_LT(iv[0].hi / iv[0].lo, 1.08 * 1.08) << j;
        EXPECT_TRUE(iv[0].lo <= set && set <= iv[0].hi) << j;
        continue;
      }
      if (j == 5) {
        EXPECT_TRUE(iv[0].open_below && iv[0].open_above) << iv[0].lo << " " << iv[0].hi;
        continue;
      }
      EXPECT_FALSE(iv[0].open_above) << j;
      EXPECT_LT(iv[0].hi / iv[0].lo, 10.0) << j;  // within a decade, of the two searched
      containing += iv[0].lo <= set && set <= iv[0].hi;
    }
    // 95 % intervals: most of the five determined joints contain the set value.
    if (noise) {
      EXPECT_GE(containing, 4);
    }
  }
}

TEST(SurveyObjective, MinEigenvalueGradientMatchesCentralDifferences) {
  // At CAD-like values (random 20 % errors): every link's smallest eigenvalue is simple there.
  const Eigen::VectorXd phi = cad_prior(0.2, 7).mean;
  for (int l = 0; l < kLinks; ++l) {
    double g[10];
    pseudo_inertia_min_eigenvalue(phi.data() + 10 * l, g);
    for (int k = 0; k < 10; ++k) {
      double p[10], q[10];
      for (int i = 0; i < 10; ++i) p[i] = q[i] = phi[10 * l + i];
      p[k] += 1e-7;
      q[k] -= 1e-7;
      const double fd = (pseudo_inertia_min_eigenvalue(p, nullptr) - pseudo_inertia_min_eigenvalue(q, nullptr)) / 2e-7;
      EXPECT_NEAR(g[k], fd, 1e-5) << "link " << l + 1 << " parameter " << k;
    }
  }
}

/// The result lies in its ranges and every link is physically consistent.
void expect_feasible_in_ranges(const Estimate& e, const SurveyData& d, FrictionModel m, const MethodSettings& s) {
  const SearchRanges r = search_ranges(d, m, nearest_consistent(s.prior.mean), OptimiserSettings{}.range_width);
  Eigen::VectorXd x(r.lo.size());
  x.head(kStandard) = e.standard;
  for (size_t i = 0; i < e.friction.size(); ++i) x[kStandard + static_cast<Eigen::Index>(i)] = e.friction[i];
  for (Eigen::Index i = 0; i < x.size(); ++i) {
    EXPECT_GE(x[i], r.lo[i] - 1e-12 * std::fabs(r.lo[i])) << e.method << " variable " << i;
    EXPECT_LE(x[i], r.hi[i] + 1e-12 * std::fabs(r.hi[i])) << e.method << " variable " << i;
  }
  for (int l = 0; l < kLinks; ++l) {
    EXPECT_GT(pseudo_inertia_min_eigenvalue(e.standard.data() + 10 * l, nullptr), 0.0) << e.method << " link " << l + 1;
  }
}

TEST(SurveyOptimisers, GradientDescentRecoversFrictionAndFitsNoiseFreeData) {
  for (FrictionModel m : kAllModels) {
    SCOPED_TRACE(model_key(m));
    const SurveyData& d = survey_data(m);
    const Estimate e = gradient_descent(d, m, survey_settings());
    expect_feasible_in_ranges(e, d, m, survey_settings());
    const Indices x = evaluate(e, d.scenario, d.tau, kEr20TauMax);
    const auto f = set_friction(d.scenario, m);
    // Each joint's friction curve over the run's velocities within 2 % (RMS) of the set one, also
    // where parameters trade off (Eq. 5's f1 and f4, Eq. 8's Fc and fp).
    for (int j = 0; j < 6; ++j) {
      EXPECT_LT(dyncal::test::friction_curve_error(d, m, e.friction, f, j), 0.02) << "joint " << j + 1;
    }
    // The set link 3 is not consistent, so a feasible fit leaves a small residual (survey: 6e-4).
    EXPECT_LT(x.e_T_std, 5e-3);
    // Eq. 7 and 4 as the survey's: friction within 5 % on average, J_e level A (Table 2). Eq. 5's
    // f1 and f4 are nearly collinear over this excitation (exp(-1 / (f5 |qd|)) varies slowly), so
    // only its torque fit and Coulomb level are asserted (measured e_f 0.55).
    if (m == FrictionModel::eq7 || m == FrictionModel::eq4) {
      EXPECT_LT(x.e_f, 0.05);
    }
    if (m != FrictionModel::eq5) {
      EXPECT_LT(x.J_e, 1.0);
    }
  }
}

// Why the optimisers' link 3 (Tables 5, 6) is further from the set values than the survey's: the
// error lies in the directions of the standard parameters that no torque can show (the null space
// of Gautier's base map). Split the error phi - phi_set into its part in the row space of the base
// map (what the data determine) and the rest: the first alone leaves link 3 close; the rest is
// where the search stopped in its box. With the CAD prior in those directions (standard_prior, the
// same base parameters and torques) link 3 is close again.
TEST(SurveyOptimisers, Link3ErrorLiesInTheDirectionsNoTorqueDetermines) {
  const SurveyData& d = survey_data(FrictionModel::eq7);
  const Estimate e = gradient_descent(d, FrictionModel::eq7, survey_settings());
  const Eigen::MatrixXd& G = base_map();
  const Eigen::MatrixXd row_space = G.completeOrthogonalDecomposition().pseudoInverse() * G;
  const Eigen::VectorXd set = set_standard(), err = e.standard - set;
  const double full = link_inertial_error(e.standard, 2), determined = link_inertial_error(set + row_space * err, 2);
  EXPECT_GT(full, 0.3);                                              // measured 0.77 (survey: 0.26)
  EXPECT_LT(determined, 0.25 * full);                                // measured 0.04
  EXPECT_LT(link_inertial_error(e.standard_prior, 2), 0.25 * full);  // measured 0.07
  // Same base parameters: the prior-anchored point predicts the same torques.
  EXPECT_LT((G * (e.standard_prior - e.standard)).norm(), 1e-9 * (G * e.standard).norm());
}

TEST(SurveyOptimisers, GeneticAlgorithmAndParticleFilterFitNoiseFreeDataWithinTheirRanges) {
  const FrictionModel m = FrictionModel::eq7;
  const SurveyData& d = survey_data(m);
  const auto f = set_friction(d.scenario, m);
  // No initial values, only ranges. Tolerances: J_e level A (survey: GA 0.87, PF 0.65); the GA
  // (elitist) recovers each Fc and beta within 10 % (5 % on average), the particle filter's friction within 30 % on
  // average (it samples the tempered posterior; its spread in the flat directions is the price).
  const Estimate ga = genetic_algorithm(d, m, survey_settings()), pf = particle_filter(d, m, survey_settings());
  for (const Estimate* e : {&ga, &pf}) {
    expect_feasible_in_ranges(*e, d, m, survey_settings());
    const Indices x = evaluate(*e, d.scenario, d.tau, kEr20TauMax);
    EXPECT_LT(x.e_T_std, 0.02) << e->method;
    EXPECT_LT(x.J_e, 1.0) << e->method;
    EXPECT_LT(x.e_f, e == &ga ? 0.05 : 0.3) << e->method;
  }
  for (int i = 0; i < 12; ++i) EXPECT_NEAR(ga.friction[i], f[i], 0.1 * f[i]) << "GA friction " << i;
  // Both beat the CAD values with mid-range friction on the Eq. 25 objective by far.
  const TorqueObjective obj(d, m, survey_settings().sigma);
  Eigen::VectorXd start(kStandard + 12), x_ga(kStandard + 12), x_pf(kStandard + 12);
  const SearchRanges r = search_ranges(d, m, nearest_consistent(survey_settings().prior.mean), 0.4);
  start = 0.5 * (r.lo + r.hi);
  x_ga << ga.standard, Eigen::Map<const Eigen::VectorXd>(ga.friction.data(), 12);
  x_pf << pf.standard, Eigen::Map<const Eigen::VectorXd>(pf.friction.data(), 12);
  EXPECT_LT(obj.eq25(x_ga.data(), 1.0), 0.1 * obj.eq25(start.data(), 1.0));
  EXPECT_LT(obj.eq25(x_pf.data(), 1.0), 0.1 * obj.eq25(start.data(), 1.0));
}

TEST(SurveyOptimisers, StochasticOptimisersAreDeterministicForASeed) {
  const SurveyData& d = survey_data(FrictionModel::eq7);
  OptimiserSettings o;
  o.generations = 50;
  o.population = 24;
  for (auto run : {genetic_algorithm, particle_filter}) {
    const Estimate a = run(d, FrictionModel::eq7, survey_settings(), o),
                   b = run(d, FrictionModel::eq7, survey_settings(), o);
    EXPECT_EQ(a.standard, b.standard);
    EXPECT_EQ(a.friction, b.friction);
    o.seed = 2;
    EXPECT_NE(run(d, FrictionModel::eq7, survey_settings(), o).standard, a.standard);
    o.seed = 1;
  }
}

TEST(SurveyOptimisers, RejectsTooSmallBudgets) {
  OptimiserSettings o;
  o.population = 2;
  EXPECT_THROW(genetic_algorithm(survey_data(FrictionModel::eq7), FrictionModel::eq7, survey_settings(), o),
               InputError);
  EXPECT_THROW(particle_filter(survey_data(FrictionModel::eq7), FrictionModel::eq7, survey_settings(), o), InputError);
}

}  // namespace
