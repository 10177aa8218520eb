#pragma once
// The --plots commands' one way of drawing: gnuplot on a script they wrote.

#include <string>

namespace dyncal::host {

/// Runs gnuplot on `dir`/plots.gp, its messages into `dir`/gnuplot.log. Throws InputError when
/// gnuplot fails or is missing (scripts/setup installs gnuplot-nox), naming the log.
void run_gnuplot(const std::string& dir);

}  // namespace dyncal::host
