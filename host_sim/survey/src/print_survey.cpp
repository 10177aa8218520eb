// print_survey: the study's tables next to the published ones, one function per table.
#include "dyncal_host/survey/print_survey.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <map>
#include <ostream>
#include <sstream>
#include <vector>

#include "dyncal_host/survey/indices.hpp"
#include "dyncal_host/survey/tracking.hpp"

namespace dyncal::host::survey {
namespace {

using nlohmann::json;

constexpr int kName = 56;  // width of the method column

std::string fmt(double v, int precision = 4) {
  std::ostringstream s;
  if (v != 0 && (std::fabs(v) < 1e-3 || std::fabs(v) >= 1e5)) {
    s << std::scientific << std::setprecision(1) << v;
  } else {
    s << std::fixed << std::setprecision(precision) << v;
  }
  return s.str();
}

std::string cell(const json& v) {
  return v.is_null() ? "-" : (v.is_number() ? fmt(v.get<double>()) : v.get<std::string>());
}

void joint3_table(std::ostream& out, const char* title, const json& ours, const json& published) {
  out << "\n" << title << "\n";
  const json& names = published["parameters"];
  out << std::left << std::setw(18) << "parameter" << std::right << std::setw(10) << "set";
  std::vector<std::string> pub_methods, our_methods;
  for (auto& [k, v] : published.items())
    if (k != "parameters" && k != "set") pub_methods.push_back(k);
  for (auto& [k, v] : ours.items()) our_methods.push_back(k);
  for (const auto& m : pub_methods) out << std::setw(12) << m.substr(0, 11);
  out << "  |";
  for (const auto& m : our_methods) out << std::setw(12) << m.substr(0, 11);
  out << "\n" << std::left << std::setw(28) << "" << std::right;  // under "parameter" and "set"
  for (size_t i = 0; i < pub_methods.size(); ++i) out << std::setw(12) << "(published)";
  out << "  |";
  for (size_t i = 0; i < our_methods.size(); ++i) out << std::setw(12) << "(dyncal)";
  out << "\n";
  for (size_t i = 0; i < names.size(); ++i) {
    out << std::left << std::setw(18) << names[i].get<std::string>() << std::right << std::setw(10)
        << cell(published["set"][i]);
    for (const auto& m : pub_methods) out << std::setw(12) << cell(published[m][i]);
    out << "  |";
    for (const auto& m : our_methods) out << std::setw(12) << cell(ours[m]["joint3"][i]);
    out << "\n";
  }
  // Link 3's mean relative error over its inertial parameters (m, X Y Z, I11..I33 with nonzero set
  // values): the figure e_d averages over the links. "prior": with the CAD prior in the directions
  // no torque determines (the parameters e_d prior scores).
  std::array<double, 10> set{};
  for (size_t i = 0; i < set.size(); ++i) set[i] = published["set"][i].get<double>();
  auto link3_error = [&](const json& row) {
    std::array<double, 10> est{};
    for (size_t i = 0; i < est.size(); ++i) est[i] = row[i].get<double>();
    return mean_relative_error(set.data(), est.data(), 10);
  };
  out << std::left << std::setw(28) << "link 3 error" << std::right;
  for (const auto& m : pub_methods) out << std::setw(12) << fmt(link3_error(published[m]));
  out << "  |";
  for (const auto& m : our_methods) out << std::setw(12) << fmt(link3_error(ours[m]["joint3"]));
  out << "\n";
  bool with_prior = true;
  for (const auto& m : our_methods) with_prior = with_prior && ours[m].contains("joint3_prior");
  if (!with_prior) return;
  out << std::left << std::setw(28) << "link 3 error, prior" << std::right;
  for (size_t i = 0; i < pub_methods.size(); ++i) out << std::setw(12) << "";
  out << "  |";
  for (const auto& m : our_methods) out << std::setw(12) << fmt(link3_error(ours[m]["joint3_prior"]));
  out << "\n";
}

void je_table(std::ostream& out, const char* title, const json& ours, const json& published) {
  out << "\n" << title << "\n";
  const std::vector<std::string> idx = {"e_d", "e_f", "e_T", "e_T_std", "J_e"};
  for (const char* noise : {"without_noise", "with_noise"}) {
    out << (std::string(noise) == "with_noise" ? "with Table 7 noise" : "without noise") << "\n";
    out << std::left << std::setw(kName) << "method" << std::right;
    for (const auto& i : idx) out << std::setw(10) << i;
    out << std::setw(11) << "e_d prior" << std::setw(11) << "J_e prior" << std::setw(9) << "e_b" << std::setw(10)
        << "time [s]"
        << "\n";
    const json pub_rows = published.value(noise, json::object());
    for (auto& [m, v] : pub_rows.items()) {
      out << std::left << std::setw(kName) << (m + " (published)") << std::right;
      for (const auto& x : v) out << std::setw(10) << fmt(x.get<double>());
      out << "\n";
    }
    for (auto& [m, v] : ours["methods"].items()) {
      const json& r = v[noise];
      out << std::left << std::setw(kName) << (m + " (dyncal)") << std::right;
      for (const auto& i : idx) out << std::setw(10) << fmt(r[i].get<double>());
      out << std::setw(11) << fmt(r["e_d_prior"].get<double>()) << std::setw(11) << fmt(r["J_e_prior"].get<double>())
          << std::setw(9) << fmt(r["e_b"].get<double>()) << std::setw(10) << fmt(r["seconds"].get<double>(), 3) << "\n";
    }
  }
  out << "Delta J_e = (J_e with noise - J_e without) / J_e without\n";
  const json pub_delta = published.value("delta_J_e", json::object());
  for (auto& [m, v] : pub_delta.items())
    out << "  " << std::left << std::setw(kName) << (m + " (published)") << std::right << fmt(v.get<double>()) << "\n";
  for (auto& [m, v] : ours["methods"].items())
    out << "  " << std::left << std::setw(kName) << (m + " (dyncal)") << std::right << fmt(v["delta_J_e"].get<double>())
        << "   (with the prior: " << fmt(v["delta_J_e_prior"].get<double>()) << ")\n";
}

/// Joint 3's friction parameters of every method on a model without published numbers, beside the set
/// values.
void friction3_table(std::ostream& out, const json& c) {
  out << "joint 3 friction, without noise\n" << std::left << std::setw(kName) << "parameter" << std::right;
  for (const auto& n : c["parameters"]) out << std::setw(10) << n.get<std::string>();
  out << "\n" << std::left << std::setw(kName) << "set" << std::right;
  for (const auto& v : c["set_joint3"]) out << std::setw(10) << fmt(v.get<double>());
  out << "\n";
  const size_t k = c["parameters"].size();
  for (auto& [m, v] : c["methods"].items()) {
    out << std::left << std::setw(kName) << (m + " (dyncal)") << std::right;
    for (size_t i = 0; i < k; ++i) out << std::setw(10) << fmt(v["joint3"][10 + i].get<double>());
    out << "\n";
  }
}

void print_header(std::ostream& out, const json& r) {
  const json& s = r["settings"];
  out << "dyncal survey: the survey's simulation study (Sec. 6) on the er20 through the simulated drive\n"
      << "100 Hz sampling, " << s["periods"].get<int>()
      << " period(s) of a Fourier excitation (Eq. 27, L = 5, f_f = 0.1 Hz), "
      << "seed " << s["seed"].get<std::uint64_t>() << "; CAD prior: set "
      << (s.value("prior_on", "standard") == "table5" ? "Table 5 parameters (m, c, I about c)" : "standard parameters")
      << " x (1 + U(-" << s["prior_error"].get<double>() << ", +" << s["prior_error"].get<double>() << "))\n"
      << "cond(K) of the designed excitations (dyncal excite; Eq. 26, unit-scaled columns): "
      << fmt(r["models"]["eq7"]["trajectory_cond"].get<double>(), 2) << " for Eq. 7, "
      << fmt(r["models"]["eq4"]["trajectory_cond"].get<double>(), 2) << " for Eq. 4 (survey: 4.6 and 5.7)\n"
      << "e_d as the survey: standard parameters as the method gives them (base-parameter methods: the\n"
      << "minimum-norm ones, as a pseudo-inverse returns); 'e_d prior': with the CAD prior in the directions\n"
      << "the data cannot see; e_b: base-parameter error (needs no prior). e_T: |signed mean|, as the\n"
      << "published values (docs/survey.md).\n";
}

/// Tables 5, 6, 8, 9, and Tables 8 / 9 for the models the survey did not run.
void print_model_tables(std::ostream& out, const json& r, const json& pub) {
  joint3_table(out, "Table 5: linear calibration (Eq. 7) of joint 3, without noise", r["models"]["eq7"]["methods"],
               pub["table5_joint3_linear"]);
  joint3_table(out, "Table 6: nonlinear calibration (Eq. 4) of joint 3, without noise", r["models"]["eq4"]["methods"],
               pub["table6_joint3_nonlinear"]);
  je_table(out, "Table 8: J_e without and with noise, linear model (Eq. 7)", r["models"]["eq7"], pub["table8_linear"]);
  je_table(out, "Table 9: J_e without and with noise, nonlinear model (Eq. 4)", r["models"]["eq4"],
           pub["table9_nonlinear"]);
  for (const char* key : {"eq8", "eq9", "eq5", "eq6"}) {
    if (!r["models"].contains(key)) continue;
    const std::string title = std::string("Tables 8 / 9 for ") +
                              (key[2] == '8'   ? "Eq. 8"
                               : key[2] == '9' ? "Eq. 9"
                               : key[2] == '5' ? "Eq. 5"
                                               : "Eq. 6") +
                              " (the survey's study ran Eq. 7 and Eq. 4 only: no published numbers)";
    je_table(out, title.c_str(), r["models"][key], json::object());
    friction3_table(out, r["models"][key]);
  }
}

void print_undetermined_scale_parameters(std::ostream& out, const json& r) {
  out << "\nScale parameters the data do not determine (95 % profile-likelihood interval of the joint friction\n"
      << "scan at physically consistent LS's rigid body open on both sides within the searched range):\n";
  for (auto& [model, c] : r["models"].items()) {
    if (!c.contains("undetermined_scale_parameters")) continue;
    for (const char* noise : {"without_noise", "with_noise"}) {
      std::string list;
      for (const auto& x : c["undetermined_scale_parameters"][noise])
        list += (list.empty() ? "" : ", ") + x.get<std::string>();
      out << "  Eq. " << model.substr(2)
          << (std::string(noise) == "with_noise" ? " with noise:    " : " without noise: ")
          << (list.empty() ? "none" : list) << "\n";
    }
  }
}

void print_table10(std::ostream& out, const json& r, const json& pub) {
  if (r.contains("table10")) {
    const json& t = r["table10"];
    const json& p10 = pub["table10_idim_iv_eq7"];
    out << "\nTable 10: IDIM-IV and the pseudo-inverse (Eq. 7) on measured positions (noise "
        << t["position_noise_std"].get<double>() << " rad, Table 7 torque noise),\n"
        << "with and without the 20 Hz fourth-order Butterworth filter before differentiation;\n"
        << "Delta J_e = (J_e without - J_e with) / J_e with\n";
    out << std::left << std::setw(kName) << "method" << std::right << std::setw(12) << "J_e filter" << std::setw(14)
        << "J_e no filter" << std::setw(10) << "dJ_e" << std::setw(15) << "J_e prior f." << std::setw(17)
        << "J_e prior no f." << std::setw(10) << "dJ_e pr." << std::setw(10) << "e_b f." << std::setw(11) << "e_b no f."
        << "\n";
    for (const char* m : {"pseudo-inverse", "IDIM-IV"}) {
      out << std::left << std::setw(kName) << (std::string(m) + " (published)") << std::right << std::setw(12)
          << fmt(p10[m][0].get<double>()) << std::setw(14) << fmt(p10[m][1].get<double>()) << std::setw(10)
          << fmt(p10[m][2].get<double>()) << "\n";
    }
    for (const char* m : {"pseudo-inverse", "IDIM-IV"}) {
      const json& v = t["methods"][m];
      out << std::left << std::setw(kName) << (std::string(m) + " (dyncal)") << std::right << std::setw(12)
          << fmt(v["with_filter"]["J_e"].get<double>()) << std::setw(14)
          << fmt(v["without_filter"]["J_e"].get<double>()) << std::setw(10) << fmt(v["delta_J_e"].get<double>())
          << std::setw(14) << fmt(v["with_filter"]["J_e_prior"].get<double>()) << std::setw(15)
          << fmt(v["without_filter"]["J_e_prior"].get<double>()) << std::setw(10)
          << fmt(v["delta_J_e_prior"].get<double>()) << std::setw(10) << fmt(v["with_filter"]["e_b"].get<double>())
          << std::setw(11) << fmt(v["without_filter"]["e_b"].get<double>()) << "\n";
    }
    if (t.contains("parallel_decimation")) {
      out << "Without the filter but with parallel decimation (torque and regressor low-passed alike, every "
          << t["parallel_decimation"].get<int>() << "th sample kept; Sec. 3.1):\n";
      for (const char* m : {"pseudo-inverse", "IDIM-IV"}) {
        const json& v = t["methods"][m]["without_filter_parallel_decimation"];
        out << "  " << std::left << std::setw(kName - 2) << m << std::right << "J_e " << fmt(v["J_e"].get<double>())
            << "   J_e prior " << fmt(v["J_e_prior"].get<double>()) << "   e_b " << fmt(v["e_b"].get<double>()) << "\n";
      }
    }
    const json& iv = t["methods"]["IDIM-IV"];
    out << "IDIM-IV: " << iv["with_filter"]["iterations"].get<int>() << " / "
        << iv["without_filter"]["iterations"].get<int>() << " closed-loop simulations ("
        << iv["with_filter"].value("note", std::string()) << " / " << iv["without_filter"].value("note", std::string())
        << ")\n";
  }
}

void print_tracking(std::ostream& out, const json& r) {
  if (r.contains("tracking")) {
    out << "\nFig. 4: following beta of joint 3 (40 -> 60 Nm s/rad over the second half of a 4-period run,\n"
        << "Table 7 noise);\n"
        << "over the last quarter of the run, relative to the change (20): lag |mean(beta_hat - beta)|\n"
        << "(follows: < 0.2) and scatter std(beta_hat - beta); forgetting mu = " << r["tracking"]["mu"].get<double>()
        << ";\n"
        << kConsistentForgetting << ": calibrated offline on the samples before the change, then only\n"
        << "the friction amplitudes tracked\n";
    out << std::left << std::setw(kName) << "method" << std::right;
    for (const char* p : {"step", "ramp", "second order"}) out << std::setw(28) << (std::string(p) + " lag / scatter");
    out << "\n";
    for (auto& [m, t] : r["tracking"]["methods"].items()) {
      out << std::left << std::setw(kName) << (m + " (dyncal)") << std::right;
      for (const char* p : {"step", "ramp", "second order"}) {
        out << std::setw(28) << (fmt(t[p]["lag"].get<double>(), 3) + " / " + fmt(t[p]["scatter"].get<double>(), 3));
      }
      out << "\n";
    }
  }
}

/// Table 11: levels (Tables 1-4); methods that run on both models are averaged before marking.
void print_table11(std::ostream& out, const json& r, const json& pub) {
  out << "\nTable 11: feature levels (Tables 1-4; e_d with the CAD prior in brackets; methods on both models\n"
      << "averaged before marking, as the survey)\n";
  out << std::left << std::setw(kName) << "method" << std::right << std::setw(8) << "e_d" << std::setw(8) << "e_f"
      << std::setw(8) << "e_T" << std::setw(10) << "J_e" << std::setw(14) << "follow" << std::setw(12) << "time"
      << std::setw(18) << "models" << std::setw(8) << "dJ_e"
      << "\n";
  for (auto& [m, levels] : pub["table11_levels"].items()) {
    if (m == "rows") continue;
    out << std::left << std::setw(kName) << (m + " (published)") << std::right << std::setw(8)
        << levels[0].get<std::string>() << std::setw(8) << levels[1].get<std::string>() << std::setw(8)
        << levels[2].get<std::string>() << std::setw(10) << levels[3].get<std::string>() << std::setw(14)
        << levels[4].get<std::string>() << std::setw(12) << levels[5].get<std::string>() << std::setw(18)
        << levels[6].get<std::string>() << std::setw(8) << levels[7].get<std::string>() << "\n";
  }
  std::map<std::string, std::vector<const json*>> by_method;
  for (const char* model : {"eq7", "eq4"}) {
    for (auto& [m, v] : r["models"][model]["methods"].items()) {
      const std::string name = m == "exponential forgetting" ? "exponential forgetting" : m;
      by_method[name].push_back(&v);
    }
  }
  // Which family of friction models (linear: Eq. 7, 8, 9; nonlinear: Eq. 4, 5, 6) each method ran on.
  auto families = [&](const std::string& method) {
    bool lin = false, nonlin = false;
    for (auto& [model, c] : r["models"].items()) {
      if (!c["methods"].contains(method)) continue;
      (model == "eq7" || model == "eq8" || model == "eq9" ? lin : nonlin) = true;
    }
    return std::string(lin && nonlin ? "linear/nonlinear" : (lin ? "linear" : "nonlinear"));
  };
  auto print_row = [&](const std::string& name, const std::vector<const json*>& list, const std::string& follow,
                       const std::string& time, const std::string& models) {
    auto avg = [&](const char* noise, const char* key) {
      double sum = 0;
      for (const json* v : list) sum += (*v)[noise][key].get<double>();
      return sum / static_cast<double>(list.size());
    };
    double dje = 0;
    for (const json* v : list) dje += (*v)["delta_J_e"].get<double>() / static_cast<double>(list.size());
    out << std::left << std::setw(kName) << (name + " (dyncal)") << std::right << std::setw(3)
        << level(avg("without_noise", "e_d"), 0.2, 1) << " (" << level(avg("without_noise", "e_d_prior"), 0.2, 1) << ")"
        << std::setw(8) << level(avg("without_noise", "e_f"), 0.2, 1) << std::setw(8)
        << level(avg("without_noise", "e_T"), 0.01, 0.1) << std::setw(10) << level(avg("without_noise", "J_e"), 1, 10)
        << std::setw(14) << follow << std::setw(12) << time << std::setw(18) << models << std::setw(8)
        << level(dje, 0.1, 1) << "\n";
  };
  auto offline_time = [](const std::vector<const json*>& list) {
    double secs = 0;
    for (const json* v : list) secs = std::max(secs, (*v)["without_noise"]["seconds"].get<double>());
    return std::string("offline ") + level(secs, 60, 3600);
  };
  for (const auto& [m, list] : by_method) {
    const bool online = (*list.front())["online"].get<bool>();
    std::string follow = online ? "not measured" : "C (offline)";
    if (online && r.contains("tracking") && r["tracking"]["methods"].contains(m)) {
      const json& t = r["tracking"]["methods"][m];
      follow = std::string(1, follow_level(t["ramp"]["lag"].get<double>(), t["step"]["lag"].get<double>()));
    }
    print_row(m, list, follow, online ? "online" : offline_time(list), families(m));
  }
  // dyncal's hybrid: physically consistent LS offline (its indices on the study's runs are that
  // method's), then its friction tracked online; follows if it does on both the Eq. 7 and Eq. 4 run.
  const char* pcls = "physically consistent LS";
  if (by_method.count(pcls) && r.contains("tracking")) {
    double ramp = 0, step = 0;
    int runs = 0;
    for (auto& [m, t] : r["tracking"]["methods"].items()) {
      if (m.rfind(kConsistentForgetting, 0) != 0) continue;
      ramp = std::max(ramp, t["ramp"]["lag"].get<double>());
      step = std::max(step, t["step"]["lag"].get<double>());
      ++runs;
    }
    if (runs == 2) {
      print_row(kConsistentForgetting, by_method[pcls], std::string(1, follow_level(ramp, step)),
                offline_time(by_method[pcls]), families(pcls));
      out << "(" << kConsistentForgetting << ": " << pcls << " offline, its indices above are that\n"
          << "method's; then the friction amplitudes tracked online (Fig. 4); follows: on the Eq. 7 and Eq. 4 runs)\n";
    }
  }
}

void print_table12(std::ostream& out, const json& r, const json& pub) {
  if (r.contains("table12")) {
    const json& t = r["table12"];
    const json& p12 = pub["table12_experiment_torque_error_nm"];
    out << "\nTable 12: torque error [Nm] (mean / std over all joints and samples) of each friction model fitted to\n"
        << "one measured run. Published: the real ER20, particle filter. dyncal: a STAND-IN (no real ER20 log\n"
        << "here): the simulated drive with Eq. 4 friction, Table 7 torque noise and 1e-4 rad position noise,\n"
        << "states from the measured positions (20 Hz filter, central differences), fitted on the first\n"
        << "period; 'validation': the std on the second period, which the fit did not see\n";
    out << std::left << std::setw(kName) << "method" << std::right;
    for (const auto& m : p12["models"]) out << std::setw(16) << m.get<std::string>();
    out << "\n" << std::left << std::setw(kName) << "particle filter (published, ER20)" << std::right;
    for (size_t i = 0; i < p12["models"].size(); ++i)
      out << std::setw(16) << (fmt(p12["mean"][i].get<double>(), 2) + " / " + fmt(p12["std"][i].get<double>(), 2));
    out << "\n";
    for (auto& [m, v] : t["methods"].items()) {
      out << std::left << std::setw(kName) << (m + " (stand-in)") << std::right;
      for (const auto& key : p12["models"]) {
        const json& x = v[key.get<std::string>()];
        out << std::setw(16) << (fmt(x["mean"].get<double>(), 2) + " / " + fmt(x["std"].get<double>(), 2));
      }
      out << "\n" << std::left << std::setw(kName) << "  validation std" << std::right;
      for (const auto& key : p12["models"])
        out << std::setw(16) << fmt(v[key.get<std::string>()]["validation_std"].get<double>(), 3);
      out << "\n";
    }
  }
}

}  // namespace

void print_survey(std::ostream& out, const json& r, const json& pub) {
  print_header(out, r);
  print_model_tables(out, r, pub);
  print_undetermined_scale_parameters(out, r);
  print_table10(out, r, pub);
  print_tracking(out, r);
  print_table11(out, r, pub);
  print_table12(out, r, pub);
}

}  // namespace dyncal::host::survey
