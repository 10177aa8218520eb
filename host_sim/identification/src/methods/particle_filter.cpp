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
#include "dyncal_host/identification/methods/search_problem.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace {

using detail::kParticleMovesPerStep;
using detail::SearchProblem;

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

/// The particles and what moves them (the sampler of the file's comment), one population of
/// proposals evaluated at a time.
class ParticleSampler {
 public:
  ParticleSampler(const SearchProblem& problem, const OptimiserSettings& options)
      : problem_(problem),
        D_(problem.free_dimension()),
        N_(options.population),
        rng_(options.seed),
        // Negative log-likelihood of the torques under the assumed noise (survey: Table 7 sigma_j,
        // Gaussian, (S / 2) sum_j ||e_j / sigma_j||^2 / S); the target at b = 1 is the posterior on
        // the ranges.
        likelihood_scale_(problem.likelihood_scale()),
        X_(D_, N_),
        f_(N_) {}

  /// Initial particles: uniform on the feasible part of the box. Feasibility is per link and the
  /// box is a product, so each link's variables are drawn until that link is consistent. Throws
  /// InputError when no feasible point is found.
  void draw_initial() {
    const int links = problem_.num_links();
    std::vector<std::vector<int>> link_vars(static_cast<size_t>(links) + 1);  // free variables per link; last: the rest
    for (int k = 0; k < D_; ++k)
      link_vars[static_cast<size_t>(std::min(problem_.free_index(k) / 10, links))].push_back(k);
    for (int i = 0; i < N_; ++i) {
      for (int k = 0; k < D_; ++k) X_(k, i) = U_(rng_);
      for (int l = 0; l < links; ++l) {
        for (int tries = 0; tries < 100000; ++tries) {
          const Eigen::VectorXd x = problem_.full(X_.col(i).data());
          if (pseudo_inertia_min_eigenvalue(x.data() + 10 * l, nullptr) > 0) break;
          for (int k : link_vars[static_cast<size_t>(l)]) X_(k, i) = U_(rng_);
        }
      }
      us_.push_back(X_.col(i));
    }
    fitted();
    for (int i = 0; i < N_; ++i) {
      X_.col(i) = us_[static_cast<size_t>(i)];
      f_[i] = costs_[static_cast<size_t>(i)];
      if (problem_.violation(xs_[static_cast<size_t>(i)]) > 0)
        throw InputError("particle filter: no feasible point found in the search ranges");
    }
    us_.clear();
  }

  /// Raises the inverse temperature (adaptive tempering) and resamples (systematic).
  void temper_and_resample() {
    const double b_next = std::min(1.0, b_ < 1.0 ? next_inverse_temperature(f_, b_) : 1.0);
    Eigen::VectorXd w = (-(f_.array() - f_.minCoeff()) * (b_next - b_)).exp().matrix();
    w /= w.sum();
    b_ = b_next;
    Eigen::MatrixXd Xr(D_, N_);
    Eigen::VectorXd fr(N_);
    const double u0 = U_(rng_) / N_;
    double cum = w[0];
    int src = 0;
    for (int i = 0; i < N_; ++i) {
      while (cum < u0 + static_cast<double>(i) / N_ && src < N_ - 1) cum += w[++src];
      Xr.col(i) = X_.col(src);
      fr[i] = f_[src];
    }
    X_.swap(Xr);
    f_.swap(fr);
  }

  /// kParticleMovesPerStep passes of random-walk Metropolis moves, the proposal covariance the
  /// resampled particles' own; the scale adapted towards kTargetAcceptance.
  void random_walk_moves() {
    const Eigen::VectorXd mean = X_.rowwise().mean();
    const Eigen::MatrixXd C = X_.colwise() - mean;
    Eigen::MatrixXd cov = C * C.transpose() / std::max(N_ - 1, 1);
    cov.diagonal().array() += 1e-14;
    const Eigen::MatrixXd L = Eigen::LLT<Eigen::MatrixXd>(cov).matrixL();
    int accepted = 0;
    for (int move = 0; move < kParticleMovesPerStep; ++move) {
      for (int i = 0; i < N_; ++i) {
        Eigen::VectorXd z(D_);
        for (int k = 0; k < D_; ++k) z[k] = normal_(rng_);
        Eigen::VectorXd u = X_.col(i) + scale_ * (L * z);
        const double lu = std::log(U_(rng_));
        if ((u.array() < 0).any() || (u.array() > 1).any()) continue;  // outside the box: density 0
        particle_.push_back(i);
        logu_.push_back(lu);
        us_.push_back(std::move(u));
      }
      accepted += try_moves();
    }
    const double rate = static_cast<double>(accepted) / (kParticleMovesPerStep * N_);
    scale_ *= std::exp(rate - kTargetAcceptance);
  }

