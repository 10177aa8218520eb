#include "dyncal_host/common/friction_model.hpp"

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

FrictionModel parse_friction_model(const std::string& name) {
  if (name == "eq4") return FrictionModel::eq4;
  if (name == "eq5") return FrictionModel::eq5;
  if (name == "eq6") return FrictionModel::eq6;
  if (name == "eq7") return FrictionModel::eq7;
  if (name == "eq8") return FrictionModel::eq8;
  if (name == "eq9") return FrictionModel::eq9;
  throw InputError("unknown friction model '" + name + "' (eq4, eq5, eq6, eq7, eq8 or eq9)");
}

}  // namespace dyncal::host
