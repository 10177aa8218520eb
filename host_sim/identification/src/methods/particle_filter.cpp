// Particle filter for static parameters (survey Sec. 3.4 (3)) as a sequential Monte Carlo sampler
// (Del Moral, Doucet and Jasra 2006): particles drawn uniformly from the feasible search box are
// carried through the tempered targets p_b(x) ~ exp(-b J(x)) on that box, J the negative
// log-likelihood of the torques under the assumed (Table 7) noise, b rising from 0 to 1 (the
// posterior). Each step raises b so that the effective sample size of the incremental weights is
// half the particle count (adaptive tempering), resamples (systematic), and rejuvenates every
// particle by random-walk Metropolis moves whose proposal covariance is the particles' own
// (scale 2.38 / sqrt(D), adapted towards an acceptance rate of 0.234); at b = 1 the moves go on
// until the budget is spent. On the nonlinear models each step also gives every particle one
// independence Metropolis-Hastings move of one joint's scale parameters, proposed from their
// uniform prior on the box (acceptance exp(-b (J' - J)): prior and proposal cancel): a local
// random walk does not cross from one decade of a Stribeck velocity to another, and the
// joint's term of J is what decides. The friction amplitudes (every friction parameter but the scale
// parameters, in which the torque is linear once the scales are fixed) are not sampled: each
// particle carries their least-squares values given its other parameters, which is their
// conditional posterior mean under a flat prior, so the particles sample the other parameters'
// profile posterior (Rao-Blackwellised, without the Laplace factor |B^T B|^-1/2 of the exact
// marginal). The estimate is the posterior mean.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/inertial_parameters.hpp"
#include "dyncal_host/identification/methods/search_problem.hpp"

