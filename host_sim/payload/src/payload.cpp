#include "dyncal_host/payload/payload.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <iomanip>
#include <limits>
#include <nlohmann/json.hpp>
#include <ostream>
#include <sstream>

#include "dyncal/payload_estimator.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/methods/autocorrelation.hpp"
#include "dyncal_host/identification/methods/effect_model.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/inertial_parameters.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host {
namespace {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Vec10 = Eigen::Matrix<double, 10, 1>;
using Mat10 = Eigen::Matrix<double, 10, 10>;

constexpr const char* kStandardNames[10] = {"XX", "XY", "XZ", "YY", "YZ", "ZZ", "MX", "MY", "MZ", "M"};
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

/// The base map's columns of the last link (num_base x 10): a change dphi of its standard
/// parameters moves the base parameters by K_N dphi (the standard parameters are link by link).
MatrixXd last_link_base_map(const CompiledRobot& c) {
  return base_map(c).rightCols(10);
}

/// The weighted least-squares system of the payload columns C on the rows `use` (row s N + j),
/// joint j's rows weighted by w[j]: R (10 x 10, upper triangular, R^T R = A^T A), z (the rotated
/// right-hand side), rss (what no combination of the columns explains) and the rows used.
struct WeightedSystem {
  MatrixXd R;
  VectorXd z;
  double rss = 0;
  long rows = 0;
};

WeightedSystem weighted_system(const MatrixXd& C, const VectorXd& r, const std::vector<char>& use, const VectorXd& w) {
  const int N = static_cast<int>(w.size());
  long n = 0;
  for (char u : use) n += u;
  MatrixXd A(n, 10);
  VectorXd b(n);
  for (Index row = 0, k = 0; row < C.rows(); ++row) {
    if (!use[static_cast<size_t>(row)]) continue;
    A.row(k) = w[row % N] * C.row(row);
    b[k++] = w[row % N] * r[row];
  }
  WeightedSystem s;
  s.rows = n;
  const Eigen::HouseholderQR<MatrixXd> qr(A);
  s.R = qr.matrixQR().topRows(10).triangularView<Eigen::Upper>();
  s.z = (qr.householderQ().transpose() * b).head(10);
  s.rss = std::max(0.0, b.squaredNorm() - s.z.squaredNorm());
  return s;
}

/// Least squares of the kept parameters on the system (the others 0).
Vec10 solve_kept(const WeightedSystem& s, const std::vector<int>& dropped) {
  std::vector<Index> kept;
  for (int i = 0; i < 10; ++i)
    if (std::find(dropped.begin(), dropped.end(), i) == dropped.end()) kept.push_back(i);
  const MatrixXd A = s.R(Eigen::all, kept);
  const VectorXd x = A.colPivHouseholderQr().solve(s.z);
  Vec10 out = Vec10::Zero();
  for (size_t k = 0; k < kept.size(); ++k) out[kept[k]] = x[static_cast<Index>(k)];
  return out;
}

/// Per joint: residual std of the rows `use` of r - C theta (Gautier's weights, joint_noise_std).
VectorXd joint_sigma(const MatrixXd& C, const VectorXd& r, const Vec10& theta, const std::vector<char>& use, int N) {
  VectorXd rss = VectorXd::Zero(N), n = VectorXd::Zero(N);
  for (Index row = 0; row < C.rows(); ++row) {
    if (!use[static_cast<size_t>(row)]) continue;
    const double e = r[row] - C.row(row).dot(theta);
    rss[row % N] += e * e;
    n[row % N] += 1;
  }
  return joint_noise_std(rss, n, 10);
}

std::string fixed(double v, int precision) {
  std::ostringstream s;
  s << std::setprecision(precision) << v;
  return s.str();
}

/// identify_payload's from_current (payload.hpp): the torque constants' relative errors into `cov`
/// (the kept parameters' entries), or a note that they are not in it.
void add_torque_constant_error(const RobotDescription& robot, const ParameterSet& arm, const MatrixXd& C,
                               const VectorXd& theta, const std::vector<char>& use, const VectorXd& w,
                               const std::vector<Index>& kept, Mat10& cov, PayloadResult& res) {
  const int N = robot.num_joints;
  const bool with_std =
      arm.torque_constants.size() == N && arm.torque_constants_std.size() == N && arm.torque_constants_std.allFinite();
  if (!with_std) {
    res.notes.push_back(
        "torque constants: " +
        (arm.torque_constants.size() == N ? arm.torque_constants_source : std::string("robot.json's")) +
        " have no std: their error scales the load's torque and is NOT in the interval below (fit them "
        "with a known load: identify --torque-from current --loaded-data L.csv --load-mass M --params, then "
        "payload with that file)");
    return;
  }
  const MatrixXd T = robot.transmission.size() > 0 ? robot.transmission : MatrixXd::Identity(N, N);
  const MatrixXd to_motor = T.transpose().inverse();  // motor torques u = N^-T tau
  const Index rows = C.rows(), K = static_cast<Index>(kept.size());
  long n_use = 0;
  for (char u : use) n_use += u;
  MatrixXd Ak(n_use, K), G(n_use, N);  // G: per motor, its share of the load's torque (weighted)
  const VectorXd tau_load = C * theta;
  for (Index row = 0, k = 0; row < rows; row += N) {
    const VectorXd u = to_motor * tau_load.segment(row, N);
    for (int j = 0; j < N; ++j) {
      if (!use[static_cast<size_t>(row + j)]) continue;
      for (Index a = 0; a < K; ++a) Ak(k, a) = w[j] * C(row + j, kept[static_cast<size_t>(a)]);
      for (int m = 0; m < N; ++m) G(k, m) = w[j] * T(m, j) * u[m];  // (N^T e_m u_m)_j
      ++k;
    }
  }
  const MatrixXd M = (Ak.transpose() * Ak).ldlt().solve(Ak.transpose() * G);  // K x N: dtheta / d(rel Kt_m)
  VectorXd rel(N);
  for (int m = 0; m < N; ++m) rel[m] = arm.torque_constants_std[m] / std::abs(arm.torque_constants[m]);
  const MatrixXd add = M * rel.cwiseAbs2().asDiagonal() * M.transpose();
  for (Index a = 0; a < K; ++a)
    for (Index b = 0; b < K; ++b) cov(kept[static_cast<size_t>(a)], kept[static_cast<size_t>(b)]) += add(a, b);
  res.torque_constant_error_included = true;
  res.notes.push_back("torque constants: " + arm.torque_constants_source + ", their std (" +
                      fixed(100.0 * rel.maxCoeff(), 2) + " % at most) included in the payload's");
}

/// Covariance of the kept parameters of `fit` (10 x 10, 0 on the dropped ones): sigma2 inflation
/// (R_k^T R_k)^-1; `kept` receives their indices.
Mat10 kept_covariance(const WeightedSystem& sys, const DeterminedFit& fit, double inflation, std::vector<Index>& kept) {
  kept.clear();
  for (int i = 0; i < 10; ++i)
    if (std::find(fit.dropped.begin(), fit.dropped.end(), i) == fit.dropped.end()) kept.push_back(i);
  const MatrixXd Rk = sys.R(Eigen::all, kept);
  const MatrixXd inv = (Rk.transpose() * Rk).ldlt().solve(MatrixXd::Identity(Rk.cols(), Rk.cols()));
  Mat10 cov = Mat10::Zero();
  for (size_t a = 0; a < kept.size(); ++a)
    for (size_t b = 0; b < kept.size(); ++b)
      cov(kept[a], kept[b]) = fit.sigma2 * inflation * inv(static_cast<Index>(a), static_cast<Index>(b));
  return cov;
}

/// Adds the arm's calibration error to `cov` (or notes that the file gives none).
void add_arm_error(const StackedData& d, const ParameterSet& arm, const MatrixXd& C, const std::vector<char>& use,
                   const VectorXd& w, const std::vector<Index>& kept, Mat10& cov, PayloadResult& res) {
  const int N = static_cast<int>(d.q.cols());
  const Index rows = d.t.size() * N;
  // The arm's parameters are a fit too: their error e moves the residual by -X e (X the arm's
  // design, tau_arm = X phi_arm) and the payload by M e, M = (A_k^T A_k)^-1 A_k^T W X (A the
  // weighted payload columns, W the weights). Its covariance M diag(std_arm^2) M^T is added (the
  // file gives no correlations between the arm's parameters: taken as independent).
  res.arm_error_included = arm.stdev.size() == arm.values.size();
  if (res.arm_error_included) {
    const MatrixXd* X = &d.W;
    MatrixXd with_effects;
    if (!arm.effects.empty()) {
      with_effects = model_design(d, arm.effects, arm.values, arm.tau_model_reference);
      X = &with_effects;
    }
    long n_use = 0;
    for (char u : use) n_use += u;
    MatrixXd Ak(n_use, static_cast<Index>(kept.size())), Xw(n_use, X->cols());
    for (Index row = 0, k = 0; row < rows; ++row) {
      if (!use[static_cast<size_t>(row)]) continue;
      const double wj = w[row % N];
      for (size_t a = 0; a < kept.size(); ++a) Ak(k, static_cast<Index>(a)) = wj * C(row, kept[a]);
      Xw.row(k++) = wj * X->row(row);
    }
    const MatrixXd M = (Ak.transpose() * Ak).ldlt().solve(Ak.transpose() * Xw);
    VectorXd var_arm(arm.stdev.size());
    int unknown = 0;
    for (Index i = 0; i < var_arm.size(); ++i) {
      const bool known = std::isfinite(arm.stdev[i]);
      unknown += !known && arm.values[i] == 0.0;
      var_arm[i] = known ? arm.stdev[i] * arm.stdev[i] : 0.0;
    }
    const MatrixXd cov_arm = M * var_arm.asDiagonal() * M.transpose();
    for (size_t a = 0; a < kept.size(); ++a)
      for (size_t b = 0; b < kept.size(); ++b)
        cov(kept[a], kept[b]) += cov_arm(static_cast<Index>(a), static_cast<Index>(b));
    if (unknown > 0)
      res.notes.push_back(std::to_string(unknown) +
                          " of the arm's parameters were not determined by its calibration (held at 0, no std): "
                          "where this log excites them, the payload takes their share");
  } else {
    res.notes.push_back(arm.source +
                        " gives no standard deviations: the payload's std covers this log's noise only, not the "
                        "arm's calibration error");
  }
}

/// The payload's mass, centre of mass and inertia about it with their std and verdicts (res.quantities,
/// res.inertia_determined) from res.standard and its covariance; returns the mass [kg].
double add_physical_quantities(const DeterminedFit& fit, const Mat10& cov, const double* nominal, PayloadResult& res) {
  // Mass, centre of mass and inertia about it (Table 5's parametrisation) with the delta method:
  // cov_physical = J^-1 cov J^-T, J = d standard / d physical (standard_from_physical).
  const std::array<double, 10> phys = physical_parameters(res.standard.data());
  Eigen::Matrix<double, 10, 10, Eigen::RowMajor> J;
  Vec10 again;
  standard_from_physical(phys, again.data(), J.data());
  const Mat10 Jinv = Mat10(J).inverse();
  const Mat10 cov_phys = Jinv * cov * Jinv.transpose();
  auto is_dropped = [&](int i) { return std::find(fit.dropped.begin(), fit.dropped.end(), i) != fit.dropped.end(); };
  const double m = phys[0];
  Vec10 fit_scale;  // the quantities' scales use the final fit's lever
  const double lever_fit = dyncal::payload_scales(Vec10(res.standard), nominal, fit_scale);
  const char* names[10] = {"mass", "com_x", "com_y", "com_z", "I11", "I12", "I13", "I22", "I23", "I33"};
  const char* units[10] = {"kg", "m", "m", "m", "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2"};
  const bool mass_kept = !is_dropped(9);
  res.inertia_determined = true;
  for (int k = 0; k < 10; ++k) {
    PayloadQuantity q;
    q.name = names[k];
    q.unit = units[k];
    // What each quantity needs: the mass; a coordinate, its first moment too; an inertia entry, its
    // entry about the origin and the whole centre of mass.
    bool available = mass_kept;
    if (k >= 1 && k <= 3) available = available && !is_dropped(5 + k);
    if (k >= 4) available = available && !is_dropped(k - 4) && !is_dropped(6) && !is_dropped(7) && !is_dropped(8);
    q.scale = k == 0 ? std::abs(m) : (k <= 3 ? lever_fit : std::abs(m) * lever_fit * lever_fit);
    if (available) {
      q.std = std::sqrt(std::max(0.0, cov_phys(k, k)));
      q.verdict = verdict_of(q.std, q.scale);
      // A quantity whose 95 % interval is wider than its scale is not printed as a value; its std is.
      q.value = q.verdict == Verdict::not_determined ? kNan : phys[static_cast<size_t>(k)];
    } else {
      q.value = kNan;
      q.std = kNan;
      q.verdict = Verdict::not_determined;
    }
    if (k >= 4 && q.verdict == Verdict::not_determined) res.inertia_determined = false;
    res.quantities.push_back(q);
  }
  return m;
}

/// Refuses a payload without a determined, positive mass (InputError); notes whether its inertia is
/// physically consistent or not determined.
void check_physical(double m, int N, PayloadResult& res) {
  const PayloadQuantity& mass = res.quantities[0];
  if (mass.verdict == Verdict::not_determined) {
    std::ostringstream s;
    s << std::setprecision(3) << "payload: the log does not determine the payload's mass";
    if (std::isfinite(mass.std))
      s << " (" << m << " kg, 95 % " << m - kVerdictZ * mass.std << ".." << m + kVerdictZ * mass.std
        << ": 0 is inside)";
    s << ": no load to speak of on link " << N << ", or too little motion with it";
    throw InputError(s.str());
  }
  if (m < 0) {
    std::ostringstream s;
    s << std::setprecision(3) << "payload: the log's torque beyond the arm's model needs a negative mass (" << m
      << " +- " << mass.std << " kg): the parameter file does not describe this arm (another arm, or it changed)";
    throw InputError(s.str());
  }
  if (res.inertia_determined) {
    res.min_eigenvalue =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(pseudo_inertia(res.standard.data())).eigenvalues().minCoeff();
    if (!(res.min_eigenvalue > 0))
      res.notes.push_back(
          "the payload's inertia about its centre of mass is not physically consistent (smallest "
          "pseudo-inertia eigenvalue " +
          fixed(res.min_eigenvalue, 3) + "): no rigid body has it; the arm's model error may be in it");
  } else {
    res.notes.push_back(
        "inertia about the centre of mass: not determined by this log (too little acceleration and "
        "rotation of the last link); its entries are held at 0 in the loaded model, which then "
        "carries the payload as a point mass at its centre of mass");
  }
}

/// res.unloaded, res.loaded: the prediction error of the arm's model alone, and with the payload fitted
/// out of fold (blocked folds as identify's; the parameters `dropped` held at 0 in every fold).
void out_of_fold_errors(const StackedData& d, const MatrixXd& C, const VectorXd& r, const VectorXd& tau_arm,
                        const std::vector<char>& use, const VectorXd& w, const std::vector<int>& dropped,
                        const IdentifyOptions& options, const VectorXd& tau_max, PayloadResult& res) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size(), rows = S * N;
  std::vector<char> none(static_cast<size_t>(rows), 0);
  VectorXd before = tau_arm, after = VectorXd::Constant(rows, kNan);
  const Index block = std::max<Index>(1, std::lround(options.block_seconds * d.rate_hz));
  for (int f = 0; f < options.folds; ++f) {
    std::vector<char> train = use;
    for (Index s = 0; s < S; ++s)
      if ((s / block) % options.folds == f)
        for (int j = 0; j < N; ++j) train[static_cast<size_t>(s * N + j)] = 0;
    const WeightedSystem fs = weighted_system(C, r, train, w);
    const Vec10 theta = solve_kept(fs, dropped);
    for (Index s = 0; s < S; ++s)
      if ((s / block) % options.folds == f)
        for (int j = 0; j < N; ++j) after[s * N + j] = tau_arm[s * N + j] + C.row(s * N + j).dot(theta);
  }
  for (Index row = 0; row < rows; ++row)
    if (!use[static_cast<size_t>(row)]) before[row] = after[row] = kNan;
  res.unloaded = torque_metrics(d.y, before, N, tau_max);
  res.loaded = torque_metrics(d.y, after, N, tau_max);
}

}  // namespace

