#pragma once
// The --plots commands' one way of drawing: gnuplot on a script they wrote, in a folder of their
// own, the results then written into the user's folder by the host's one writer (output_file.hpp).

#include <string>
#include <vector>

#include "dyncal_host/common/temporary_folder.hpp"

namespace dyncal::host {

/// Runs gnuplot on `work`/plots.gp in `work` (its log in work/gnuplot.log). Returns false when
/// gnuplot fails or is missing (scripts/setup installs gnuplot-nox).
bool run_gnuplot(const TemporaryFolder& work);

/// SVG plots drawn into memory (an HTML page embeds them): write the data and plots.gp into work(),
/// then draw() runs gnuplot and returns each SVG's text. Throws InputError (one line): gnuplot failed
/// or is missing, with the first line of its log.
class SvgPlots {
 public:
  SvgPlots() : work_("dyncal-svg") {}
  const std::string& work() const { return work_.path(); }
  std::vector<std::string> draw(const std::vector<std::string>& svg_names);

 private:
  TemporaryFolder work_;
};

/// A --plots folder, drawn all or nothing per file. The data files and the script plots.gp are
/// written into work(), a private temporary folder, naming each other by bare file names (so the
/// published script redraws in its own folder: `cd DIR && gnuplot plots.gp`); draw() runs gnuplot
/// there and writes every file it holds into the user's folder through write_output_file. The
/// folder must be a folder or a new name in an existing one's tree (created then). Throws
/// InputError (one line): the folder is a file, cannot be created, gnuplot fails or is missing
/// (scripts/setup installs gnuplot-nox; its log is then written into the folder and named), or a
/// file cannot be written. The work folder is removed in every case.
class PlotFolder {
 public:
  explicit PlotFolder(std::string dir);
  PlotFolder(const PlotFolder&) = delete;
  PlotFolder& operator=(const PlotFolder&) = delete;
  /// The private folder the data and plots.gp go to.
  const std::string& work() const { return work_.path(); }
  /// Runs gnuplot on work()/plots.gp in work(), then writes every file of work() but gnuplot's log
  /// into the folder. Returns the paths there of `svg_names` (bare names the script wrote).
  std::vector<std::string> draw(const std::vector<std::string>& svg_names);

 private:
  std::string dir_;
  TemporaryFolder work_;
};

}  // namespace dyncal::host
