#pragma once
// What the three optimisers (gradient descent, genetic algorithm, particle filter; survey Sec. 3.4)
// search, for any robot. A decision vector x: the standard parameters of every
// link (10 per link, Khalil-Kleinfinger order, link-major), then the problem's other parameters;
// a box [lo, hi] whose free variables map to the unit box (linearly; logarithmically for scale
// parameters); physical feasibility per link (pseudo-inertia positive definite, Wensing et al.
// 2017); and a least-squares cost whose amplitudes (the parameters the torque is linear in once the
// others are fixed) have a closed-form fit. Two problems derive from it: the survey study's
// (host_sim/survey's BoundedProblem: the study's RunData and a friction model of Eq. 4-9) and identify's
// (CompressedProblem: any robot's weighted data compressed to their triangular factor).

#include <Eigen/Core>
#include <vector>

#include "dyncal_host/identification/methods/optimiser_settings.hpp"

namespace dyncal::host::detail {

class SearchProblem {
 public:
  virtual ~SearchProblem() = default;

  int dimension() const { return static_cast<int>(lo_.size()); }
  int num_links() const { return num_links_; }
  int num_standard() const { return 10 * num_links_; }
  int free_dimension() const { return static_cast<int>(free_.size()); }
  int free_index(int k) const { return free_[static_cast<size_t>(k)]; }
  /// Full decision vector from unit coordinates u (free_dimension()); fixed variables at lo.
  Eigen::VectorXd full(const double* u) const;
  /// Unit coordinates of a full decision vector (clamped into [0, 1]).
  Eigen::VectorXd unit(const Eigen::VectorXd& x) const;
  /// d x / d u of free variable k at x (the range width; x ln(hi / lo) for a scale parameter).
  double scale(int k, const Eigen::VectorXd& x) const;
  /// The box's centre for the standard parameters: the nominal (CAD) values projected onto the
  /// physically consistent set, so the feasible part of the box is never empty.
  const Eigen::VectorXd& cad() const { return cad_; }
  /// Sum over links of max(0, -lambda_min(J_l)) / ||J_l(cad)||_F (0: feasible).
  double violation(const Eigen::VectorXd& x) const;
  /// The margin a strictly feasible solution keeps: lambda_min(J_l) >= 1e-6 ||J_l(cad)||_F.
  double link_margin(int l) const;

  /// Residual groups (joints) the cost sums over.
  virtual int groups() const = 0;
  /// Least-squares cost sum_g mean_g^2 + var_g of the normalised residual; its gradient d/dx
  /// (dimension()) into grad if not null.
  virtual double least_squares(const double* x, double* grad) const = 0;
  /// x with its amplitudes at their least-squares values given the rest of x (clamped into the box
  /// where they are free variables); each group's residual mean and (population) variance there.
  virtual Eigen::VectorXd with_fitted_amplitudes(const Eigen::VectorXd& x, std::vector<double>& mean,
                                                 std::vector<double>& var) const = 0;
  /// with_fitted_amplitudes of every vector of xs (full), in place, with each one's group moments
  /// in means[i], vars[i]: the samplers' population at once. Each result equals the single call's
  /// bit for bit; a problem may order the work for its memory (BoundedProblem: joint by joint).
  virtual void fit_population(std::vector<Eigen::VectorXd>& xs, std::vector<std::vector<double>>& means,
                              std::vector<std::vector<double>>& vars) const;
  /// The negative log-likelihood of the data under the assumed noise, up to a constant, is
  /// likelihood_scale() x the least-squares cost (the particle filter's target).
  virtual double likelihood_scale() const = 0;
  /// A start from the data and the nominal values alone (no set value): the genetic algorithm's
  /// seeded individual.
  virtual Eigen::VectorXd data_start() const = 0;
  /// Each group's scale parameters as free-variable indices (the particle filter's independence
  /// moves); empty when the problem has none.
  virtual std::vector<std::vector<int>> scale_groups() const { return {}; }
  /// The genetic algorithm's memetic step on its best individual x (full): true and the child
  /// written when the problem has one.
  virtual bool memetic_child(const Eigen::VectorXd& x, Eigen::VectorXd& child) const {
    (void)x;
    (void)child;
    return false;
  }

 protected:
  /// The box: lo, hi (dimension entries; lo == hi fixes a variable), whether each variable is
  /// searched on a logarithmic scale (only where lo > 0), the standard parameters' centre `cad`.
  void set_box(Eigen::VectorXd lo, Eigen::VectorXd hi, const std::vector<bool>& logarithmic, Eigen::VectorXd cad);
  const Eigen::VectorXd& lo() const { return lo_; }
  const Eigen::VectorXd& hi() const { return hi_; }

 private:
  int num_links_ = 0;
  Eigen::VectorXd lo_, hi_, cad_;
  std::vector<int> free_;
  std::vector<bool> logarithmic_;  // per free variable
  std::vector<double> cad_norm_;   // ||J_l(cad)||_F per link
};

/// The gradient-based algorithms: NLopt SLSQP (Kraft 1988; the survey study's) or CCSAQ (Svanberg
/// 2002: conservative convex separable quadratic approximations, globally convergent; identify's:
/// on a real robot file's wide, ill-conditioned box SLSQP stalls at its start, TX40 measured).
enum class GradientAlgorithm { slsqp, ccsaq };

/// `algorithm` on the problem's least-squares cost over the free variables (scaled to the unit box)
/// from x0 (full), one inequality lambda_min(J_l) >= link_margin(l) per link with its analytic
/// gradient; at most max_evaluations cost evaluations, added to `evaluations`. The best feasible
/// point evaluated when NLopt stops on an error. Throws InputError when it found none.
Eigen::VectorXd gradient_search(const SearchProblem& problem, const Eigen::VectorXd& x0, int max_evaluations,
                                GradientAlgorithm algorithm, int& evaluations);

/// The real-coded genetic algorithm (the survey's genetic_algorithm, or identify --method ga); returns the best
/// individual (full, amplitudes fitted).
Eigen::VectorXd genetic_search(const SearchProblem& problem, const OptimiserSettings& options);

/// Random-walk Metropolis moves per tempering step of the particle filter.
inline constexpr int kParticleMovesPerStep = 5;
/// The particle filter (the survey's particle_filter, or identify --method pf); returns the posterior mean (full) and
/// the tempering steps run into `steps`.
Eigen::VectorXd particle_search(const SearchProblem& problem, const OptimiserSettings& options, int& steps);

}  // namespace dyncal::host::detail
