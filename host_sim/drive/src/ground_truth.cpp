#include "dyncal_host/drive/ground_truth.hpp"

#include "dyncal_host/drive/drive_plant.hpp"

namespace dyncal::host {

std::vector<TrueParameter> true_parameters(const Scenario& s, unsigned terms) {
  return make_drive_plant(s.robot)->true_parameters(s, terms);
}

}  // namespace dyncal::host
