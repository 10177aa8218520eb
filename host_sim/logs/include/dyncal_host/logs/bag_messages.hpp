#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace dyncal::host {

/// A topic of a ROS 2 bag as its storage declares it.
struct BagTopic {
  std::string name;      ///< e.g. /joint_states
  std::string type;      ///< ROS type, e.g. sensor_msgs/msg/JointState (MCAP: the schema's name)
  std::string encoding;  ///< serialisation, e.g. cdr
};

/// One serialised message of a kept topic.
struct BagMessage {
  int topic = 0;              ///< index into BagMessages::topics
  std::int64_t log_time = 0;  ///< the recorder's receive time [ns since the epoch]
  std::vector<std::uint8_t> data;
};

/// The topics of a bag and the messages of those its reader was asked to keep, in storage order.
struct BagMessages {
  std::vector<BagTopic> topics;
  std::vector<BagMessage> messages;
};

/// Which topics' messages a bag reader keeps (the others are skipped without being copied).
using KeepTopic = std::function<bool(const BagTopic&)>;

}  // namespace dyncal::host
