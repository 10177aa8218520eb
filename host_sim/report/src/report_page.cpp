// The HTML page of a command's JSON report (report_page.hpp).
#include "dyncal_host/report/report_page.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <vector>

#include "dyncal_host/common/gnuplot.hpp"
#include "dyncal_host/report/gate.hpp"
#include "dyncal_host/report/input_digest.hpp"

namespace dyncal::host {
namespace {

using Json = nlohmann::json;

std::string escape(const std::string& s) {
  std::string out;
  for (const char c : s) switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  return out;
}

/// A label inside a gnuplot single-quoted string: a quote doubled.
std::string gnuplot_text(const std::string& s) {
  std::string out;
  for (const char c : s) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out;
}

/// %.6g, or every digit of an integer below 1e15 (sample counts, byte counts).
std::string g6(double v) {
  char text[32];
  if (std::abs(v) < 1e15 && v == std::floor(v))
    std::snprintf(text, sizeof text, "%.0f", v);
  else
    std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

std::string pointer_escape(const std::string& key) {
  std::string out;
  for (const char c : key) out += c == '~' ? "~0" : c == '/' ? "~1" : std::string(1, c);
  return out;
}

/// A JSON value as HTML: numbers with their JSON pointer, arrays and objects inline.
std::string value_html(const Json& v, const std::string& path) {
  // A non-finite number is null in the JSON file (nlohmann-json writes NaN as null): a dash, as null.
  if (v.is_null() || (v.is_number() && !std::isfinite(v.get<double>()))) return "<span class=\"none\">&ndash;</span>";
  if (v.is_number()) return "<span class=\"num\" data-path=\"" + escape(path) + "\">" + g6(v.get<double>()) + "</span>";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_string()) return escape(v.get<std::string>());
  std::string out;
  if (v.is_array()) {
    for (size_t i = 0; i < v.size(); ++i) out += (i ? " " : "") + value_html(v[i], path + "/" + std::to_string(i));
    return out;
  }
  for (const auto& [k, x] : v.items())
    out += (out.empty() ? "" : "; ") + escape(k) + " " + value_html(x, path + "/" + pointer_escape(k));
  return out;
}

/// An array of objects as a table: one row per object, the columns the objects' keys (first-seen
/// order, `first` keys leading, `skip` keys left out).
std::string table_html(const Json& rows, const std::string& path, const std::vector<std::string>& first = {},
                       const std::vector<std::string>& skip = {}) {
  std::vector<std::string> columns;
  auto add = [&](const std::string& k) {
    for (const auto& s : skip)
      if (s == k) return;
    for (const auto& c : columns)
      if (c == k) return;
    columns.push_back(k);
  };
  for (const auto& k : first)
    for (const auto& r : rows)
      if (r.is_object() && r.contains(k)) {
        add(k);
        break;
      }
  for (const auto& r : rows)
    if (r.is_object())
      for (const auto& [k, v] : r.items()) add(k);
  std::string out = "<table><thead><tr>";
  for (const auto& c : columns) out += "<th>" + escape(c) + "</th>";
  out += "</tr></thead><tbody>";
  for (size_t i = 0; i < rows.size(); ++i) {
    out += "<tr>";
    for (const auto& c : columns) {
      const std::string p = path + "/" + std::to_string(i) + "/" + pointer_escape(c);
      out += "<td>" + (rows[i].contains(c) ? value_html(rows[i][c], p) : std::string()) + "</td>";
    }
    out += "</tr>";
  }
  return out + "</tbody></table>";
}

double num(const Json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : NAN;
}

/// Whether the array holds a finite number (gnuplot stops on a plot with none).
bool any_number(const Json& a) {
  for (const auto& v : a)
    if (v.is_number() && std::isfinite(v.get<double>())) return true;
  return false;
}

void write_column(std::ofstream& out, const Json& a, size_t i) {
  if (i < a.size() && a[i].is_number())
    out << " " << a[i].get<double>();
  else
    out << " NaN";
}

/// The plots of one page, drawn by one gnuplot run. add() returns a placeholder the page puts where
/// the figure goes; place() replaces each by its figure once drawn.
class Plots {
 public:
  /// Adds plot `name` (its data files already in work()); `script` draws it.
  std::string add(const std::string& name, const std::string& title, const std::string& script) {
    names_.push_back(name);
    titles_.push_back(title);
    script_ += "set output '" + name + ".svg'\n" + script + "\n";
    return placeholder(name);
  }
  const std::string& work() const { return svg_.work(); }
  /// `page` with each placeholder replaced by its <figure> (an embedded SVG).
  std::string place(std::string page) {
    if (names_.empty()) return page;
    std::ofstream(svg_.work() + "/plots.gp")
        << "set terminal svg size 820,300 background rgb 'white' noenhanced font 'sans,11'\nset grid\nset key "
           "outside right top\n"
        << script_;
    std::vector<std::string> files;
    for (const auto& n : names_) files.push_back(n + ".svg");
    const std::vector<std::string> texts = svg_.draw(files);
    for (size_t i = 0; i < texts.size(); ++i) {
      const std::string figure = "<figure><img class=\"plot\" data-plot=\"" + escape(names_[i]) + "\" alt=\"" +
                                 escape(titles_[i]) + "\" src=\"data:image/svg+xml;base64," + base64(texts[i]) +
                                 "\"><figcaption>" + escape(titles_[i]) + "</figcaption></figure>";
      const size_t at = page.find(placeholder(names_[i]));
      if (at != std::string::npos) page.replace(at, placeholder(names_[i]).size(), figure);
    }
    return page;
  }

