#pragma once
// A private folder for intermediate files (a tool's output before the host's writer publishes it,
// gnuplot's work), removed with its contents however the command ends.

#include <string>

namespace dyncal::host {

/// A new folder under the system's temporary directory (mkdtemp: a fresh name, mode 0700), removed
/// with everything in it when the object goes. Throws InputError when it cannot be created.
class TemporaryFolder {
 public:
  /// `prefix` starts the folder's name ("dyncal-export" gives /tmp/dyncal-export-XXXXXX).
  explicit TemporaryFolder(const std::string& prefix);
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::string& path() const { return path_; }
  /// The bytes of the file `name` in the folder. Throws InputError when it cannot be read.
  std::string read(const std::string& name) const;

 private:
  std::string path_;
};

}  // namespace dyncal::host