PayloadResult identify_payload(const RobotDescription& robot, const JointLog& log, const ParameterSet& arm,
                               const IdentifyOptions& options, bool from_current) {
  const StackedData d = prepare_stacked(robot, log, prediction_options(robot, options, arm));
  const CompiledRobot& compiled = compiled_robot_for(robot);
  const int N = robot.num_joints;
  const Index S = d.t.size(), rows = S * N;
  PayloadResult res;
  res.robot = robot.name;
  res.model = arm.model;
  res.params_source = arm.source;
  res.log_source = log.source;
  res.link = N;
  res.samples = static_cast<long>(S);
  res.notes = d.notes;
  const VectorXd tau_arm = predicted_torque(d, arm);
  const VectorXd r = d.y - tau_arm;
  // The payload's columns: Y_b K_N (the torque of a unit change of each of link N's parameters).
  const MatrixXd C = d.W.leftCols(d.num_base) * last_link_base_map(compiled);
  std::vector<char> use(static_cast<size_t>(rows), 1);
  if (!d.fit_row.empty()) use = d.fit_row;

  // Gautier's weights from a first (unweighted) fit's residual; its mass and centre of mass set the
  // verdicts' scales.
  const Vec10 first = solve_kept(weighted_system(C, r, use, VectorXd::Ones(N)), {});
  const VectorXd w = joint_sigma(C, r, first, use, N).cwiseInverse();
  const WeightedSystem sys = weighted_system(C, r, use, w);
  const Vec10 second = solve_kept(sys, {});
  // The verdicts' scales (lib/ payload_scales, docs/payload.md): the mass against itself, a first
  // moment against m l, an inertia entry against m l^2, l the payload's lever.
  const double* nominal = compiled.nominal_standard.data() + 10 * (N - 1);
  Vec10 scale10;
  const double lever = dyncal::payload_scales(second, nominal, scale10);
  if (!(std::abs(second[9]) > 0) || !(lever > 0))
    throw InputError("payload: the log shows no load on link " + std::to_string(N) +
                     " (its torque beyond the arm's model has no mass component)");
  const VectorXd scale = scale10;
  VectorXd residual = r - C * second;
  std::vector<char> all(static_cast<size_t>(S), 1);
  res.inflation = autocorrelation_inflation(d, all, residual);
  DeterminedFit fit;
  try {
    fit = determined_least_squares(sys.R, sys.z, sys.rss, sys.rows, scale, res.inflation);
  } catch (const InputError&) {
    throw InputError("payload: the log determines none of the payload's parameters (too little motion with the load)");
  }
  for (int i : fit.dropped) res.undetermined.push_back(kStandardNames[i]);
  // Covariance of the kept parameters: sigma2 inflation (R_k^T R_k)^-1.
  std::vector<Index> kept;
  Mat10 cov = kept_covariance(sys, fit, res.inflation, kept);
  add_arm_error(d, arm, C, use, w, kept, cov, res);
  if (from_current) add_torque_constant_error(robot, arm, C, fit.phi, use, w, kept, cov, res);
  for (int i = 0; i < 10; ++i) {
    const bool dropped = std::find(fit.dropped.begin(), fit.dropped.end(), i) != fit.dropped.end();
    res.standard[i] = dropped ? 0.0 : fit.phi[i];
    res.standard_std[i] = dropped ? kNan : std::sqrt(cov(i, i));
  }

  const double m = add_physical_quantities(fit, cov, nominal, res);
  check_physical(m, N, res);
  if (!fit.dropped.empty())
    res.notes.push_back("held at 0: " +
                        dropped_parameters_text(fit, {std::begin(kStandardNames), std::end(kStandardNames)}));

  // The prediction error on this log: the arm's model alone, and with the payload fitted out of fold.
  out_of_fold_errors(d, C, r, tau_arm, use, w, fit.dropped, options, robot.tau_max, res);
  return res;
}

