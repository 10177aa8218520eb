#include "dyncal_host/common/gnuplot.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/output_file.hpp"

namespace dyncal::host {
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

PlotFolder::PlotFolder(std::string dir) : dir_(std::move(dir)) {
  std::error_code ec;
  if (fs::exists(dir_, ec) && !fs::is_directory(dir_, ec))
    throw InputError("--plots '" + dir_ + "': it exists and is not a folder");
  fs::create_directories(dir_, ec);
  if (ec) throw InputError("--plots '" + dir_ + "': cannot create the folder: " + ec.message());
  std::string work = (fs::temp_directory_path(ec) / "dyncal-plots-XXXXXX").string();
  if (ec || ::mkdtemp(work.data()) == nullptr) throw InputError("cannot create a temporary folder for the plots");
  work_ = work;
}

PlotFolder::~PlotFolder() {
  std::error_code ignored;
  fs::remove_all(work_, ignored);
}

std::vector<std::string> PlotFolder::draw(const std::vector<std::string>& svg_names) {
  const std::string cmd = "cd '" + work_ + "' && gnuplot plots.gp 2>gnuplot.log";
  if (std::system(cmd.c_str()) != 0) {
    write_output_file(dir_ + "/gnuplot.log", slurp(fs::path(work_) / "gnuplot.log"), "gnuplot log");
    throw InputError("gnuplot failed or is missing (scripts/setup installs gnuplot-nox); see " + dir_ + "/gnuplot.log");
  }
  for (const auto& entry : fs::directory_iterator(work_)) {
    const std::string name = entry.path().filename().string();
    if (name == "gnuplot.log" || !entry.is_regular_file()) continue;
    write_output_file(dir_ + "/" + name, slurp(entry.path()), "plot file");
  }
  std::vector<std::string> paths;
  for (const std::string& name : svg_names) paths.push_back(dir_ + "/" + name);
  return paths;
}

}  // namespace dyncal::host