  /// One independence move per particle: one joint's scale parameters (`joint_scales`) drawn anew.
  void independence_moves(const std::vector<std::vector<int>>& joint_scales) {
    std::uniform_int_distribution<int> joint(0, static_cast<int>(joint_scales.size()) - 1);
    for (int i = 0; i < N_; ++i) {
      Eigen::VectorXd u = X_.col(i);
      for (int k : joint_scales[static_cast<size_t>(joint(rng_))]) u[k] = U_(rng_);
      particle_.push_back(i);
      logu_.push_back(std::log(U_(rng_)));
      us_.push_back(std::move(u));
    }
    try_moves();
  }

  /// The posterior mean (feasible: the consistent set and the box are convex in these coordinates).
  Eigen::VectorXd posterior_mean() const {
    const Eigen::VectorXd mean = X_.rowwise().mean();
    return problem_.full(mean.data());
  }

 private:
  /// Proposals us_ (unit coordinates) with their amplitudes at their conditional least-squares
  /// values (written back), their full vectors into xs_ and their costs into costs_: one population
  /// (fit_population; no random number is drawn while evaluating, so a pass's proposals are drawn
  /// first and evaluated together, with the results of one by one).
  void fitted() {
    xs_.clear();
    for (const Eigen::VectorXd& u : us_) xs_.push_back(problem_.full(u.data()));
    problem_.fit_population(xs_, means_, vars_);
    costs_.assign(us_.size(), 0.0);
    for (size_t p = 0; p < us_.size(); ++p) {
      us_[p] = problem_.unit(xs_[p]);
      double ls = 0;
      for (size_t j = 0; j < means_[p].size(); ++j) ls += means_[p][j] * means_[p][j] + vars_[p][j];
      costs_[p] = likelihood_scale_ * ls;
    }
  }

  /// One pass of proposals, at most one per particle (particle_[p], proposal us_[p], log u logu_[p]):
  /// Metropolis acceptance of each at the current b (written back with its fitted amplitudes);
  /// infeasible proposals have density 0. Returns the number accepted.
  int try_moves() {
    fitted();
    int taken = 0;
    for (size_t p = 0; p < us_.size(); ++p) {
      const int i = particle_[p];
      if (problem_.violation(xs_[p]) > 0 || !(logu_[p] < -b_ * (costs_[p] - f_[i]))) continue;
      X_.col(i) = us_[p];
      f_[i] = costs_[p];
      ++taken;
    }
    particle_.clear();
    logu_.clear();
    us_.clear();
    return taken;
  }

  const SearchProblem& problem_;
  const int D_, N_;
  std::mt19937_64 rng_;
  std::uniform_real_distribution<double> U_{0.0, 1.0};
  std::normal_distribution<double> normal_{0.0, 1.0};
  const double likelihood_scale_;
  Eigen::MatrixXd X_;  ///< D x N particles, unit coordinates
  Eigen::VectorXd f_;  ///< N costs
  double b_ = 0, scale_ = 2.38 / std::sqrt(static_cast<double>(D_));
  std::vector<Eigen::VectorXd> us_, xs_;
  std::vector<std::vector<double>> means_, vars_;
  std::vector<double> costs_, logu_;
  std::vector<int> particle_;
};

}  // namespace

namespace detail {

Eigen::VectorXd particle_search(const SearchProblem& problem, const OptimiserSettings& options, int& steps) {
  if (options.population < 4 || options.generations < kParticleMovesPerStep) {
    throw InputError("particle filter: >= 4 particles and >= 5 evaluations per particle");
  }
  ParticleSampler sampler(problem, options);
  sampler.draw_initial();
  // Each joint's scale-parameter coordinates (nonlinear models), for the independence moves.
  const std::vector<std::vector<int>> joint_scales = problem.scale_groups();
  const bool independence_moves = !joint_scales.empty();
  steps = options.generations / (kParticleMovesPerStep + (independence_moves ? 1 : 0));
  for (int step = 0; step < steps; ++step) {
    sampler.temper_and_resample();
    sampler.random_walk_moves();
    if (independence_moves) sampler.independence_moves(joint_scales);
  }
  return sampler.posterior_mean();
}

}  // namespace detail

}  // namespace dyncal::host
