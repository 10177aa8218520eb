#pragma once
// sensor_msgs/msg/JointState in ROS 2's serialisation (OMG CDR, XCDR1 as rmw writes it): a 4-byte
// encapsulation header (0x00 0x00 big endian, 0x00 0x01 little endian), then, aligned to their
// size counted from after that header: std_msgs/Header (stamp.sec i32, stamp.nanosec u32,
// frame_id string), name (u32 count, strings), position, velocity, effort (u32 count, float64s).
// A string is a u32 length counting its terminating NUL, then its bytes.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dyncal::host {

/// A decoded JointState. Units as the message defines them: rad (revolute), rad/s, Nm (or
/// whatever the driver puts in effort).
struct JointStateMessage {
  std::int32_t stamp_sec = 0;
  std::uint32_t stamp_nanosec = 0;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;
  /// The header stamp [ns since the epoch].
  std::int64_t stamp_ns() const { return std::int64_t{stamp_sec} * 1000000000 + stamp_nanosec; }
};

/// Decodes `size` bytes at `data`. Returns false and sets `error` (what and at which byte) when the
/// bytes are not a JointState: an unknown encapsulation, a field or count running past the end, a
/// string without its NUL, a nanosec of 1e9 or more.
bool decode_joint_state(const std::uint8_t* data, std::size_t size, JointStateMessage& out, std::string& error);

}  // namespace dyncal::host
