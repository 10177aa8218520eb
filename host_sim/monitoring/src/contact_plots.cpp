// dyncal monitor --plots: SVG plots of each joint's observer residual with its contact threshold,
// through gnuplot.
#include <filesystem>
#include <fstream>

#include "dyncal_host/common/gnuplot.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/monitoring/contact_monitor.hpp"

namespace dyncal::host {

std::vector<std::string> write_contact_plots(const ObserverRun& run, const ResidualStatistics& s,
                                             const std::vector<ContactThreshold>& thresholds,
                                             const std::vector<Contact>& contacts, const std::string& dir) {
  PlotFolder folder(dir);
  const std::string& w = folder.work();
  const Eigen::Index N = run.r.cols();
  {
    std::ofstream data(w + "/residual.dat");
    data << "# t, then per joint: r - mean, the threshold at that sample (widened at rest) [Nm]\n";
    for (const auto& [a, b] : run.segments) {
      for (Eigen::Index k = a; k < b; ++k) {
        data << run.t[k];
        for (Eigen::Index j = 0; j < N; ++j) {
          const size_t i = static_cast<size_t>(j);
          data << " " << run.r(k, j) - s.mean[i] << " "
               << thresholds[i].value + run.friction_weight(k, j) * run.static_friction[i];
        }
        data << "\n";
      }
      data << "\n";  // a gap between segments
    }
  }
  std::vector<std::string> files;
  std::ofstream gp(w + "/plots.gp");
  gp << "set terminal svg size 1000,450 dynamic background rgb 'white' noenhanced\nset grid\nset key outside\n"
        "set xlabel 't [s]'\nset ylabel '[Nm]'\n";
  for (const auto& c : contacts)
    gp << "set object rect from " << c.start << ", graph 0 to " << c.end
       << ", graph 1 fc rgb '#ffcccc' fs solid 0.5 noborder behind\n";
  for (Eigen::Index j = 0; j < N; ++j) {
    const Eigen::Index col = 2 + 2 * j;
    const std::string J = std::to_string(j + 1), name = "joint" + J + "_residual.svg";
    files.push_back(name);
    gp << "set output '" << name << "'\nset title 'joint " << J
       << ": momentum observer residual r - mean and the contact threshold (contacts shaded)'\nplot 'residual.dat' u 1:"
       << col << " w l t 'r - mean', '' u 1:" << col + 1 << " w l lw 2 t 'threshold', '' u 1:(-$" << col + 1
       << ") w l lw 2 t ''\n";
  }
  gp.close();
  return folder.draw(files);
}

}  // namespace dyncal::host
