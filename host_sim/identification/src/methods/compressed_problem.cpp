#include "compressed_problem.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/normal_quantile.hpp"
#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/identify_result.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"

namespace dyncal::host {
namespace detail {
namespace {
constexpr double kChiSquare95 = 3.84;  ///< 95 % quantile of chi-square with one degree of freedom
}  // namespace

CompressedProblem::CompressedProblem(const ConsistentProblem& p, double range_width) : num_base_(p.num_base), K_(p.K) {
  const Eigen::Index P = p.R.cols(), ns = p.K.cols();
  if (p.R.rows() != P || p.z.size() != P || p.num_base < 1 || p.num_base > P || p.K.rows() != p.num_base ||
      ns % 10 != 0 || p.prior.size() != ns || !(p.sigma2 > 0) || !(range_width > 0)) {
    throw InputError("optimiser search: inconsistent problem shapes");
  }
  others_ = static_cast<int>(P) - p.num_base;
  inv_sigma2_ = 1.0 / p.sigma2;
  const Eigen::MatrixXd R = p.R.triangularView<Eigen::Upper>();
  const Eigen::MatrixXd B = R.leftCols(p.num_base) * p.K;
  if (others_ == 0) {
    B2_ = B;
    c2_ = p.z;
  } else {
    // R_others = Q [R1; 0]: the others' least-squares values given phi are R1^-1 Q1^T (z - B phi),
    // and the residual left is the complement's part Q2^T (z - B phi).
    const Eigen::HouseholderQR<Eigen::MatrixXd> qr(R.rightCols(others_));
    const Eigen::MatrixXd Q = qr.householderQ();
    R1_ = qr.matrixQR().topRows(others_).triangularView<Eigen::Upper>();
    if ((R1_.diagonal().array().abs() <= 1e-12 * R1_.diagonal().cwiseAbs().maxCoeff()).any())
      throw InputError("optimiser search: the model's friction and other terms are not excited (rank deficient)");
    B1_ = Q.leftCols(others_).transpose() * B;
    c1_ = Q.leftCols(others_).transpose() * p.z;
    B2_ = Q.rightCols(P - others_).transpose() * B;
    c2_ = Q.rightCols(P - others_).transpose() * p.z;
  }
  const Eigen::VectorXd cad = nearest_consistent(p.prior);
  const Eigen::VectorXd half = range_width * prior_std(p.prior, 1.0);
  Eigen::VectorXd lo = Eigen::VectorXd::Zero(ns + others_), hi = lo;
  lo.head(ns) = cad - half;
  hi.head(ns) = cad + half;
  set_box(std::move(lo), std::move(hi), std::vector<bool>(static_cast<size_t>(ns + others_), false), cad);
}

double CompressedProblem::least_squares(const double* x, double* grad) const {
  const Eigen::Map<const Eigen::VectorXd> phi(x, num_standard());
  const Eigen::VectorXd r = c2_ - B2_ * phi;
  if (grad) {
    Eigen::Map<Eigen::VectorXd> g(grad, dimension());
    g.setZero();
    g.head(num_standard()) = -2 * inv_sigma2_ * (B2_.transpose() * r);
  }
  return inv_sigma2_ * r.squaredNorm();
}

Eigen::VectorXd CompressedProblem::with_fitted_amplitudes(const Eigen::VectorXd& x, std::vector<double>& mean,
                                                          std::vector<double>& var) const {
  Eigen::VectorXd y = x;
  if (others_ > 0) {
    const Eigen::VectorXd rhs = c1_ - B1_ * x.head(num_standard());
    y.tail(others_) = R1_.triangularView<Eigen::Upper>().solve(rhs);
  }
  mean.assign(1, 0.0);
  var.assign(1, least_squares(x.data(), nullptr));
  return y;
}

Eigen::VectorXd CompressedProblem::data_start() const {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(dimension());
  x.head(num_standard()) = cad();
  std::vector<double> m, v;
  return with_fitted_amplitudes(x, m, v);
}

bool CompressedProblem::memetic_child(const Eigen::VectorXd& x, Eigen::VectorXd& child) const {
  if (violation(x) > 0) return false;
  int evaluations = 0;
  try {
    child = gradient_search(*this, x, kMemeticEvaluations, GradientAlgorithm::ccsaq, evaluations);
  } catch (const InputError&) {
    return false;  // no feasible point found: the best individual stays as it is
  }
  return true;
}

Eigen::VectorXd CompressedProblem::model_parameters(const Eigen::VectorXd& x) const {
  Eigen::VectorXd p(num_base_ + others_);
  p.head(num_base_) = K_ * x.head(num_standard());
  p.tail(others_) = x.tail(others_);
  return p;
}

int CompressedProblem::at_range_end(const Eigen::VectorXd& x) const {
  // A range end binds when moving that parameter alone outwards, to where the cost is least along
  // it, would lower the cost by more than 3.84 (chi-square units, one degree of freedom, 95 %: the
  // convention of the profile-likelihood intervals). The cost is quadratic in the parameter:
  // c(x + t e_i) = c + g_i t + h_ii t^2 / 2, so the gain is g_i^2 / (2 h_ii) when g_i points inwards.
  // A parameter the data determine only in combination with others may sit at an end that costs
  // nothing: that end does not bind.
  Eigen::VectorXd g(dimension());
  least_squares(x.data(), g.data());
  const Eigen::VectorXd u = unit(x);
  int n = 0;
  for (int k = 0; k < free_dimension(); ++k) {
    const int i = free_index(k);
    if (i >= num_standard() || (u[k] > 1e-6 && u[k] < 1 - 1e-6)) continue;
    const double outwards = u[k] >= 0.5 ? 1.0 : -1.0, h = 2 * inv_sigma2_ * B2_.col(i).squaredNorm();
    if (-g[i] * outwards > 0 && h > 0 && g[i] * g[i] / (2 * h) > kChiSquare95) ++n;
  }
  return n;
}

}  // namespace detail

bool is_search_method(const std::string& m) {
  return m == "gd" || m == "ga" || m == "pf";
}

SearchMethod search_method(const std::string& m) {
  if (m == "gd") return SearchMethod::gradient_descent;
  if (m == "ga") return SearchMethod::genetic_algorithm;
  if (m == "pf") return SearchMethod::particle_filter;
  throw InputError("unknown optimiser '" + m + "' (expected gd, ga or pf)");
}

OptimiserSettings search_settings(const IdentifyOptions& o) {
  OptimiserSettings s;
  s.range_width = o.range_width;
  s.seed = o.seed;
  s.max_evaluations = o.search_evaluations > 0 ? o.search_evaluations : kSearchGradientEvaluations;
  if (o.search_evaluations > 0) s.generations = o.search_evaluations;
  return s;
}

namespace {

std::string search_note(const ConsistentSolution& s, const IdentifyOptions& o) {
  char line[400];
  std::snprintf(line, sizeof line,
                "%s: the weighted cost ends %.3g above the least-squares minimum (chi-square units, after %d %s); %d "
                "standard parameter(s) held at an end of the search range (--range-width %.3g)%s",
                o.method.c_str(), s.cost_excess, s.iterations,
                o.method == "gd" ? "cost evaluations" : (o.method == "ga" ? "generations" : "tempering steps"),
                s.at_range_end, o.range_width,
                s.at_range_end > 0 ? ": the range, not the data, limits the fit; widen it" : "");
  return line;
}

}  // namespace

bool is_consistent_method(const std::string& m) {
  return m == "pcls" || is_search_method(m);
}

namespace {

/// Eigen-decomposition of a symmetric positive semi-definite matrix, with what it leaves unseen.
struct Spectrum {
  explicit Spectrum(const Eigen::MatrixXd& H) : es(H) {
    // Numerical rank: a prior's information can be 1e-12 of the data's and is still information.
    tolerance = 1e-14 * std::max(es.eigenvalues().cwiseAbs().maxCoeff(), 1e-300);
  }
  /// Whether g lies in the matrix's range (no component along an eigenvalue below the tolerance).
  bool sees(const Eigen::VectorXd& g) const {
    double unseen = 0;
    for (Eigen::Index i = 0; i < g.size(); ++i)
      if (es.eigenvalues()[i] < tolerance) unseen += std::pow(es.eigenvectors().col(i).dot(g), 2);
    return unseen <= 1e-12 * g.squaredNorm();
  }
  /// g^T H^+ g.
  double quadratic(const Eigen::VectorXd& g) const {
    double q = 0;
    for (Eigen::Index i = 0; i < g.size(); ++i)
      if (es.eigenvalues()[i] >= tolerance) q += std::pow(es.eigenvectors().col(i).dot(g), 2) / es.eigenvalues()[i];
    return q;
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es;
  double tolerance = 0;
};

/// The std of link `link`'s physical quantities `v` (its standard parameters at s.standard[o10..])
/// and what its mass rests on (report_consistent).
void link_intervals(const ConsistentSolution& s, Eigen::Index o10, const std::array<double, 10>& v,
                    LinkInertial& link) {
  // The delta method: cov_physical = J^-1 cov_standard J^-T, J = d standard / d physical; each
  // quantity's gradient in the fit's coordinates g = (J^-1 row k) d standard / d v.
  Eigen::Matrix<double, 10, 10, Eigen::RowMajor> J;
  double again[10];
  standard_from_physical(v, again, J.data());
  const Eigen::Matrix<double, 10, 10> Jinv = Eigen::Matrix<double, 10, 10>(J).inverse();
  const Eigen::Matrix<double, 10, 10> cov = Jinv * s.standard_cov.block(o10, o10, 10, 10) * Jinv.transpose();
  const Eigen::MatrixXd grad = Jinv * s.standard_jacobian.middleRows(o10, 10);  // 10 x inputs
  // range(D + P) = range(D / |D| + P / |P|): each source at its own scale, so that a prior's information
  // is not lost below the rank tolerance of a data block 1e14 times stronger (a prismatic joint's force).
  const auto unit = [](const Eigen::MatrixXd& H) -> Eigen::MatrixXd {
    const double top = H.cwiseAbs().maxCoeff();
    return top > 0 ? Eigen::MatrixXd(H / top) : H;
  };
  const Spectrum fit(unit(s.information_data) + unit(s.information_prior)), data(s.information_data);
  for (int k = 0; k < 10; ++k) {
    const double sd = fit.sees(grad.row(k).transpose()) ? std::sqrt(std::max(0.0, cov(k, k))) : LinkInertial::kNoStd;
    if (k == 0) link.mass_std = sd;
    if (k >= 1 && k <= 3) link.com_std[static_cast<size_t>(k - 1)] = sd;
    if (k >= 4) link.inertia_std[static_cast<size_t>(k - 4)] = sd;
  }
  const Eigen::VectorXd g = grad.row(0).transpose();
  const bool by_data = data.sees(g) && kZ95 * std::sqrt(s.inflation * data.quadratic(g)) < link.mass;
  const bool prior = s.information_prior.cwiseAbs().maxCoeff() > 0.0;
  link.mass_basis = by_data ? "data" : prior ? "prior" : "neither";
}

}  // namespace

void report_consistent(const ConsistentSolution& s, const IdentifyOptions& o, IdentifyResult& res) {
  if (is_search_method(o.method)) res.notes.push_back(search_note(s, o));
  if (o.method == "pcls" && o.prior_std == 0)
    res.notes.push_back(
        "pcls: no prior (--prior-std 0): consistency alone; the standard parameters the data do not determine stay "
        "where the fit leaves them, starting from robot.json's values projected onto the consistent set (only their "
        "base combinations are identified)");
  for (size_t l = 0; l < s.min_eigenvalue.size(); ++l) {
    const std::array<double, 10> v = physical_parameters(s.standard.data() + 10 * l);
    LinkInertial link;
    link.link = static_cast<int>(l) + 1;
    link.mass = v[0];
    link.com = {v[1], v[2], v[3]};
    link.inertia = {v[4], v[5], v[6], v[7], v[8], v[9]};
    link.min_eigenvalue = s.min_eigenvalue[l];
    const auto o10 = static_cast<Eigen::Index>(10 * l);
    if (s.standard_cov.rows() >= o10 + 10) link_intervals(s, o10, v, link);
    res.links.push_back(link);
  }
  for (size_t l = 0; l < s.prior_mass.size() && l < res.links.size(); ++l) {
    const double prior = s.prior_mass[l], mass = res.links[l].mass;
    if (!(std::abs(mass - prior) > o.prior_std * prior)) continue;
    char line[360], sd[40] = "";
    if (std::isfinite(res.links[l].mass_std)) std::snprintf(sd, sizeof sd, " +- %.2g kg (std)", res.links[l].mass_std);
    std::snprintf(line, sizeof line,
                  "warning: pcls moved link %zu's mass from robot.json's %.4g kg to %.4g kg%s, beyond the prior's "
                  "+-%.3g %%: the data, an effect the model lacks, a load or a wrong URDF put it there",
                  l + 1, prior, mass, sd, 100.0 * o.prior_std);
    res.notes.push_back(line);
  }
}

ConsistentSolution search_consistent(const ConsistentProblem& p, SearchMethod method, OptimiserSettings options) {
  options.objective = Objective::least_squares;  // the compressed data carry no per-joint moments (Eq. 25)
  const detail::CompressedProblem problem(p, options.range_width);
  Eigen::VectorXd x;
  int iterations = 0;
  switch (method) {
    case SearchMethod::gradient_descent:
      x = detail::gradient_search(problem, problem.data_start(), options.max_evaluations,
                                  detail::GradientAlgorithm::ccsaq, iterations);
      break;
    case SearchMethod::genetic_algorithm:
      x = detail::genetic_search(problem, options);
      iterations = options.generations;
      break;
    case SearchMethod::particle_filter:
      x = detail::particle_search(problem, options, iterations);
      break;
  }
  std::vector<double> mean, var;
  x = problem.with_fitted_amplitudes(x, mean, var);
  if (!x.allFinite()) throw InputError("optimiser search: the solution is not finite");
  ConsistentSolution s;
  s.params = problem.model_parameters(x);
  s.standard = x.head(problem.num_standard());
  for (int l = 0; l < problem.num_links(); ++l)
    s.min_eigenvalue.push_back(pseudo_inertia_min_eigenvalue(s.standard.data() + 10 * l, nullptr));
  s.iterations = iterations;
  s.at_range_end = problem.at_range_end(x);
  s.cost_excess = problem.least_squares(x.data(), nullptr);
  return s;
}

}  // namespace dyncal::host
