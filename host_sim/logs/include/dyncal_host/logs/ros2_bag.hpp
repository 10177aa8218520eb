#pragma once
// A ROS 2 bag's sensor_msgs/msg/JointState topic as a JointLog (docs/cli.md, "Logs"): an .mcap
// file, a .db3 file, or a rosbag2 folder (metadata.yaml naming its .mcap or .db3 files, read with
// yaml-cpp; zstd FILE or MESSAGE compression undone).

#include <string>
#include <vector>

#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// The clock a bag's samples are put on: the JointState's header stamp (when the driver sampled
/// the joints) or the log time (when the recorder received the message).
enum class BagClock { header, log };

struct BagLogOptions {
  std::string topic;  ///< the JointState topic; empty: the bag's only one
  BagClock clock = BagClock::header;
  std::vector<std::string> joint_names;  ///< the robot's joint names, joint 1 first (robot.json)
};

/// A bag read as a log, and what the reading found: the topic, the two clocks (period and jitter of
/// each), the joints ignored, messages without the robot's joints.
struct BagLog {
  JointLog log;  ///< tau holds JointState.effort as recorded (joint torque or motor current)
  std::vector<std::string> notes;
};

/// True when `path` is an MCAP file, a SQLite3 file named .db3, or a folder with a metadata.yaml.
/// Throws InputError for a file named .mcap or .db3 without that storage's magic (the real cause,
/// rather than reading it as a CSV).
bool is_ros2_bag(const std::string& path);

/// Reads the bag at `path`. Each message's joints are matched by name to `options.joint_names`
/// (other joints ignored); position [rad], velocity [rad/s] (when every message has it) and
/// effort as recorded. t [s] counts from the first sample on the chosen clock; the stamps are
/// integers of ns, subtracted before they become doubles (an epoch time in seconds as a double
/// keeps only 0.2 us). Messages are put in the clock's order. Throws InputError on one line: the
/// storage's errors (mcap_reader.hpp, sqlite_bag.hpp), no or several JointState topics without
/// `topic`, `topic` absent or not a JointState, a message that does not decode (its index and
/// byte), a message with some but not all of the robot's joints or lengths that disagree with its
/// names, no position or effort, a clock that repeats a time (the duplicate named), header stamps
/// that are not set (all zero: use the log time).
BagLog read_ros2_bag_log(const std::string& path, const BagLogOptions& options);

}  // namespace dyncal::host
