// dyncal diagnose's report: text, JSON, and the effects as parameter-table terms.
#include <algorithm>
#include <iomanip>
#include <optional>
#include <sstream>

#include "candidates.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"

namespace dyncal::host {

void print_diagnose_report(std::ostream& out, const DiagnoseResult& r) {
  out << "dyncal diagnose: robot " << r.robot << ", declared model " << r.declared_model << " (" << r.method << "), "
      << r.samples << " samples, " << r.validation
      << ", BIC with n_eff = " << std::lround(r.effective_samples_per_joint)
      << " per joint (mean, from the residual's autocorrelation)\n";
  for (const auto& n : r.notes) out << "note: " << n << "\n";
  out << "\n";
  out << "effects added (greedy, by validation gain, each with BIC evidence):\n";
  if (r.effects.empty()) out << "  none: no candidate, in the catalogue or beyond it, is significant\n";
  for (const auto& e : r.effects) {
    out << "  " << std::left << std::setw(20) << effect_name(e.kind) << std::right << " dBIC " << std::setw(8)
        << std::setprecision(4) << e.delta_bic << ", validation RSS -" << std::setprecision(3)
        << 100 * e.validation_gain << " %, " << 100 * e.excess_share << " % (95 % "
        << 100 * e.excess_share_interval.first << ".." << 100 * e.excess_share_interval.second
        << ") of the excess over the noise floor left before it\n    " << e.explanation << "\n";
    if (e.kind == Effect::torque_delay)
      out << "    delay " << 1e3 * e.shape << " ms, 95 % " << 1e3 * e.shape_interval.first << " .. "
          << 1e3 * e.shape_interval.second << " ms\n";
    if (!e.alternatives.empty()) {
      out << "    indistinguishable on this log from:";
      for (size_t k = 0; k < e.alternatives.size(); ++k) out << (k ? ", " : " ") << e.alternatives[k];
      out << "\n";
    }
  }
  out << "\nstrongest rejected candidates:\n";
  for (const auto& c : r.rejected) {
    out << "  " << std::left << std::setw(20) << effect_name(c.kind) << std::right << " joint";
    for (int j : c.joints) out << " " << j;
    out << ": " << c.reason << "\n";
  }
  out << "\njoint   RMS val before   after [Nm]   R2 before   after   rel. RMS after e_T_abs before  after e_T_abs_std "
         "before  after\n"
      << std::fixed;
  for (const auto& j : r.joints) {
    out << std::setw(5) << j.joint << std::setprecision(4) << std::setw(17) << j.rms_validation_before << std::setw(12)
        << j.rms_validation_after << std::setw(12) << j.r2_validation_before << std::setw(8) << j.r2_validation_after
        << std::setw(17) << j.rms_validation_after / j.rms_tau << std::setw(15) << j.e_T_abs_before << std::setw(7)
        << j.e_T_abs_after << std::setw(15) << j.e_T_abs_std_before << std::setw(7) << j.e_T_abs_std_after << "\n";
  }
  out << "\njoint   RMS train before   after [Nm]   rel. RMS train before   after\n";
  for (const auto& j : r.joints) {
    out << std::setw(5) << j.joint << std::setprecision(4) << std::setw(19) << j.rms_train_before << std::setw(12)
        << j.rms_train_after << std::setw(24) << j.rms_train_before / j.rms_tau << std::setw(8)
        << j.rms_train_after / j.rms_tau << "\n";
  }
  out << "\njoint   noise floor [Nm] (95 %)            excess left (95 %; share of the declared model's validation "
         "RSS above the floor)\n";
  for (const auto& j : r.joints) {
    std::ostringstream band;
    band << std::fixed << std::setprecision(4) << "(" << j.rms_noise_floor_interval.first << ".."
         << j.rms_noise_floor_interval.second << ")";
    out << std::fixed << std::setw(5) << j.joint << std::setprecision(4) << std::setw(13) << j.rms_noise_floor << " "
        << std::left << std::setw(20) << band.str() << std::right << std::setprecision(1) << std::setw(9)
        << 100 * j.excess_left << " % (" << 100 * j.excess_left_interval.first << ".."
        << 100 * j.excess_left_interval.second << " %)\n";
  }
  out << std::defaultfloat;
}

std::optional<ModelEffect> model_effect(const DiagnosedEffect& e) {
  const std::optional<EffectKind> kind = detail::effect_spec(e.kind).table_kind;
  if (!kind) return std::nullopt;
  ModelEffect m;
  m.kind = *kind;
  m.joint = e.joints.front() - 1;
  m.shape = e.shape;
  m.variable = e.variable;
  m.knots = e.knots;
  m.penalty = e.penalty;
  if (m.kind == EffectKind::shape) m.shape = 0;
  if (m.kind == EffectKind::coupling) {
    m.joint2 = e.joints.back() - 1;
    m.sign = e.sign > 0 ? 1 : -1;
  }
  return m;
}

ParameterSet diagnosed_parameter_set(const ParameterSet& declared, const DiagnoseResult& r,
                                     std::vector<std::string>* skipped) {
  if (r.declared_params.size() != declared.names.size())
    throw InputError("the diagnosis has " + std::to_string(r.declared_params.size()) + " declared parameters, the " +
                     "declared model " + std::to_string(declared.names.size()));
  ParameterSet p = declared;
  std::vector<double> values = r.declared_params;
  for (const auto& e : r.effects) {
    const std::optional<ModelEffect> m = model_effect(e);
    if (!m || m->kind == EffectKind::shape) {
      if (skipped)
        skipped->push_back(std::string(effect_name(e.kind)) + " on joint " + std::to_string(e.joints.front()));
      continue;
    }
    const std::vector<std::string> names = effect_param_names(*m);
    std::vector<double> c = e.params;  // a coupled motor without rotor inertia: Ia 0
    c.resize(names.size(), 0.0);
    p.effects.push_back(*m);
    p.names.insert(p.names.end(), names.begin(), names.end());
    values.insert(values.end(), c.begin(), c.end());
    p.model += "," + effect_item(*m);
  }
  p.values = Eigen::Map<const Eigen::VectorXd>(values.data(), static_cast<Eigen::Index>(values.size()));
  p.stdev.resize(0);  // the diagnosis's values, not the declared fit's
  p.source = declared.source + " with the diagnosis";
  return p;
}

nlohmann::json diagnose_report_json(const DiagnoseResult& r) {
  nlohmann::json j;
  j["robot"] = r.robot;
  j["declared_model"] = r.declared_model;
  j["method"] = r.method;
  j["samples"] = r.samples;
  j["validation"] = r.validation;
  j["effective_samples_per_joint"] = r.effective_samples_per_joint;
  j["notes"] = r.notes;
  j["effects"] = nlohmann::json::array();
  for (const auto& e : r.effects) {
    // The effect as a --model item for identify (none for drift, which has no model term).
    const std::optional<ModelEffect> me = model_effect(e);
    const std::string item = e.kind == Effect::coupled_motor
                                 ? coupled_motor_item({e.joints[0] - 1, e.joints[1] - 1, e.sign * e.shape})
                                 : (me ? effect_item(*me) : "");
    nlohmann::json p = nlohmann::json::object();
    for (size_t i = 0; i < e.params.size(); ++i) p[e.param_names[i]] = e.params[i];
    nlohmann::json effect = {{"kind", effect_name(e.kind)},
                             {"joint", e.joints.front()},
                             {"joints", e.joints},
                             {"shape", e.shape},
                             {"shape_interval", {e.shape_interval.first, e.shape_interval.second}},
                             {"sign", e.sign},
                             {"item", item},
                             {"parameters", p},
                             {"evidence", {{"delta_bic", e.delta_bic}, {"validation_gain", e.validation_gain}}},
                             {"inertia_held_at_zero", e.inertia_held},
                             {"variable", e.variable},
                             {"knots", e.knots},
                             {"penalty", e.penalty},
                             {"effective_parameters", e.effective_parameters},
                             {"excess_share", e.excess_share},
                             {"excess_share_interval", {e.excess_share_interval.first, e.excess_share_interval.second}},
                             {"explanation", e.explanation},
                             {"indistinguishable_from", e.alternatives}};
    if (!e.curve_x.empty())
      effect["curve"] = {{"x", e.curve_x}, {"y", e.curve_y}, {"y_lo", e.curve_lo}, {"y_hi", e.curve_hi}};
    j["effects"].push_back(std::move(effect));
  }
  j["rejected"] = nlohmann::json::array();
  for (const auto& c : r.rejected)
    j["rejected"].push_back(
        {{"kind", effect_name(c.kind)}, {"joints", c.joints}, {"delta_bic", c.delta_bic}, {"reason", c.reason}});
  j["joints"] = nlohmann::json::array();
  for (const auto& m : r.joints) {
    j["joints"].push_back(
        {{"joint", m.joint},
         {"rms_train_before", m.rms_train_before},
         {"rms_train_after", m.rms_train_after},
         {"rms_validation_before", m.rms_validation_before},
         {"rms_validation_after", m.rms_validation_after},
         {"relative_rms_validation_before", m.rms_validation_before / m.rms_tau},
         {"relative_rms_validation_after", m.rms_validation_after / m.rms_tau},
         {"r2_validation_before", m.r2_validation_before},
         {"r2_validation_after", m.r2_validation_after},
         {"e_T_abs_before", m.e_T_abs_before},
         {"e_T_abs_after", m.e_T_abs_after},
         {"e_T_abs_std_before", m.e_T_abs_std_before},
         {"e_T_abs_std_after", m.e_T_abs_std_after},
         {"rms_noise_floor", m.rms_noise_floor},
         {"rms_noise_floor_interval", {m.rms_noise_floor_interval.first, m.rms_noise_floor_interval.second}},
         {"excess_left", m.excess_left},
         {"excess_left_interval", {m.excess_left_interval.first, m.excess_left_interval.second}}});
  }
  return j;
}

}  // namespace dyncal::host
