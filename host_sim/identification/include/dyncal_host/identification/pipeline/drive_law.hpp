#pragma once
// Reading the control law a log was recorded under (common/drive_law.hpp) from a law file
// (docs/cli.md "Law file", identify --law).

#include <string>

#include "dyncal_host/common/drive_law.hpp"
#include "dyncal_host/common/robot_description.hpp"

namespace dyncal::host {

/// Reads a law file: {"trajectory": an excite file's object or its path (relative to the law
/// file), "periods", "sample_rate_hz", "kp": [N], "kd": [N], optional "control_rate_hz" and
/// "feed_forward": an identify --params file's path or "feed_forward_table": a table file's path
/// (the encoded table as the drive held it, calibrate --save-law; CRC-checked; absent: the factory
/// table)}. Paths relative to the law file. Throws InputError
/// naming the file and the field: not JSON, a field missing or of the wrong type or length, gains not
/// finite and positive, rates not positive, a trajectory outside the robot's limits, parameters of
/// another robot.
DriveLaw read_drive_law(const std::string& path, const RobotDescription& robot);

}  // namespace dyncal::host
