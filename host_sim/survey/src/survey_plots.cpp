// dyncal survey --plots: the survey's Fig. 2 and Fig. 4 and the residual per joint per method, as
// SVG through gnuplot (as dyncal diagnose --plots).
#include "dyncal_host/survey/survey_plots.hpp"

#include <filesystem>
#include <fstream>

#include "dyncal_host/common/gnuplot.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host::survey {
namespace {

std::ofstream open_data(const std::string& path) {
  std::ofstream f(path);
  if (!f) throw InputError("cannot write '" + path + "'");
  f.precision(9);
  return f;
}

const char* model_title(const std::string& model) {
  return model == "eq7" ? "Eq. 7" : "Eq. 4";
}

}  // namespace

namespace {

/// Adds `name` to `files` and sets it as gnuplot's output.
void svg_output(std::ofstream& gp, std::vector<std::string>& files, const std::string& name) {
  files.push_back(name);
  gp << "set output '" << name << "'\n";
}

/// Fig. 2: each model's excitation as the drive played it (data and script in the work folder `w`).
void plot_trajectories(const SurveySeries& series, const std::string& w, std::ofstream& gp,
                       std::vector<std::string>& files) {
  for (const SurveySeries::Trajectory& tr : series.trajectories) {
    const std::string data = "trajectory_" + tr.model + ".dat";
    std::ofstream f = open_data(w + "/" + data);
    f << "# t [s], q1..q6 [rad]: the designed excitation (Eq. 27) as the drive played it\n";
    for (Eigen::Index s = 0; s < tr.t.size(); ++s) {
      f << tr.t[s];
      for (Eigen::Index j = 0; j < tr.q.cols(); ++j) f << " " << tr.q(s, j);
      f << "\n";
    }
    svg_output(gp, files, "fig2_trajectories_" + tr.model + ".svg");
    gp << "set title 'Fig. 2: joint positions of the excitation designed for " << model_title(tr.model)
       << " (cond(K) minimised, L = 5, f_f = 0.1 Hz)'\nset key outside\nset xlabel 't [s]'\nset ylabel 'q [rad]'\n"
       << "plot for [j=1:" << tr.q.cols() << "] '" << data << "' u 1:(column(j+1)) w l lw 2 t sprintf('joint %d', j)\n";
  }
}

/// The RMS torque residual per joint and method, without and with noise, per model.
void plot_residual_rms(const nlohmann::json& result, const std::string& w, std::ofstream& gp,
                       std::vector<std::string>& files) {
  for (const char* model : {"eq7", "eq4"}) {
    if (!result.contains("models") || !result["models"].contains(model)) continue;
    const nlohmann::json& methods = result["models"][model]["methods"];
    const std::string data = std::string("residual_rms_") + model + ".dat";
    std::ofstream f = open_data(w + "/" + data);
    std::vector<std::string> names;
    for (auto& [name, m] : methods.items()) names.push_back(name);
    for (const char* noise : {"without_noise", "with_noise"}) {
      f << "# " << noise << ": joint, then per method (";
      for (const std::string& n : names) f << n << (&n == &names.back() ? ")" : ", ");
      f << " the RMS of tau - tau_hat [Nm]\n";
      for (size_t j = 0; j < 6; ++j) {
        f << j + 1;
        for (const std::string& n : names) f << " " << methods[n][noise]["residual_rms"][j].get<double>();
        f << "\n";
      }
      f << "\n\n";
    }
    svg_output(gp, files, std::string("residual_rms_") + model + ".svg");
    gp << "set terminal svg size 1000,900 dynamic background rgb 'white' noenhanced\n"
       << "set multiplot layout 2,1 title 'RMS torque residual per joint and method, " << model_title(model)
       << " runs'\nset style data histograms\nset style histogram cluster gap 1\nset style fill solid 0.9 noborder\n"
       << "set xlabel 'joint'\nset ylabel 'RMS(tau - tau_hat) [Nm]'\nset logscale y\nset format y '%g'\nset key "
          "outside right top font "
          "',9'\n";
    for (int block = 0; block < 2; ++block) {
      gp << "set title '" << (block == 0 ? "without noise" : "with Table 7 noise") << "'\nplot ";
      for (size_t i = 0; i < names.size(); ++i) {
        gp << (i ? ", " : "") << "'" << data << "' index " << block << " u " << i + 2 << (i ? "" : ":xtic(1)") << " t '"
           << names[i] << "'";
      }
      gp << "\n";
    }
    gp << "unset multiplot\nunset logscale y\nset format y\nset style data lines\n"
       << "set terminal svg size 900,600 dynamic background rgb 'white' noenhanced\n";
  }
}

/// Fig. 4: joint 3's beta followed by each method, per change profile.
void plot_tracking(const SurveySeries& series, const std::string& w, std::ofstream& gp,
                   std::vector<std::string>& files) {
  for (const SurveySeries::Tracking& tk : series.tracking) {
    const std::string data = "tracking_" + tk.model + ".dat";
    std::ofstream f = open_data(w + "/" + data);
    // One block per profile: N, beta, then every method's beta_hat.
    std::vector<std::string> profiles, methods;
    for (const TrackingResult& t : tk.runs) {
      if (std::find(profiles.begin(), profiles.end(), to_string(t.profile)) == profiles.end())
        profiles.push_back(to_string(t.profile));
      if (std::find(methods.begin(), methods.end(), t.method) == methods.end()) methods.push_back(t.method);
    }
    for (const std::string& p : profiles) {
      std::vector<const TrackingResult*> runs;
      for (const TrackingResult& t : tk.runs) {
        if (to_string(t.profile) == p) runs.push_back(&t);
      }
      f << "# " << p << ": N, beta_3 [Nm s/rad], then the estimate of each of";
      for (const TrackingResult* t : runs) f << " '" << t->method << "'";
      f << "\n";
      for (size_t n = 0; n < runs.front()->beta.size(); ++n) {
        f << n + 1 << " " << runs.front()->beta[n];
        for (const TrackingResult* t : runs) f << " " << t->beta_hat[n];
        f << "\n";
      }
      f << "\n\n";
    }
    svg_output(gp, files, "fig4_tracking_" + tk.model + ".svg");
    gp << "set terminal svg size 900,900 dynamic background rgb 'white' noenhanced\n"
       << "set multiplot layout " << profiles.size() << ",1 title 'Fig. 4: following beta of joint 3, "
       << model_title(tk.model) << " run with Table 7 noise'\nset key inside top left opaque font ',9'\n"
       << "set xlabel 'N (sample)'\n"
       << "set ylabel 'beta_3 [Nm s/rad]'\nset yrange [0:100]\n";
    for (size_t b = 0; b < profiles.size(); ++b) {
      gp << "set title '" << profiles[b] << " change'\nplot '" << data << "' index " << b
         << " u 1:2 w l lw 3 lc rgb 'black' t 'beta (set)'";
      for (size_t i = 0; i < methods.size(); ++i)
        gp << ", '' index " << b << " every 4 u 1:" << i + 3 << " w l t '" << methods[i] << "'";
      gp << "\n";
    }
    gp << "unset multiplot\nset autoscale y\n"
       << "set terminal svg size 900,600 dynamic background rgb 'white' noenhanced\n";
  }
}

}  // namespace

std::vector<std::string> write_survey_plots(const nlohmann::json& result, const SurveySeries& series,
                                            const std::string& dir) {
  PlotFolder folder(dir);
  const std::string& w = folder.work();
  std::vector<std::string> files;
  std::ofstream gp = open_data(w + "/plots.gp");
  gp << "set terminal svg size 900,600 dynamic background rgb 'white' noenhanced\nset grid\n";
  plot_trajectories(series, w, gp, files);
  plot_residual_rms(result, w, gp, files);
  plot_tracking(series, w, gp, files);
  gp.close();
  return folder.draw(files);
}

}  // namespace dyncal::host::survey
