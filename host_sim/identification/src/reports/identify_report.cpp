#include "dyncal_host/identification/reports/identify_report.hpp"

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/common/spline_basis.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"

namespace dyncal::host {
namespace {

std::string format(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

/// The per-joint validation table of identify and predict.
void print_joint_table(std::ostream& out, const std::vector<JointMetrics>& joints) {
  out << "joint   RMS [Nm]   rel. RMS      R^2   e_T_abs e_T_abs_std RMS tau [Nm]\n";
  for (const auto& j : joints) {
    char line[160];
    std::snprintf(line, sizeof line, "%5d %10.4f %10.4f %8.4f %9.5f %10.5f %14.4f\n", j.joint, j.rms, j.relative_rms,
                  j.r2, j.e_T_abs, j.e_T_abs_std, j.rms_tau);
    out << line;
  }
}

}  // namespace

void print_identify_report(std::ostream& out, const IdentifyResult& r) {
  out << "dyncal identify: robot " << r.robot << ", method " << r.method << ", model " << r.model << "\n";
  out << "data: " << r.data_source << ", " << r.samples_used << " samples used at "
      << format("%.0f", r.decimated_rate_hz) << " Hz (from " << format("%.0f", r.sample_rate_hz)
      << " Hz; zero-phase Butterworth " << format("%g", r.cutoff_hz) << " Hz, parallel decimation)\n";
  out << "validation: " << r.validation << " (every sample predicted by a fit that did not see it)\n\n";
  print_joint_table(out, r.joints);
  if (!r.prismatic_joints.empty()) {
    out << "prismatic joint" << (r.prismatic_joints.size() > 1 ? "s" : "");
    for (const int j : r.prismatic_joints) out << " " << j;
    out << ": torques are forces [N] (RMS, Fc), Fv [N s/m], Ia [kg], q [m]\n";
  }
  out << "\nregressor condition number cond(W): " << format("%.4g", r.condition_number) << "; full-data fit in "
      << format("%.3f", r.fit_seconds) << " s\n";
  out << "\nparameter                   value        std    std %      scale  verdict (95 % interval against the "
         "scale: docs/accuracy.md \"Real arms\")\n";
  for (const auto& p : r.params) {
    char line[240];
    if (p.verdict == Verdict::not_determined && std::isfinite(p.data_share)) {
      // The MAP value with its posterior std, and how much of it the log contributed.
      std::snprintf(line, sizeof line,
                    "%-20s %12.5g %10.3g %8s %10.3g  not determined by the log: MAP with the prior "
                    "(data share %.0f %%)\n",
                    p.name.c_str(), p.value, p.std, "-", p.scale, 100.0 * p.data_share);
    } else if (p.basis == "sign constraint") {
      std::snprintf(line, sizeof line,
                    "%-20s %12s %10s %8s %10.3g  held at 0 by the sign constraint (the free fit "
                    "gives < 0)\n",
                    p.name.c_str(), "0", "-", "-", p.scale);
    } else if (p.verdict == Verdict::not_determined && p.basis == "prior" && !std::isfinite(p.std)) {
      // iv: held at robot.json's value, which the fit kept the determined combination around.
      std::snprintf(line, sizeof line, "%-20s %12.5g %10s %8s %10.3g  not determined: held at robot.json's value\n",
                    p.name.c_str(), p.value, "-", "-", p.scale);
    } else if (p.verdict == Verdict::not_determined) {
      // Never a free number: what the value rests on instead.
      std::snprintf(line, sizeof line, "%-20s %12s %10.3g %8s %10.3g  not determined (%s)\n", p.name.c_str(),
                    p.basis == "held at 0" ? "0" : "-", p.std, "-", p.scale, p.basis.c_str());
    } else {
      const double rel = p.value != 0.0 ? 100.0 * p.std / std::abs(p.value) : INFINITY;
      // A value its own 95 % interval does not tell from 0 says so.
      const bool zero_within = std::abs(p.value) <= kVerdictZ * p.std;
      std::snprintf(line, sizeof line, "%-20s %12.5g %10.3g %8.1f %10.3g  %s%s\n", p.name.c_str(), p.value, p.std, rel,
                    p.scale,
                    p.contradicts_physics ? "contradicts physics: below 0 beyond its 95 % interval"
                    : p.scale > 0.0       ? to_string(p.verdict)
                                          : "not judged",
                    zero_within ? ", 0 within its 95 % interval" : "");
    }
    out << line;
  }
  if (!r.links.empty()) {
    out << "\nconsistent inertials per link (link frame; inertia about the centre of mass), pseudo-inertia's "
           "smallest eigenvalue\n";
    out << "link   mass [kg]   com x y z [m]                    I11 I12 I13 I22 I23 I33 [kg m^2]"
           "                                  lambda_min\n";
    for (const auto& l : r.links) {
      char line[320];
      std::snprintf(line, sizeof line,
                    "%4d %11.4g   %9.4g %9.4g %9.4g   %10.4g %10.4g %10.4g %10.4g %10.4g %10.4g   %10.3g\n", l.link,
                    l.mass, l.com[0], l.com[1], l.com[2], l.inertia[0], l.inertia[1], l.inertia[2], l.inertia[3],
                    l.inertia[4], l.inertia[5], l.min_eigenvalue);
      out << line;
      if (l.mass_basis.empty()) continue;
      // Their std ("-": neither the data nor a prior fix it) and what the mass rests on.
      const auto sd = [](double v, int width) {
        char b[32];
        if (std::isfinite(v))
          std::snprintf(b, sizeof b, "%*.2g", width, v);
        else
          std::snprintf(b, sizeof b, "%*s", width, "-");
        return std::string(b);
      };
      out << "     +- " << sd(l.mass_std, 8) << "   " << sd(l.com_std[0], 9) << " " << sd(l.com_std[1], 9) << " "
          << sd(l.com_std[2], 9) << "  ";
      for (double v : l.inertia_std) out << " " << sd(v, 10);
      out << (l.mass_basis == "neither" ? "   (std; mass fixed by neither the data nor a prior)\n"
                                        : "   (std; mass from the " + l.mass_basis + ")\n");
    }
  }
  for (const auto& o : r.other_logs) print_log_prediction(out, o);
  for (const auto& n : r.notes) out << "note: " << n << "\n";
}

void print_log_prediction(std::ostream& out, const LogPrediction& p) {
  out << "\nprediction of another log (no sample of it fitted): " << p.source << ", " << p.samples << " samples\n";
  print_joint_table(out, p.joints);
  for (const auto& n : p.notes) out << "note (" << p.source << "): " << n << "\n";
}

nlohmann::json joint_metrics_json(const std::vector<JointMetrics>& joints) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& m : joints) {
    a.push_back({{"joint", m.joint},
                 {"rms_validation", m.rms},
                 {"relative_rms_validation", m.relative_rms},
                 {"r2_validation", m.r2},
                 {"e_T_abs", m.e_T_abs},
                 {"e_T_abs_std", m.e_T_abs_std},
                 {"rms_tau", m.rms_tau}});
  }
  return a;
}