 private:
  static std::string placeholder(const std::string& name) { return "<!--plot:" + name + "-->"; }
  SvgPlots svg_;
  std::vector<std::string> names_, titles_;
  std::string script_;
};

/// Per joint: measured and predicted torque over time, and the residual's envelope.
std::string series_plots(const Json& series, Plots& plots) {
  std::string out = "<section id=\"torque\"><h2>Measured and predicted torque</h2><p>" +
                    std::to_string(series["t"].size()) + " of the fit's " + std::to_string(series.value("samples", 0)) +
                    " samples drawn (every " + std::to_string(series.value("stride", 1)) +
                    "th); the residual's band is its min and max over every sample of each of " +
                    std::to_string(series["residual_envelope"]["t"].size()) + " consecutive buckets.</p>";
  const Json& t = series["t"];
  const Json& env = series["residual_envelope"];
  for (const auto& joint : series["joints"]) {
    const std::string J = std::to_string(joint.value("joint", 0));
    const bool after = joint.contains("predicted_after");
    if (!any_number(joint["measured"]) || !any_number(joint["predicted"])) {  // gnuplot refuses an empty plot
      out += "<p>Joint " + J + ": no predicted sample to draw.</p>";
      continue;
    }
    {
      std::ofstream d(plots.work() + "/torque" + J + ".dat");
      for (size_t i = 0; i < t.size(); ++i) {
        d << t[i].get<double>();
        write_column(d, joint["measured"], i);
        write_column(d, joint["predicted"], i);
        if (after) write_column(d, joint["predicted_after"], i);
        d << "\n";
      }
      std::ofstream e(plots.work() + "/residual" + J + ".dat");
      const Json& ej = env["joints"][static_cast<size_t>(joint.value("joint", 1) - 1)];
      for (size_t i = 0; i < env["t"].size(); ++i) {
        e << env["t"][i].get<double>();
        write_column(e, ej["min"], i);
        write_column(e, ej["max"], i);
        e << "\n";
      }
    }
    std::string script = "set xlabel 't [s]'\nset ylabel 'tau [Nm]'\nplot 'torque" + J +
                         ".dat' u 1:2 w l lc rgb '#888888' t 'measured', '' u 1:3 w l lc rgb '#1f77b4' t " +
                         (after ? "'declared model'" : "'predicted'");
    if (after) script += ", '' u 1:4 w l lc rgb '#d62728' t 'with the effects found'";
    out += plots.add("torque_joint" + J, "joint " + J + ": measured and predicted torque", script);
    out += plots.add("residual_joint" + J, "joint " + J + ": residual (measured - predicted), min and max per bucket",
                     "set xlabel 't [s]'\nset ylabel 'residual [Nm]'\nplot 'residual" + J +
                         ".dat' u 1:2:3 w filledcurves lc rgb '#9ecae1' t 'min..max', 0 w l lc rgb 'black' notitle");
  }
  return out + "</section>";
}

/// The parameters' deviation from their CAD values in units of their physical scale, with 95 %
/// intervals.
std::string cad_plot(const Json& params, Plots& plots) {
  std::ofstream d(plots.work() + "/cad.dat");
  int k = 0;
  std::string tics;
  for (const auto& p : params) {
    const double v = num(p, "value"), cad = num(p, "cad"), scale = num(p, "scale"), sd = num(p, "std");
    if (!std::isfinite(v) || !std::isfinite(cad) || !(scale > 0)) continue;
    d << k << " " << (v - cad) / scale << " " << (std::isfinite(sd) ? kZ95 * sd / scale : 0.0) << "\n";
    tics += (tics.empty() ? "" : ", ") + std::string("'") + p.value("name", "") + "' " + std::to_string(k);
    ++k;
  }
  if (k == 0) return "";
  return plots.add(
      "parameters_against_cad", "parameters against the robot's CAD values: (value - CAD) / scale, 95 % intervals",
      "set xtics (" + tics +
          ") rotate by 90 right font ',8'\nset ylabel '(value - CAD) / scale'\nset xrange [-1:" + std::to_string(k) +
          "]\nplot 'cad.dat' u 1:2:3 w yerrorbars pt 7 ps 0.5 lc rgb '#1f77b4' t 'identified', "
          "0 w l lc rgb 'black' t 'CAD'\nunset xtics\nset xtics\nset autoscale x");
}

std::string diagnose_plot(const Json& joints, Plots& plots) {
  std::ofstream d(plots.work() + "/diagnose.dat");
  for (const auto& j : joints)
    d << j.value("joint", 0) << " " << num(j, "rms_validation_before") << " " << num(j, "rms_validation_after") << "\n";
  return plots.add(
      "diagnose_before_after", "cross-validated RMS per joint before and after the effects found",
      "set style data histograms\nset style fill solid 0.8\nset boxwidth 0.9\nset xlabel 'joint'\nset ylabel "
      "'RMS [Nm]'\nset yrange [0:*]\nplot 'diagnose.dat' u 2:xtic(1) t 'before', '' u 3 t 'after'\nset autoscale "
      "y\nset style data lines");
}

/// Each shape diagnose found beyond its catalogue (or identify fitted): its torque against its
/// variable (the report's "curve"), one plot per entry, named by its 1-based place in the list.
std::string shape_plots(const Json& effects, Plots& plots) {
  std::string out;
  for (size_t i = 0; i < effects.size(); ++i) {
    const Json& e = effects[i];
    if (!e.is_object() || !e.contains("curve") || !e["curve"].is_object() || !e["curve"].contains("x") ||
        !e["curve"].contains("y") || !e["curve"]["x"].is_array() || !e["curve"]["y"].is_array() ||
        !any_number(e["curve"]["y"]))
      continue;
    const std::string k = std::to_string(i + 1);
    const std::string variable =
        e.contains("variable") && e["variable"].is_string() ? e["variable"].get<std::string>() : "x";
    std::ofstream d(plots.work() + "/shape" + k + ".dat");
    const Json &x = e["curve"]["x"], &y = e["curve"]["y"];
    // The pointwise 95 % band, where the report has one of the curve's length (diagnose's).
    const Json none = Json::array();
    const Json& lo = e["curve"].contains("y_lo") && e["curve"]["y_lo"].is_array() ? e["curve"]["y_lo"] : none;
    const Json& hi = e["curve"].contains("y_hi") && e["curve"]["y_hi"].is_array() ? e["curve"]["y_hi"] : none;
    const bool band = lo.size() == y.size() && hi.size() == y.size() && any_number(lo);
    for (size_t p = 0; p < x.size() && p < y.size(); ++p) {
      if (!x[p].is_number() || !y[p].is_number()) continue;
      d << x[p].get<double>() << " " << y[p].get<double>();
      if (band)
        d << " " << (lo[p].is_number() ? g6(lo[p].get<double>()) : "NaN") << " "
          << (hi[p].is_number() ? g6(hi[p].get<double>()) : "NaN");
      d << "\n";
    }
    const double joint = num(e, "joint");
    const std::string file = "'shape" + k + ".dat'";
    out += plots.add("shape_effect" + k,
                     "effect " + k + ", joint " + g6(joint) + ": the shape, torque against " + variable +
                         (band ? " (shaded: its pointwise 95 % band)" : ""),
                     "set xlabel '" + gnuplot_text(variable) + "'\nset ylabel 'torque [Nm]'\nplot " +
                         (band ? file + " u 1:3:4 w filledcurves lc rgb '#9ecae1' t '95 %', " : std::string()) + file +
                         " u 1:2 w l lc rgb '#1f77b4' t 'shape'");
  }
  return out;
}

/// Per joint: |r - mean| (its max per bucket) against the bound it is compared with, contacts shaded.
std::string monitor_plots(const Json& series, const Json& contacts, Plots& plots) {
  std::string out =
      "<section id=\"residual\"><h2>The observer's residual over the log</h2><p>Per joint, the largest "
      "|r - mean| of each of " +
      std::to_string(series["t"].size()) +
      " consecutive buckets against the largest threshold there (widened where the model cannot know "
      "the friction); contacts shaded.</p>";
  std::string shade;
  int n = 1;
  for (const auto& c : contacts)
    shade += "set object " + std::to_string(n++) + " rect from " + g6(num(c, "start")) + ", graph 0 to " +
             g6(num(c, "end")) + ", graph 1 fc rgb '#f4cccc' fs solid 0.6 behind\n";
  for (const auto& joint : series["joints"]) {
    const std::string J = std::to_string(joint.value("joint", 0));
    std::ofstream d(plots.work() + "/monitor" + J + ".dat");
    for (size_t i = 0; i < series["t"].size(); ++i) {
      d << series["t"][i].get<double>();
      write_column(d, joint["max"], i);
      write_column(d, joint["threshold"], i);
      d << "\n";
    }
    out += plots.add("monitor_joint" + J, "joint " + J + ": |r - mean| and its threshold [Nm]",
                     shade + "set xlabel 't [s]'\nset ylabel '|r - mean| [Nm]'\nplot 'monitor" + J +
                         ".dat' u 1:2 w l lc rgb '#1f77b4' t '|r - mean|', '' u 1:3 w l lc rgb '#d62728' t "
                         "'threshold'\nunset object");
  }
  return out + "</section>";
}

std::string contact_plot(const Json& contacts, Plots& plots) {
  std::ofstream d(plots.work() + "/contacts.dat");
  for (const auto& c : contacts) {
    const double s = num(c, "start"), e = num(c, "end");
    for (const auto& j : c.value("joints", Json::array()))
      d << s << " " << j.get<double>() << "\n" << e << " " << j.get<double>() << "\n\n";
  }
  return plots.add(
      "contacts", "contacts found on the time axis, per joint",
      "set xlabel 't [s]'\nset ylabel 'joint'\nset yrange [0.5:*]\nplot 'contacts.dat' u 1:2 w lp lw 6 pt 7 "
      "lc rgb '#d62728' t 'contact'\nset autoscale y");
}

/// Sections of a fit report (identify, predict, calibrate's batch) at JSON pointer `path`.
std::string fit_sections(const Json& r, const std::string& path, Plots& plots) {
  std::string out;
  if (r.contains("joints") && r["joints"].is_array()) {
    out += "<section id=\"joints\"><h2>Per joint</h2>" + table_html(r["joints"], path + "/joints", {"joint"}) +
           (r.contains("validation") ? "<p>Validation: " + escape(r.value("validation", "")) + "</p>" : "") +
           "</section>";
  }
  if (r.contains("series")) out += series_plots(r["series"], plots);
  if (r.contains("shapes") && r["shapes"].is_array())
    out +=
        "<section id=\"shapes\"><h2>Shapes</h2><p>Each shape the model holds (docs/diagnose.md \"A shape as a "
        "model term\"): its torque against its variable.</p>" +
        shape_plots(r["shapes"], plots) + "</section>";
  if (r.contains("params") && r["params"].is_array()) {
    Json rows = r["params"];
    out +=
        "<section id=\"parameters\"><h2>Parameters</h2><p>std: one standard deviation; 95 % interval: value "
        "&plusmn; 1.96 std; cad: the robot's CAD value (robot.json) where it has "
        "one.</p><table><thead><tr><th>name</th>"
        "<th>value</th><th>std</th><th>95 % interval</th><th>verdict</th><th>cad</th></tr></thead><tbody>";
    for (size_t i = 0; i < rows.size(); ++i) {
      const Json& p = rows[i];
      const std::string base = path + "/params/" + std::to_string(i);
      const double v = num(p, "value"), sd = num(p, "std");
      const std::string interval =
          std::isfinite(v) && std::isfinite(sd) ? "[" + g6(v - kZ95 * sd) + ", " + g6(v + kZ95 * sd) + "]" : "&ndash;";
      out += "<tr><td>" + escape(p.value("name", "")) + "</td><td>" +
             (p.contains("value") ? value_html(p["value"], base + "/value") : "") + "</td><td>" +
             (p.contains("std") ? value_html(p["std"], base + "/std") : "&ndash;") + "</td><td>" + interval +
             "</td><td>" + escape(p.value("verdict", "")) + "</td><td>" +
             (p.contains("cad") ? value_html(p["cad"], base + "/cad") : "&ndash;") + "</td></tr>";
    }
    out += "</tbody></table>" + cad_plot(rows, plots) + "</section>";
  }
  if (r.contains("links") && r["links"].is_array() && !r["links"].empty())
    out +=
        "<section id=\"links\"><h2>Link inertials</h2><p>Link frame; inertia about the centre of mass "
        "(I11 I12 I13 I22 I23 I33) [kg m&sup2;]; cad_mass: robot.json's.</p>" +
        table_html(r["links"], path + "/links", {"link", "mass", "cad_mass", "com", "cad_com"}) + "</section>";
  if (r.contains("other_logs") && r["other_logs"].is_array() && !r["other_logs"].empty())
    for (size_t i = 0; i < r["other_logs"].size(); ++i)
      out +=
          "<section><h2>Prediction of " + escape(r["other_logs"][i].value("data", "")) + "</h2>" +
          table_html(r["other_logs"][i]["joints"], path + "/other_logs/" + std::to_string(i) + "/joints", {"joint"}) +
          "</section>";
  return out;
}

std::string notes_html(const Json& r, const char* key, const char* title) {
  if (!r.contains(key) || !r[key].is_array() || r[key].empty()) return "";
  std::string out = std::string("<section id=\"") + key + "\"><h2>" + title + "</h2><ul>";
  for (const auto& n : r[key]) out += "<li>" + escape(n.is_string() ? n.get<std::string>() : n.dump()) + "</li>";
  return out + "</ul></section>";
}

const char* kStyle =
    "body{font-family:sans-serif;margin:2em;max-width:1100px;color:#222}h1{font-size:1.5em}h2{font-size:1.2em;"
    "border-bottom:1px solid #ccc;margin-top:1.6em}table{border-collapse:collapse;font-size:0.85em;margin:0.5em "
    "0;display:block;overflow-x:auto;max-width:100%}"
    "td,th{border:1px solid #ddd;padding:2px 6px;text-align:left;vertical-align:top}th{background:#f3f3f3}"
    ".num{font-family:monospace}figure{margin:0.5em 0}img.plot{max-width:100%}figcaption{font-size:0.85em;color:#555}"
    ".pass{background:#e6f4ea;border:1px solid #34a853;padding:0.6em}.fail{background:#fce8e6;border:1px solid "
    "#d93025;padding:0.6em}code{background:#f3f3f3;padding:1px 4px}";

}  // namespace

namespace {

/// The gate's section: passed or failed, the failed items, every item.
std::string gate_section(const Json& g) {
  const bool passed = g.value("passed", false);
  std::string failed;
  for (size_t i = 0; i < g["items"].size(); ++i) {
    const Json& item = g["items"][i];
    if (item.value("passed", false)) continue;
    const std::string p = "/gate/items/" + std::to_string(i);
    failed += "<li>" + escape(item.value("key", "")) + ": " + escape(item.value("what", "")) + " " +
              value_html(item["value"], p + "/value") + ", required " + escape(item.value("bound", "")) + " " +
              value_html(item["limit"], p + "/limit") + "</li>";
  }
  return std::string("<section id=\"gate\"><h2>Gate</h2><div class=\"") + (passed ? "pass" : "fail") + "\">" +
         (passed ? "PASSED" : "FAILED") + ": " + std::to_string(g["items"].size()) + " items checked" +
         (failed.empty() ? "" : "; failed:<ul>" + failed + "</ul>") + "</div><details><summary>every item</summary>" +
         table_html(g["items"], "/gate/items", {"passed", "key", "what", "value", "bound", "limit"}, {"joint"}) +
         "</details></section>";
}

/// diagnose's sections: the effects found, before and after per joint, the series, the candidates
/// rejected, the notes.
std::string diagnose_sections(const Json& report, Plots& plots) {
  std::string body;
  if (report.contains("effects")) {
    body += "<section id=\"effects\"><h2>Effects found</h2>" +
            (report["effects"].empty()
                 ? std::string("<p>None beyond the declared model.</p>")
                 : table_html(report["effects"], "/effects", {"kind", "joints", "item"}, {"joint", "knots", "curve"})) +
            shape_plots(report["effects"], plots) + "</section>";
  }
  if (report.contains("joints")) {
    body += "<section id=\"joints\"><h2>Before and after, per joint</h2>" +
            table_html(report["joints"], "/joints", {"joint"}) + diagnose_plot(report["joints"], plots) + "</section>";
  }
  if (report.contains("series")) body += series_plots(report["series"], plots);
  if (report.contains("rejected") && !report["rejected"].empty())
    body += "<section id=\"rejected\"><h2>Candidates tested and rejected</h2>" +
            table_html(report["rejected"], "/rejected", {"kind", "joints"}) + "</section>";
  body += notes_html(report, "notes", "Notes");
  return body;
}

/// payload's table of quantities with their 95 % intervals.
std::string payload_section(const Json& q) {
  std::string body =
      "<section id=\"payload\"><h2>Payload</h2><table><thead><tr><th>name</th><th>value</th><th>std</th><th>95 % "
      "interval</th><th>unit</th><th>verdict</th></tr></thead><tbody>";
  for (size_t i = 0; i < q.size(); ++i) {
    const std::string base = "/quantities/" + std::to_string(i);
    const double v = num(q[i], "value"), sd = num(q[i], "std");
    body +=
        "<tr><td>" + escape(q[i].value("name", "")) + "</td><td>" + value_html(q[i]["value"], base + "/value") +
        "</td><td>" + value_html(q[i]["std"], base + "/std") + "</td><td>" +
        (std::isfinite(v) && std::isfinite(sd) ? "[" + g6(v - kZ95 * sd) + ", " + g6(v + kZ95 * sd) + "]" : "&ndash;") +
        "</td><td>" + escape(q[i].value("unit", "")) + "</td><td>" + escape(q[i].value("verdict", "")) + "</td></tr>";
  }
  body += "</tbody></table></section>";
  return body;
}

/// monitor's sections: the contacts, the residual plots, the thresholds, the notes.
std::string monitor_sections(const Json& report, Plots& plots) {
  std::string body;
  if (report.contains("contacts")) {
    body += "<section id=\"contacts\"><h2>Contacts</h2>" +
            (report["contacts"].empty() ? std::string("<p>None.</p>")
                                        : table_html(report["contacts"], "/contacts", {"start", "end"}) +
                                              contact_plot(report["contacts"], plots)) +
            "</section>";
  }
  if (report.contains("residual_series"))
    body += monitor_plots(report["residual_series"], report.value("contacts", Json::array()), plots);
  if (report.contains("thresholds"))
    body += "<section id=\"thresholds\"><h2>Thresholds</h2>" +
            table_html(report["thresholds"], "/thresholds", {"joint"}) + "</section>";
  body += notes_html(report, "notes", "Notes");
  return body;
}

}  // namespace

std::string report_page(const std::string& command, const Json& report) {
  Plots plots;
  std::string body;
  const std::string robot = report.value("robot", report.contains("batch") ? report["batch"].value("robot", "") : "");
  body += "<h1>dyncal " + escape(command) + (robot.empty() ? "" : ": " + escape(robot)) + "</h1>";
  if (report.contains("command_line"))
    body += "<p>Command: <code id=\"command-line\">" + escape(report.value("command_line", "")) + "</code></p>";
  if (report.contains("inputs"))
    body += "<section id=\"inputs\"><h2>Inputs</h2>" + table_html(report["inputs"], "/inputs", {"path"}) + "</section>";
  if (report.contains("gate")) body += gate_section(report["gate"]);
  if (command == "calibrate" && report.contains("batch")) {
    body += "<h2>Batch fit on the drive's run</h2>" + fit_sections(report["batch"], "/batch", plots);
    if (report.contains("joints"))
      body += "<section id=\"verification\"><h2>Verification on a fresh trajectory</h2>" +
              table_html(report["joints"], "/joints", {"joint"}) + "</section>";
    if (report.contains("params"))
      body += "<section id=\"estimators\"><h2>Batch, KF and RLS estimates</h2>" +
              table_html(report["params"], "/params", {"name"}) + "</section>";
    body += notes_html(report["batch"], "notes", "Notes") + notes_html(report, "table_notes", "Table notes");
  } else if (command == "diagnose") {
    body += diagnose_sections(report, plots);
  } else if (command == "payload") {
    if (report.contains("quantities")) body += payload_section(report["quantities"]);
    if (report.contains("joints"))
      body += "<section id=\"joints\"><h2>Per joint</h2>" + table_html(report["joints"], "/joints", {"joint"}) +
              "</section>";
    body += notes_html(report, "notes", "Notes");
  } else if (command == "monitor") {
    body += monitor_sections(report, plots);
  } else {
    body += fit_sections(report, "", plots);
    body += notes_html(report, "notes", "Notes");
  }
  std::string page =
      "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta http-equiv=\"Content-Security-Policy\" "
      "content=\"default-src 'none'; img-src data:; style-src 'unsafe-inline'\"><title>dyncal " +
      escape(command) + (robot.empty() ? "" : ": " + escape(robot)) + "</title><style>" + kStyle +
      "</style></head><body>" + plots.place(body);
  return page +
         "<footer><p>Made by dyncal from its JSON report; every number shown is the report's "
         "(docs/report.md).</p></footer></body></html>\n";
}

}  // namespace dyncal::host
