#pragma once
// How much a log's decoders may decompress from one file: bounded by the file, so that a small
// file whose compressed stream claims (and really holds) gigabytes is refused before it is
// allocated (docs/cli.md "ROS 2 bags", "Bounded memory").

#include <cstdint>
#include <string>

namespace dyncal::host {

/// A budget of decompressed bytes for one file of `file_bytes` bytes: kMaxExpansion times the
/// file plus kSlackBytes, at most kMaxBytes. A six-joint 1 kHz JointState MCAP with zstd chunks
/// holds 2.1 times its size with measurement noise and 6.2 times at rest (only the stamps change;
/// tests/tools/write_ros2_bag.py, docs/cli.md): 100 leaves a margin of 16, while a decompression
/// bomb (zstd reaches 30 000 times on zeros) is stopped at that ratio instead of at the machine's
/// memory.
class DecompressionBudget {
 public:
  static constexpr std::uint64_t kMaxExpansion = 100;
  static constexpr std::uint64_t kSlackBytes = std::uint64_t{16} << 20;  ///< 16 MiB: a tiny bag's headroom
  static constexpr std::uint64_t kMaxBytes = std::uint64_t{4} << 30;     ///< 4 GiB per file

  DecompressionBudget(std::uint64_t file_bytes, std::string file);
  /// Bytes still allowed.
  std::uint64_t remaining() const { return limit_ - used_; }
  /// Counts `n` more bytes. Throws InputError (one line naming `where`, the limit and the file's
  /// size) when they exceed the budget; nothing is counted then.
  void take(std::uint64_t n, const std::string& where);
  /// Throws as take() would, without counting: for a stated size checked before it is allocated.
  void check(std::uint64_t n, const std::string& where) const;

 private:
  std::uint64_t limit_ = 0, used_ = 0, file_bytes_ = 0;
  std::string file_;
};

}  // namespace dyncal::host