ParameterSet with_payload(const ParameterSet& arm, const RobotDescription& robot, const Vec10& payload_standard) {
  const CompiledRobot& compiled = compiled_robot_for(robot);
  ParameterSet p = arm;
  p.values.head(compiled.num_base) += last_link_base_map(compiled) * payload_standard;
  p.stdev.resize(0);  // the arm's std no longer describes the loaded base parameters
  p.links.clear();    // nor its links' inertials the last link (a payload part may be undetermined)
  p.source = arm.source + " with a payload on link " + std::to_string(robot.num_joints);
  return p;
}

nlohmann::json loaded_parameter_file_json(const ParameterSet& loaded, const PayloadResult& r) {
  nlohmann::json j = parameter_file_json(loaded, "payload");
  j["source"] = loaded.source;
  j["payload"] = payload_report_json(r);
  return j;
}

void print_payload_report(std::ostream& out, const PayloadResult& r) {
  out << "dyncal payload: robot " << r.robot << ", arm model " << r.model << " (" << r.params_source << "), log "
      << r.log_source << ", " << r.samples << " samples; the payload on link " << r.link << " in its frame\n";
  for (const std::string& n : r.notes) out << "note: " << n << "\n";
  out << "\nquantity         value          std     95 % interval              verdict (1.96 std against scale)\n";
  for (const PayloadQuantity& q : r.quantities) {
    out << std::left << std::setw(6) << q.name << std::right << std::setw(8) << ("[" + q.unit + "]");
    if (!std::isfinite(q.value)) {
      out << std::setw(13) << "-" << std::setprecision(5) << std::setw(13);
      if (std::isfinite(q.std))
        out << q.std;
      else
        out << "-";
      out << std::setw(27) << "-"
          << "  not determined";
      if (std::isfinite(q.std)) out << " (scale " << std::setprecision(3) << q.scale << ")";
      out << "\n";
      continue;
    }
    std::ostringstream interval;
    interval << std::setprecision(4) << q.value - kVerdictZ * q.std << ".." << q.value + kVerdictZ * q.std;
    out << std::setprecision(5) << std::setw(13) << q.value << std::setw(13) << q.std << std::setw(27) << interval.str()
        << "  " << to_string(q.verdict) << " (scale " << std::setprecision(3) << q.scale << ")\n";
  }
  out << "\njoint   RMS arm model   with the payload (out of fold) [Nm]   R2 before   after\n" << std::fixed;
  for (size_t j = 0; j < r.loaded.size(); ++j)
    out << std::setw(5) << j + 1 << std::setprecision(4) << std::setw(16) << r.unloaded[j].rms << std::setw(28)
        << r.loaded[j].rms << std::setw(22) << r.unloaded[j].r2 << std::setw(8) << r.loaded[j].r2 << "\n";
  out << std::defaultfloat;
}