nlohmann::json log_prediction_json(const LogPrediction& p) {
  return {{"data", p.source}, {"samples", p.samples}, {"joints", joint_metrics_json(p.joints)}, {"notes", p.notes}};
}

namespace {

/// Each shape of the model fitted (model_effects.hpp): its joint, variable, item and curve (torque
/// [Nm] against the variable at kShapeCurvePoints points over its knots' span, as diagnose reports
/// a shape found).
nlohmann::json fitted_shapes_json(const IdentifyResult& r) {
  nlohmann::json out = nlohmann::json::array();
  ModelSpec spec;
  try {
    spec = parse_model_spec(r.model, static_cast<int>(r.joints.size()));
  } catch (const InputError&) {
    return out;  // a model identify itself wrote: always parses
  }
  for (const ModelEffect& e : spec.effects) {
    if (e.kind != EffectKind::shape) continue;
    std::vector<double> coefficients, x, y, lo, hi;
    std::vector<std::vector<double>> folds(r.fold_params.size());
    for (const std::string& name : effect_param_names(e))
      for (size_t i = 0; i < r.params.size(); ++i)
        if (r.params[i].name == name) {
          coefficients.push_back(r.params[i].value);
          for (size_t f = 0; f < folds.size(); ++f)
            if (i < r.fold_params[f].size()) folds[f].push_back(r.fold_params[f][i]);
        }
    const bool without_linear = shape_without_linear(e.variable);
    shape_curve(e.knots, coefficients, without_linear, kShapeCurvePoints, x, y);
    nlohmann::json curve = {{"x", x}, {"y", y}};
    shape_band(e.knots, without_linear, folds, y, lo, hi);
    if (folds.size() >= 2 && !y.empty()) curve["y_lo"] = lo, curve["y_hi"] = hi;
    out.push_back({{"joint", e.joint + 1}, {"variable", e.variable}, {"item", effect_item(e)}, {"curve", curve}});
  }
  return out;
}

}  // namespace

