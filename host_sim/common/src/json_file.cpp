#include "dyncal_host/common/json_file.hpp"

#include <fstream>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

nlohmann::json read_json_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot read '" + path + "'");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(path + ": invalid JSON: " + e.what());
  }
}

}  // namespace dyncal::host
