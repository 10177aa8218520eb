#include "dyncal_host/identification/methods/friction_comparison.hpp"

#include <Eigen/Dense>
#include <cctype>
#include <cmath>
#include <iomanip>
#include <ostream>
#include <sstream>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/friction_fit.hpp"
#include "dyncal_host/identification/methods/friction_parameters.hpp"

namespace dyncal::host {
namespace {

/// Mean and sample standard deviation of v.
std::pair<double, double> moments(const Eigen::VectorXd& v) {
  const double mean = v.mean();
  return {mean,
          std::sqrt((v.array() - mean).square().sum() / std::max<double>(1.0, static_cast<double>(v.size() - 1)))};
}

/// The stacked friction columns of `model` at the scale parameters in theta (joint-major, all
/// parameters; the amplitudes' values are not used): column kf j + k is d tau_f,j / d theta_k on
/// joint j's rows (the friction is linear in the amplitudes at fixed scales), zero for a scale
/// parameter.
Eigen::MatrixXd friction_columns(const StackedData& d, FrictionModel model, const std::vector<double>& theta,
                                 const Eigen::VectorXd& load) {
  const int N = static_cast<int>(d.qd.cols()), kf = friction_count(model);
  const Eigen::Index S = d.qd.rows();
  Eigen::MatrixXd F = Eigen::MatrixXd::Zero(S * N, N * kf);
  double g[6];
  for (Eigen::Index s = 0; s < S; ++s) {
    for (int j = 0; j < N; ++j) {
      const Eigen::Index row = s * N + j;
      friction_torque(model, theta.data() + kf * j, d.qd(s, j), load[row], g);
      for (int k = 0; k < kf; ++k) F(row, kf * j + k) = is_scale_parameter(model, k) ? 0.0 : g[k];
    }
  }
  return F;
}

}  // namespace

std::vector<FrictionModelFit> compare_friction_models(const StackedData& stacked, double validate_last) {
  // Keep the non-friction columns.
  StackedData d = stacked;
  std::vector<Eigen::Index> keep;
  std::string others;
  for (size_t c = 0; c < stacked.names.size(); ++c) {
    const std::string& n = stacked.names[c];
    const bool friction = n.size() > 2 && n[0] == 'F' && (n[1] == 'c' || n[1] == 'v' || n[1] == 'p' || n[1] == 'l') &&
                          std::isdigit(static_cast<unsigned char>(n[2]));
    if (friction) continue;
    keep.push_back(static_cast<Eigen::Index>(c));
    if (n.rfind("Ia", 0) == 0 || n.rfind("offset", 0) == 0) others += (others.empty() ? "" : ",") + n;
  }
  d.W.resize(stacked.W.rows(), static_cast<Eigen::Index>(keep.size()));
  for (size_t c = 0; c < keep.size(); ++c) d.W.col(static_cast<Eigen::Index>(c)) = stacked.W.col(keep[c]);
  if (!(validate_last > 0 && validate_last < 1)) throw InputError("compare friction models: validate-last in (0, 1)");
  const int N = static_cast<int>(d.qd.cols());
  const Eigen::Index S = d.qd.rows(),
                     fit_samples = static_cast<Eigen::Index>(std::floor((1 - validate_last) * static_cast<double>(S)));
  if (fit_samples < 10 || S - fit_samples < 10) throw InputError("compare friction models: too few samples");
  const Eigen::Index fit_rows = fit_samples * N, P = d.W.cols();
  Eigen::VectorXd load = Eigen::VectorXd::Zero(S * N);
  // Least squares of [W | F] on the fitted rows; the full residual.
  auto solve = [&](const Eigen::MatrixXd& F, Eigen::VectorXd& coef) {
    Eigen::MatrixXd A(S * N, P + F.cols());
    A << d.W, F;
    coef = A.topRows(fit_rows).colPivHouseholderQr().solve(d.y.head(fit_rows));
    return Eigen::VectorXd(d.y - A * coef);
  };
  std::vector<FrictionModelFit> out;
  Eigen::VectorXd coef7;
  for (FrictionModel model : {FrictionModel::eq7, FrictionModel::eq8, FrictionModel::eq9, FrictionModel::eq4,
                              FrictionModel::eq5, FrictionModel::eq6}) {
    const int kf = friction_count(model);
    std::vector<double> theta(static_cast<size_t>(N * kf), 0.0);
    std::vector<std::vector<ScaleInterval>> intervals;
    if (model == FrictionModel::eq9) load = d.W * coef7.head(P);  // the Eq. 7 fit's non-friction torque
    Eigen::VectorXd coef, residual;
    if (is_linear(model)) {
      residual = solve(friction_columns(d, model, theta, load), coef);
    } else {
      // Separable least squares from the Eq. 7 fit: scan each joint's scales against its
      // non-friction residual, then fit every column at the chosen scales; two rounds.
      Eigen::VectorXd base = coef7.head(P);
      intervals.assign(static_cast<size_t>(N), {});
      for (int round = 0; round < 2; ++round) {
        const Eigen::VectorXd target = d.y - d.W * base;
        for (int j = 0; j < N; ++j) {
          Eigen::VectorXd r(fit_samples), load_j(fit_samples);
          for (Eigen::Index s = 0; s < fit_samples; ++s) {
            r[s] = target[s * N + j];
            load_j[s] = load[s * N + j];
          }
          const Eigen::VectorXd qd = d.qd.col(j).head(fit_samples);
          const std::vector<double> th = fit_joint_friction(
              model, qd, load_j, r, velocity_scale_range(qd.cwiseAbs().maxCoeff()), &intervals[static_cast<size_t>(j)]);
          for (int k = 0; k < kf; ++k) {
            if (is_scale_parameter(model, k)) theta[static_cast<size_t>(kf * j + k)] = th[static_cast<size_t>(k)];
          }
        }
        residual = solve(friction_columns(d, model, theta, load), coef);
        base = coef.head(P);
      }
    }
    if (model == FrictionModel::eq7) coef7 = coef;
    for (int j = 0; j < N; ++j) {
      for (int k = 0; k < kf; ++k) {
        if (!is_scale_parameter(model, k)) theta[static_cast<size_t>(kf * j + k)] = coef[P + kf * j + k];
      }
    }
    FrictionModelFit f;
    f.model = model;
    f.others = others;
    f.parameters = N * kf;
    f.friction = theta;
    f.scale_intervals = intervals;
    std::tie(f.fit_mean, f.fit_std) = moments(residual.head(fit_rows));
    std::tie(f.validation_mean, f.validation_std) = moments(residual.tail(S * N - fit_rows));
    out.push_back(f);
  }
  return out;
}

void print_friction_comparison(std::ostream& out, const std::vector<FrictionModelFit>& fits, double validate_last) {
  out << "friction models fitted with the rigid body and " << (fits.empty() ? "" : fits.front().others)
      << " on the first " << std::fixed << std::setprecision(0) << 100 * (1 - validate_last)
      << " % of the log; torque error [Nm] pooled over the joints\n";
  out << std::left << std::setw(8) << "model" << std::right << std::setw(12) << "parameters" << std::setw(12)
      << "fit mean" << std::setw(12) << "fit std" << std::setw(16) << "held-out mean" << std::setw(15) << "held-out std"
      << "\n";
  const FrictionModelFit* best = nullptr;
  for (const auto& f : fits) {
    out << std::left << std::setw(8) << model_key(f.model) << std::right << std::setw(12) << f.parameters
        << std::setprecision(3) << std::setw(12) << f.fit_mean << std::setw(12) << f.fit_std << std::setw(16)
        << f.validation_mean << std::setw(15) << f.validation_std << "\n";
    if (!best || f.validation_std < best->validation_std) best = &f;
  }
  if (best) out << "lowest held-out std: " << model_key(best->model) << "\n";
  out << "scale parameters of the nonlinear models per joint (95 % profile-likelihood interval on the fitted part;\n"
      << "'<' or '>': the log does not bound it on that side within the searched range)\n";
  for (const auto& f : fits) {
    if (f.scale_intervals.empty()) continue;
    const std::vector<std::string> names = friction_parameter_names(f.model);
    for (size_t k = 0; k < f.scale_intervals.front().size(); ++k) {
      const int p = f.scale_intervals.front()[k].parameter;
      out << std::left << std::setw(8) << model_key(f.model) << std::setw(5) << names[static_cast<size_t>(p)]
          << (is_inverse_velocity(f.model, p) ? "[s/rad]" : "[rad/s]") << std::right;
      for (size_t j = 0; j < f.scale_intervals.size(); ++j) {
        const ScaleInterval& iv = f.scale_intervals[j][k];
        std::ostringstream cell;
        cell << std::setprecision(2) << "  " << (j + 1) << ": " << iv.best << " [" << (iv.open_below ? "<" : "")
             << iv.lo << ", " << (iv.open_above ? ">" : "") << iv.hi << "]";
        out << cell.str();
      }
      out << "\n";
    }
  }
}

}  // namespace dyncal::host
