#include "dyncal_host/identification/pipeline/drive_law.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/json_file.hpp"
#include "dyncal_host/common/trajectory_file.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "dyncal_host/model/drive_table.hpp"

namespace dyncal::host {
namespace {

double positive(const nlohmann::json& j, const char* key, const std::string& where) {
  if (!j.contains(key) || !j[key].is_number()) throw InputError(where + ": \"" + key + "\" must be a number");
  const double v = j[key].get<double>();
  if (!(v > 0.0) || !std::isfinite(v)) throw InputError(where + ": \"" + key + "\" must be finite and > 0");
  return v;
}

std::vector<double> gains(const nlohmann::json& j, const char* key, int n, const std::string& where) {
  if (!j.contains(key) || !j[key].is_array() || static_cast<int>(j[key].size()) != n)
    throw InputError(where + ": \"" + key + "\" must be an array of " + std::to_string(n) + " numbers, one per joint");
  std::vector<double> out;
  for (const auto& v : j[key]) {
    if (!v.is_number() || !(v.get<double>() > 0.0) || !std::isfinite(v.get<double>()))
      throw InputError(where + ": \"" + key + "\" joint " + std::to_string(out.size() + 1) +
                       ": a gain is finite and > 0");
    out.push_back(v.get<double>());
  }
  return out;
}

}  // namespace

DriveLaw read_drive_law(const std::string& path, const RobotDescription& robot) {
  const nlohmann::json j = read_json_file(path);
  if (!j.is_object()) throw InputError(path + ": a law file is a JSON object");
  const std::filesystem::path dir = std::filesystem::path(path).parent_path();
  auto relative = [&](const std::string& p) { return std::filesystem::path(p).is_absolute() ? p : (dir / p).string(); };
  DriveLaw law;
  law.source = path;
  if (!j.contains("trajectory")) throw InputError(path + ": \"trajectory\" is missing (an excite file or its path)");
  try {
    law.trajectory = trajectory_from_json(robot, j["trajectory"].is_string()
                                                     ? read_json_file(relative(j["trajectory"].get<std::string>()))
                                                     : j["trajectory"]);
  } catch (const InputError& e) {
    throw InputError(path + ": trajectory: " + e.what());
  }
  const double periods = positive(j, "periods", path);
  if (periods != std::floor(periods) || periods > 1000)
    throw InputError(path + ": \"periods\" must be a whole number 1..1000");
  law.periods = static_cast<int>(periods);
  law.sample_rate_hz = positive(j, "sample_rate_hz", path);
  if (j.contains("control_rate_hz")) law.control_rate_hz = positive(j, "control_rate_hz", path);
  law.kp = gains(j, "kp", robot.num_joints, path);
  law.kd = gains(j, "kd", robot.num_joints, path);
  if (j.contains("feed_forward") && j.contains("feed_forward_table"))
    throw InputError(path + ": \"feed_forward\" and \"feed_forward_table\": give one");
  if (j.contains("feed_forward_table")) {
    // The table as the drive held it (calibrate --save-law): its bytes, CRC-checked.
    if (!j["feed_forward_table"].is_string())
      throw InputError(path + ": \"feed_forward_table\" must be the path of a table file (calibrate --save-law)");
    const std::string file = relative(j["feed_forward_table"].get<std::string>());
    std::ifstream in(file, std::ios::binary);
    if (!in) throw InputError(path + ": feed_forward_table: cannot read " + file);
    const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const TableStatus st = decode_table(bytes.data(), static_cast<int>(bytes.size()), law.table);
    if (st != TableStatus::ok) throw InputError(path + ": feed_forward_table " + file + ": " + to_string(st));
    if (law.table.robot_id != compiled_robot(robot.name).robot_id)
      throw InputError(path + ": feed_forward_table " + file + ": a table of another robot than '" + robot.name + "'");
    law.has_table = true;
  }
  if (j.contains("feed_forward")) {
    if (!j["feed_forward"].is_string())
      throw InputError(path + ": \"feed_forward\" must be the path of a dyncal identify --params file");
    try {
      law.table = parameter_table(read_parameter_file(relative(j["feed_forward"].get<std::string>())), robot, nullptr);
    } catch (const InputError& e) {
      throw InputError(path + ": feed_forward: " + e.what());  // e.g. parameters of another robot
    }
    law.has_table = true;
  }
  return law;
}

}  // namespace dyncal::host
