// dyncal diagnose --plots: SVG plots of the residual and the torque through gnuplot.
#include <filesystem>
#include <fstream>

#include "dyncal_host/common/gnuplot.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/diagnosis/diagnose.hpp"

namespace dyncal::host {

using Eigen::Index;

std::vector<std::string> write_diagnose_plots(const DiagnoseResult& r, const std::string& dir) {
  PlotFolder folder(dir);
  const std::string& w = folder.work();
  const auto& tr = r.traces;
  const Index S = tr.t.size(), N = tr.q.cols();
  {
    std::ofstream data(w + "/samples.dat");
    data << "# t, then per joint: q qd tau tau_before tau_after\n";
    for (Index s = 0; s < S; ++s) {
      data << tr.t[s];
      for (Index j = 0; j < N; ++j)
        data << " " << tr.q(s, j) << " " << tr.qd(s, j) << " " << tr.tau(s, j) << " " << tr.tau_before(s, j) << " "
             << tr.tau_after(s, j);
      data << "\n";
    }
    std::ofstream spec(w + "/spectrum.dat");
    for (Index k = 0; k < tr.spectrum.rows(); ++k) {
      spec << k + 1;
      for (Index j = 0; j < N; ++j) spec << " " << std::sqrt(2.0 * tr.spectrum(k, j));  // amplitude [Nm]
      spec << "\n";
    }
  }
  std::vector<std::string> files;
  std::ofstream gp(w + "/plots.gp");
  gp << "set terminal svg size 900,500 dynamic background rgb 'white' noenhanced\nset grid\nset key outside\n";
  for (Index j = 0; j < N; ++j) {
    const Index b = 2 + 5 * j;  // column of q_j
    const std::string J = std::to_string(j + 1);
    auto out = [&](const std::string& name) {
      files.push_back(name);
      gp << "set output '" << name << "'\n";
    };
    out("joint" + J + "_residual_vs_velocity.svg");
    gp << "set title 'joint " << J << ": residual of the declared model vs velocity'\nset xlabel 'qd" << J
       << " [rad/s]'\nset ylabel 'tau - tau_hat [Nm]'\nplot 'samples.dat' u " << b + 1 << ":($" << b + 2 << "-$"
       << b + 3 << ") w p pt 7 ps 0.2 t 'declared model', '' u " << b + 1 << ":($" << b + 2 << "-$" << b + 4
       << ") w p pt 7 ps 0.2 t 'with the effects found'\n";
    out("joint" + J + "_residual_vs_position.svg");
    gp << "set title 'joint " << J << ": residual vs position'\nset xlabel 'q" << J << " [rad]'\nplot 'samples.dat' u "
       << b << ":($" << b + 2 << "-$" << b + 3 << ") w p pt 7 ps 0.2 t 'declared model', '' u " << b << ":($" << b + 2
       << "-$" << b + 4 << ") w p pt 7 ps 0.2 t 'with the effects found'\n";
    out("joint" + J + "_residual_spectrum.svg");
    gp << "set title 'joint " << J << ": residual amplitude by cycles per revolution of q" << J
       << "'\nset xlabel 'cycles per revolution'\nset ylabel 'amplitude [Nm]'\nplot 'spectrum.dat' u 1:" << j + 2
       << " w impulses lw 2 t 'declared model residual'\n";
    out("joint" + J + "_torque.svg");
    gp << "set title 'joint " << J
       << ": measured and predicted torque (fits on all data)'\nset xlabel 't [s]'\nset "
          "ylabel 'tau [Nm]'\nplot 'samples.dat' u 1:"
       << "" << b + 2 << " w l lw 2 t 'measured', '' u 1:" << b + 3 << " w l t 'declared model', '' u 1:" << b + 4
       << " w l t 'with the effects found'\n";
  }
  gp.close();
  return folder.draw(files);
}

}  // namespace dyncal::host
