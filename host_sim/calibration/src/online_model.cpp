#include "dyncal_host/calibration/online_model.hpp"

#include <map>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

// Function-local static: the robots' static initialisers may run before any other of this file.
std::map<std::string, OnlineModel>& registry() {
  static std::map<std::string, OnlineModel> models;
  return models;
}

}  // namespace

bool register_online_model(const std::string& name, const OnlineModel& model) {
  OnlineModel& entry = registry()[name];
  for (size_t i = 0; i < entry.online.size(); ++i) {
    if (model.online[i]) entry.online[i] = model.online[i];
    if (model.verify[i]) entry.verify[i] = model.verify[i];
  }
  return true;
}

const OnlineModel& online_model(const std::string& name) {
  const auto it = registry().find(name);
  if (it == registry().end()) {
    std::string known;
    for (const auto& [n, m] : registry()) known += (known.empty() ? "" : ", ") + n;
    throw InputError("calibration has no compiled model of '" + name + "' in this build (compiled: " + known +
                     "); add robots/" + name + "/ (docs/robots.md) and build again");
  }
  return it->second;
}

}  // namespace dyncal::host
