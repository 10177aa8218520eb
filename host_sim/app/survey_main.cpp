// dyncal-survey: the survey's simulation study (`dyncal survey` runs this program).
// Invoked as `dyncal-survey survey OPTIONS`; dyncal's launcher passes "dyncal" as argv[0], so that
// usage and help read `dyncal survey`.
#include "entry_points.hpp"

int main(int argc, char** argv) {
  return dyncal::app::run_dyncal_survey(argc, argv);
}
