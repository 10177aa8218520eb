// dyncal: the command-line tool. Each subcommand lives in its own file (commands.hpp).
#include "entry_points.hpp"

int main(int argc, char** argv) {
  return dyncal::app::run_dyncal(argc, argv);
}