namespace dyncal::host {
namespace {

constexpr double kTargetAcceptance = 0.234;

/// Next inverse temperature b' > b with ESS(exp(-(b' - b) f)) = N / 2 (bisection on b' - b).
double next_inverse_temperature(const Eigen::VectorXd& f, double b) {
  const double fmin = f.minCoeff();
  const double N = static_cast<double>(f.size());
  auto ess = [&](double db) {
    const Eigen::ArrayXd w = (-(f.array() - fmin) * db).exp();
    return w.sum() * w.sum() / w.square().sum();
  };
  double lo = 0, hi = 1.0 / std::max(f.maxCoeff() - fmin, 1e-300);
  while (ess(hi) > 0.5 * N && hi < 1e300) hi *= 2;
  for (int it = 0; it < 60; ++it) {
    const double mid = 0.5 * (lo + hi);
    (ess(mid) > 0.5 * N ? lo : hi) = mid;
  }
  return b + hi;
}

}  // namespace

namespace detail {

Eigen::VectorXd particle_search(const SearchProblem& problem, const OptimiserSettings& options, int& steps) {
  if (options.population < 4 || options.generations < kParticleMovesPerStep) {
    throw InputError("particle filter: >= 4 particles and >= 5 evaluations per particle");
  }
  const int links = problem.num_links();
  const int D = problem.free_dimension(), N = options.population;
  std::mt19937_64 rng(options.seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  // Initial particles: uniform on the feasible part of the box. Feasibility is per link and the
  // box is a product, so each link's variables are drawn until that link is consistent.
  Eigen::MatrixXd X(D, N);
  std::vector<std::vector<int>> link_vars(static_cast<size_t>(links) + 1);  // free variables per link; last: the rest
  for (int k = 0; k < D; ++k) link_vars[static_cast<size_t>(std::min(problem.free_index(k) / 10, links))].push_back(k);
  // Negative log-likelihood of the torques under the assumed noise (survey: Table 7 sigma_j,
  // Gaussian, (S / 2) sum_j ||e_j / sigma_j||^2 / S); the target at b = 1 is the posterior on the ranges.
  const double likelihood_scale = problem.likelihood_scale();
  // Proposals us (unit coordinates) with their amplitudes at their conditional least-squares values
  // (written back), their full vectors into xs and their costs into costs: one population
  // (fit_population; no random number is drawn while evaluating, so a pass's proposals are drawn
  // first and evaluated together, with the results of one by one).
  std::vector<Eigen::VectorXd> xs;
  std::vector<std::vector<double>> means, vars;
  std::vector<double> costs;
  auto fitted = [&](std::vector<Eigen::VectorXd>& us) {
    xs.clear();
    for (const Eigen::VectorXd& u : us) xs.push_back(problem.full(u.data()));
    problem.fit_population(xs, means, vars);
    costs.assign(us.size(), 0.0);
    for (size_t p = 0; p < us.size(); ++p) {
      us[p] = problem.unit(xs[p]);
      double ls = 0;
      for (size_t j = 0; j < means[p].size(); ++j) ls += means[p][j] * means[p][j] + vars[p][j];
      costs[p] = likelihood_scale * ls;
    }
  };
  Eigen::VectorXd f(N);
  std::vector<Eigen::VectorXd> us;
  for (int i = 0; i < N; ++i) {
    for (int k = 0; k < D; ++k) X(k, i) = U(rng);
    for (int l = 0; l < links; ++l) {
      for (int tries = 0; tries < 100000; ++tries) {
        const Eigen::VectorXd x = problem.full(X.col(i).data());
        if (pseudo_inertia_min_eigenvalue(x.data() + 10 * l, nullptr) > 0) break;
        for (int k : link_vars[static_cast<size_t>(l)]) X(k, i) = U(rng);
      }
    }
    us.push_back(X.col(i));
  }
  fitted(us);
  for (int i = 0; i < N; ++i) {
    X.col(i) = us[static_cast<size_t>(i)];
    f[i] = costs[static_cast<size_t>(i)];
    if (problem.violation(xs[static_cast<size_t>(i)]) > 0)
      throw InputError("particle filter: no feasible point found in the search ranges");
  }
  // Each joint's scale-parameter coordinates (nonlinear models), for the independence moves.
  const std::vector<std::vector<int>> joint_scales = problem.scale_groups();
  const bool independence_moves = !joint_scales.empty();
  double b = 0, scale = 2.38 / std::sqrt(static_cast<double>(D));
  steps = options.generations / (kParticleMovesPerStep + (independence_moves ? 1 : 0));
  for (int step = 0; step < steps; ++step) {
    const double b_next = std::min(1.0, b < 1.0 ? next_inverse_temperature(f, b) : 1.0);
    Eigen::VectorXd w = (-(f.array() - f.minCoeff()) * (b_next - b)).exp().matrix();
    w /= w.sum();
    b = b_next;
    // Systematic resampling.
    Eigen::MatrixXd Xr(D, N);
    Eigen::VectorXd fr(N);
    const double u0 = U(rng) / N;
    double cum = w[0];
    int src = 0;
    for (int i = 0; i < N; ++i) {
      while (cum < u0 + static_cast<double>(i) / N && src < N - 1) cum += w[++src];
      Xr.col(i) = X.col(src);
      fr[i] = f[src];
    }
    X.swap(Xr);
    f.swap(fr);
    // Proposal covariance from the resampled particles.
    const Eigen::VectorXd mean = X.rowwise().mean();
    const Eigen::MatrixXd C = X.colwise() - mean;
    Eigen::MatrixXd cov = C * C.transpose() / std::max(N - 1, 1);
    cov.diagonal().array() += 1e-14;
    const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(cov).matrixL();
    // One pass of proposals, at most one per particle (particle[p], proposal us[p], log u logu[p]):
    // Metropolis acceptance of each at the current b (written back with its fitted amplitudes);
    // infeasible proposals have density 0. Returns the number accepted.
    std::vector<int> particle;
    std::vector<double> logu;
    auto try_moves = [&]() {
      fitted(us);
      int taken = 0;
      for (size_t p = 0; p < us.size(); ++p) {
        const int i = particle[p];
        if (problem.violation(xs[p]) > 0 || !(logu[p] < -b * (costs[p] - f[i]))) continue;
        X.col(i) = us[p];
        f[i] = costs[p];
        ++taken;
      }
      particle.clear();
      logu.clear();
      us.clear();
      return taken;
    };
    int accepted = 0;
    us.clear();
    for (int move = 0; move < kParticleMovesPerStep; ++move) {
      for (int i = 0; i < N; ++i) {
        Eigen::VectorXd z(D);
        for (int k = 0; k < D; ++k) z[k] = normal(rng);
        Eigen::VectorXd u = X.col(i) + scale * (L * z);
        const double lu = std::log(U(rng));
        if ((u.array() < 0).any() || (u.array() > 1).any()) continue;  // outside the box: density 0
        particle.push_back(i);
        logu.push_back(lu);
        us.push_back(std::move(u));
      }
      accepted += try_moves();
    }
    const double rate = static_cast<double>(accepted) / (kParticleMovesPerStep * N);
    scale *= std::exp(rate - kTargetAcceptance);
    if (independence_moves) {
      std::uniform_int_distribution<int> joint(0, static_cast<int>(joint_scales.size()) - 1);
      for (int i = 0; i < N; ++i) {
        Eigen::VectorXd u = X.col(i);
        for (int k : joint_scales[static_cast<size_t>(joint(rng))]) u[k] = U(rng);
        particle.push_back(i);
        logu.push_back(std::log(U(rng)));
        us.push_back(std::move(u));
      }
      try_moves();
    }
  }
  // The posterior mean (feasible: the consistent set and the box are convex in these coordinates).
  const Eigen::VectorXd posterior_mean = X.rowwise().mean();
  return problem.full(posterior_mean.data());
}

}  // namespace detail

}  // namespace dyncal::host