nlohmann::json identify_report_json(const IdentifyResult& r) {
  nlohmann::json j;
  j["robot"] = r.robot;
  j["method"] = r.method;
  j["model"] = r.model;
  j["validation"] = r.validation;
  j["data"] = r.data_source;
  j["sample_rate_hz"] = r.sample_rate_hz;
  j["decimated_rate_hz"] = r.decimated_rate_hz;
  j["cutoff_hz"] = r.cutoff_hz;
  j["samples"] = r.samples_used;
  j["condition_number"] = r.condition_number;
  if (!r.prismatic_joints.empty()) j["prismatic_joints"] = r.prismatic_joints;  // forces [N], not torques
  j["fit_seconds"] = r.fit_seconds;
  j["joints"] = joint_metrics_json(r.joints);
  j["params"] = nlohmann::json::array();
  for (const auto& p : r.params) {
    nlohmann::json e = {{"name", p.name}, {"value", p.value}, {"std", p.std}};  // a NaN std (dropped) is null
    if (p.value != 0.0 && std::isfinite(p.std)) e["relative_std"] = p.std / std::abs(p.value);
    if (std::isfinite(p.std)) e["zero_within_95"] = std::abs(p.value) <= kVerdictZ * p.std;
    if (p.scale > 0.0) {
      e["scale"] = p.scale;
      e["verdict"] = to_string(p.verdict);
    }
    if (!p.basis.empty()) e["basis"] = p.basis;
    if (std::isfinite(p.data_share)) e["data_share"] = p.data_share;
    if (p.contradicts_physics) e["physics"] = "contradicted: below 0 beyond its 95 % interval";
    j["params"].push_back(e);
  }
  const nlohmann::json shapes = fitted_shapes_json(r);
  if (!shapes.empty()) j["shapes"] = shapes;  // a model with shapes only
  j["notes"] = r.notes;
  j["links"] = link_inertials_json(r.links);
  j["other_logs"] = nlohmann::json::array();
  for (const auto& o : r.other_logs) j["other_logs"].push_back(log_prediction_json(o));
  return j;
}

void add_cad_values(nlohmann::json& report, const std::string& robot) {
  const CompiledRobot& c = compiled_robot(robot);
  const Eigen::VectorXd nominal = Eigen::Map<const Eigen::VectorXd>(
      c.nominal_standard.data(), static_cast<Eigen::Index>(c.nominal_standard.size()));
  if (nominal.size() != c.num_standard) return;
  const Eigen::VectorXd base = c.standard_to_base(nominal);
  nlohmann::json& params = report["params"];
  for (Eigen::Index i = 0; i < c.num_base && i < static_cast<Eigen::Index>(params.size()); ++i)
    params[static_cast<size_t>(i)]["cad"] = base[i];
  for (auto& l : report["links"]) {
    const Eigen::Index k = l.value("link", 0) - 1;
    if (k < 0 || 10 * k + 9 >= nominal.size()) continue;
    const double m = nominal[10 * k + 9];
    l["cad_mass"] = m;
    if (m > 0) l["cad_com"] = {nominal[10 * k + 6] / m, nominal[10 * k + 7] / m, nominal[10 * k + 8] / m};
  }
}

nlohmann::json parameter_table_json(const IdentifyResult& r) {
  return parameter_file_json(parameter_set(r), r.method);
}

}  // namespace dyncal::host
