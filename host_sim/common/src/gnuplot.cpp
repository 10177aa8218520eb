#include "dyncal_host/common/gnuplot.hpp"

#include <cstdlib>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

void run_gnuplot(const std::string& dir) {
  const std::string cmd = "gnuplot '" + dir + "/plots.gp' 2>'" + dir + "/gnuplot.log'";
  if (std::system(cmd.c_str()) != 0)
    throw InputError("gnuplot failed or is missing (scripts/setup installs gnuplot-nox); see " + dir + "/gnuplot.log");
}

}  // namespace dyncal::host