nlohmann::json payload_report_json(const PayloadResult& r) {
  auto number = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  nlohmann::json j;
  j["robot"] = r.robot;
  j["model"] = r.model;
  j["params"] = r.params_source;
  j["log"] = r.log_source;
  j["samples"] = r.samples;
  j["link"] = r.link;
  j["notes"] = r.notes;
  j["autocorrelation_inflation"] = r.inflation;
  j["std_includes_arm_calibration"] = r.arm_error_included;
  j["quantities"] = nlohmann::json::array();
  for (const PayloadQuantity& q : r.quantities)
    j["quantities"].push_back({{"name", q.name},
                               {"unit", q.unit},
                               {"value", number(q.value)},
                               {"std", number(q.std)},
                               {"scale", q.scale},
                               {"verdict", to_string(q.verdict)}});
  nlohmann::json standard = nlohmann::json::array();
  for (int i = 0; i < 10; ++i)
    standard.push_back({{"name", kStandardNames[i]}, {"value", r.standard[i]}, {"std", number(r.standard_std[i])}});
  j["standard_parameters"] = standard;
  j["not_determined"] = r.undetermined;
  j["torque_constant_error_included"] = r.torque_constant_error_included;
  j["inertia_determined"] = r.inertia_determined;
  if (r.inertia_determined) j["pseudo_inertia_min_eigenvalue"] = r.min_eigenvalue;
  j["joints"] = nlohmann::json::array();
  for (size_t k = 0; k < r.loaded.size(); ++k)
    j["joints"].push_back({{"joint", k + 1},
                           {"rms_arm_model", r.unloaded[k].rms},
                           {"rms_with_payload", r.loaded[k].rms},
                           {"r2_arm_model", r.unloaded[k].r2},
                           {"r2_with_payload", r.loaded[k].r2}});
  return j;
}

}  // namespace dyncal::host
