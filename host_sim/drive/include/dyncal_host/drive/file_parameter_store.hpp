#pragma once
// The Linux simulated drive's flash: a parameter table in a regular file, replaced atomically
// (lib/'s port::ParameterStore, dyncal/port.hpp, which the drive application stores through).

#include <cstdint>
#include <string>
#include <vector>

#include "dyncal/parameter_table.hpp"
#include "dyncal/port.hpp"

namespace dyncal::host {

class FileParameterStore final : public port::ParameterStore {
 public:
  /// The store in file `path` (it need not exist). Throws InputError when `path` exists and is not
  /// a regular file (a FIFO would block the drive before it is ready, a device such as /dev/zero
  /// would never end).
  explicit FileParameterStore(std::string path);

  /// Encodes `table` and replaces the file with it (write_file_atomically): ok, or transport_error
  /// with the file as it was and error() saying why; *reason ok either way (the table's checks are
  /// the drive application's).
  port::PortStatus write(const ParameterTable& table, TableStatus* reason) noexcept override;
  /// Decodes the file (read up to one byte past the largest table): ok, or rejected with *reason
  /// (bad_magic for a missing or empty file).
  port::PortStatus read(ParameterTable& table, TableStatus* reason) noexcept override;

  /// Whether the file exists.
  bool exists() const;
  const std::string& path() const { return path_; }
  /// Why the last write failed (empty after one that did not).
  const std::string& error() const { return error_; }
  /// Milliseconds to sleep after each 64-byte chunk written (0: none): lets tests kill the drive in
  /// the middle of a flash.
  int chunk_delay_ms = 0;

 private:
  std::string path_;
  std::string error_;
};

/// `t` encoded as the drive's flash holds it (parameter_table.hpp). Throws std::logic_error if it
/// does not encode (a table built by the host always does).
std::vector<std::uint8_t> encoded_table(const ParameterTable& t);

/// Writes `bytes` to `path` atomically (temporary file in the same directory, fsync, rename, fsync
/// of the directory): a crash at any moment leaves the old or the new content. Throws
/// std::runtime_error on I/O failure. This is the parameter store's only write path, and its seam
/// for crash tests: `cut_at` >= 0 simulates the process dying at that point and returns there —
/// 0..size: after that many bytes of the temporary file (the write in progress torn at that
/// offset), before its fsync; size + 1: after the fsync, before the rename; size + 2: after the
/// rename, before the directory's fsync. -1: no cut.
void write_file_atomically(const std::string& path, const std::vector<std::uint8_t>& bytes, int chunk_delay_ms = 0,
                           long cut_at = -1);

}  // namespace dyncal::host
