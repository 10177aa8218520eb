#pragma once
// Physically consistent weighted least squares for any robot (identify --method pcls): the base
// parameters are K phi, phi the standard parameters of every link with its pseudo-inertia positive
// definite by construction (log-Cholesky, log_cholesky.hpp; Wensing et al. 2017, Rucker and Wensing
// 2022), the model's other parameters (friction, rotor inertia, offsets) free; maximum a posteriori
// with a Gaussian prior on phi centred on the robot file's nominal inertials, which decides only the
// directions of phi the data cannot see. Solved by Levenberg-Marquardt on the data compressed to
// its triangular factor (P rows, not the log's).

#include <Eigen/Core>
#include <string>
#include <vector>

#include "dyncal_host/identification/methods/optimiser_settings.hpp"

namespace dyncal::host {

/// Relative standard deviation of the nominal (CAD) inertials in the prior: each standard
/// parameter within +-50 % (1 sigma) of max(|value|, 5 % of the largest of its kind in the link:
/// inertia, first moment, mass). Weak beside a log's thousands of samples on what they identify.
inline constexpr double kPriorRelativeStd = 0.5;

struct ConsistentProblem {
  Eigen::MatrixXd R;      ///< P x P upper triangular: R^T R = W^T W of the weighted data (StreamingLeastSquares)
  Eigen::VectorXd z;      ///< P: the rotated right-hand side, ||W p - y||^2 = ||R p - z||^2 + const
  int num_base = 0;       ///< the first num_base of the P model parameters are base parameters
  Eigen::MatrixXd K;      ///< num_base x 10 L: base parameters of the standard ones (Gautier)
  Eigen::VectorXd prior;  ///< 10 L nominal standard parameters (robot.json inertials)
  double prior_relative_std = kPriorRelativeStd;  ///< <= 0: no prior (consistency alone)
  /// 10 L x 10 L, block diagonal (10 x 10 per link), or empty. When given, the prior is the
  /// Gaussian N(prior, (W^T W)^-1), W = prior_whitening, its residual W (phi - prior) (the survey
  /// study's seeded CAD prior), and prior_relative_std is not used.
  Eigen::MatrixXd prior_whitening;
  /// Variance of the weighted residual per row: the data rows weigh 1 / sigma2 against the prior
  /// and set the parameters' standard deviations (identify: the WLS residual's variance).
  double sigma2 = 1;
  /// Indices (>= num_base) of parameters held >= 0 (friction, rotor inertia): fitted as squares.
  std::vector<int> nonnegative;
  Eigen::VectorXd start;              ///< P: start of the non-inertial parameters (e.g. the WLS solution); empty: 0
  int max_evaluations = 400;          ///< Levenberg-Marquardt's cost evaluations at most
  double relative_tolerance = 1e-12;  ///< its tolerance on the cost and on the solution (MINPACK ftol, xtol)
};

struct ConsistentSolution {
  Eigen::VectorXd params;              ///< P model parameters (base ones = K standard)
  Eigen::VectorXd params_std;          ///< their standard deviations (Gauss-Newton at the solution, sigma2)
  Eigen::VectorXd standard;            ///< 10 L consistent standard parameters
  std::vector<double> min_eigenvalue;  ///< per link, of its pseudo-inertia (> 0: consistent)
  /// consistent_least_squares: the solution's log-Cholesky coordinates (10 L, log_cholesky.hpp).
  Eigen::VectorXd theta;
  /// consistent_least_squares with a prior: per link, the prior's mass [kg] (robot.json's), which
  /// report_consistent compares the fitted mass with.
  std::vector<double> prior_mass;
  /// consistent_least_squares: the 10 L x 10 L covariance of `standard` (consistent_covariance);
  /// empty for the searches.
  Eigen::MatrixXd standard_cov;
  /// consistent_least_squares: at the solution, in its coordinates v (log-Cholesky, then the other
  /// parameters), the Gauss-Newton matrices of the data's rows (in units of sigma2) and of the
  /// prior's, and the Jacobians of the model parameters and of the standard ones in v.
  Eigen::MatrixXd information_data, information_prior, model_jacobian, standard_jacobian;
  double inflation = 1;  ///< the data's noise factor consistent_covariance last used
  int iterations = 0;
  /// search_consistent: standard parameters that end at an end of their range (within 1e-6 of its
  /// width) that binds: moving that parameter alone outwards to where the cost is least along it
  /// would lower the cost by more than 3.84 chi-square units (95 %, one degree of freedom).
  int at_range_end = 0;
  /// search_consistent: ||R params - z||^2 / sigma2, the weighted cost above its least-squares
  /// minimum (chi-square units).
  double cost_excess = 0;
};

/// The parameters among names[num_base..] that physics keeps >= 0 in a consistent fit: each
/// motor's Coulomb and viscous friction and rotor inertia (Fc<j>, Fv<j>, Ia<j>, as identify names
/// them); not effect terms (an asymmetric difference Fc+<j> has either sign).
std::vector<int> nonnegative_terms(const std::vector<std::string>& names, int num_base);

/// Solves `p`. Throws InputError when Levenberg-Marquardt fails or ends non-finite. params_std and
/// standard_cov are consistent_covariance(s, 1).
ConsistentSolution consistent_least_squares(const ConsistentProblem& p);

/// Sets s.params_std and s.standard_cov of a consistent_least_squares solution from the sandwich
/// covariance of v, H^+ (inflation D + Q) H^+ with D, Q its information_data and information_prior
/// and H = D + Q: the data's noise `inflation` times their white variance (the residual's
/// autocorrelation, S / n_eff), the prior's as it is; propagated through model_jacobian and
/// standard_jacobian.
void consistent_covariance(ConsistentSolution& s, double inflation);

/// The survey's optimisers (Sec. 3.4; optimisers.hpp) on the same weighted problem as
/// consistent_least_squares, for any robot (identify --method gd|ga|pf). They search the 10 L
/// standard parameters phi within nominal +- options.range_width x prior_std(nominal, 1) (every
/// parameter within range_width of max(|value|, 5 % of the largest of its kind in the link)), centred
/// on the nominal values projected onto the consistent set, with every link's pseudo-inertia
/// positive definite (Wensing et al. 2017); no prior. The model's other parameters (friction, rotor
/// inertia, offsets, effects), in which the torque is linear, take their least-squares values given
/// phi (variable projection, Golub and Pereyra 1973), unbounded as in WLS. Cost: ||R p - z||^2 /
/// sigma2, p = [K phi; the others] (the weighted residual's sum of squares less its least-squares
/// minimum); the particle filter's target is exp(-cost / 2); the genetic algorithm's cost is this one
/// (options.objective is ignored: the compressed data keep no per-joint means for Eq. 25).
/// Deterministic for options.seed.
/// Gradient-based: NLopt CCSAQ (Svanberg 2002) from the consistent nominal values (SLSQP, the
/// survey's, stalls at its start on a real robot file's wide box); genetic algorithm and particle
/// filter as in optimisers.hpp, the former seeded with that start.
/// params_std is left empty (the caller's least-squares statistics apply: the model is linear);
/// iterations: cost evaluations (gradient), generations (genetic), tempering steps (particle).
enum class SearchMethod { gradient_descent, genetic_algorithm, particle_filter };
/// identify's method names of the optimisers: gd, ga, pf.
bool is_search_method(const std::string& method);
/// The optimiser of gd, ga or pf; throws InputError on another name.
SearchMethod search_method(const std::string& method);
ConsistentSolution search_consistent(const ConsistentProblem& p, SearchMethod method, OptimiserSettings options);

/// Cost evaluations of identify's gradient-based search when IdentifyOptions::search_evaluations is 0.
inline constexpr int kSearchGradientEvaluations = 20000;

struct IdentifyOptions;
struct IdentifyResult;
/// identify's settings of search_consistent: --range-width, --seed, --evaluations (IdentifyOptions).
OptimiserSettings search_settings(const IdentifyOptions& options);
/// identify's report of a consistent fit (pcls, gd, ga, pf) into res: each link's inertials
/// (res.links: mass, centre of mass, inertia about it, smallest pseudo-inertia eigenvalue; for pcls
/// their std from standard_cov by the delta method through d standard / d physical, NaN for a
/// quantity neither the data nor the prior fix (its gradient outside the range of the fit's
/// Gauss-Newton matrix), and what the mass rests on: "data" when the data alone put 0 outside its 95 %
/// interval, else "prior" with a prior, else "neither"); for pcls
/// a warning per link whose mass the fit moved beyond the prior's standard deviation (--prior-std
/// of robot.json's mass: the data, an effect the model lacks, a load or a wrong URDF put it there); for a
/// search, a note with the cost above least squares' minimum and the parameters the search range
/// limited; for pcls without a prior, a note that only base combinations are identified.
void report_consistent(const ConsistentSolution& s, const IdentifyOptions& options, IdentifyResult& res);
/// True for the methods that fit physically consistent inertials: pcls, gd, ga, pf.
bool is_consistent_method(const std::string& method);

/// Prior standard deviation of each of the 10 L standard parameters of `nominal` (see
/// kPriorRelativeStd); a kind that is zero in a link takes the robot's largest of that kind as its
/// scale (and 1 if zero everywhere).
Eigen::VectorXd prior_std(const Eigen::VectorXd& nominal, double relative_std);

}  // namespace dyncal::host
