#include "dyncal_host/common/gnuplot.hpp"

#include <cstdlib>
#include <filesystem>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/output_file.hpp"

namespace dyncal::host {
namespace fs = std::filesystem;

bool run_gnuplot(const TemporaryFolder& work) {
  const std::string cmd = "cd '" + work.path() + "' && gnuplot plots.gp 2>gnuplot.log";
  return std::system(cmd.c_str()) == 0;
}

std::vector<std::string> SvgPlots::draw(const std::vector<std::string>& svg_names) {
  if (!run_gnuplot(work_)) {
    const std::string log = work_.read("gnuplot.log");
    throw InputError("gnuplot failed or is missing (scripts/setup installs gnuplot-nox): " +
                     log.substr(0, log.find('\n')));
  }
  std::vector<std::string> texts;
  for (const std::string& name : svg_names) texts.push_back(work_.read(name));
  return texts;
}

PlotFolder::PlotFolder(std::string dir) : dir_(std::move(dir)), work_("dyncal-plots") {
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw InputError("--plots '" + dir_ + "': it exists and is not a folder");
  fs::create_directories(dir_, ec);
  if (ec) throw InputError("--plots '" + dir_ + "': cannot create the folder: " + ec.message());
}

std::vector<std::string> PlotFolder::draw(const std::vector<std::string>& svg_names) {
  if (!run_gnuplot(work_)) {
    write_output_file(dir_ + "/gnuplot.log", work_.read("gnuplot.log"), "gnuplot log");
    throw InputError("gnuplot failed or is missing (scripts/setup installs gnuplot-nox); see " + dir_ + "/gnuplot.log");
  }
  for (const auto& entry : fs::directory_iterator(work_.path())) {
    const std::string name = entry.path().filename().string();
    if (name == "gnuplot.log" || !entry.is_regular_file()) continue;
    write_output_file(dir_ + "/" + name, work_.read(name), "plot file");
  }
  std::vector<std::string> paths;
  for (const std::string& name : svg_names) paths.push_back(dir_ + "/" + name);
  return paths;
}

}  // namespace dyncal::host
