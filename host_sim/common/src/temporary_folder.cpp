#include "dyncal_host/common/temporary_folder.hpp"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace fs = std::filesystem;

TemporaryFolder::TemporaryFolder(const std::string& prefix) {
  std::error_code ec;
  std::string path = (fs::temp_directory_path(ec) / (prefix + "-XXXXXX")).string();
  if (ec || ::mkdtemp(path.data()) == nullptr)
    throw InputError("cannot create a temporary folder (" + prefix + ") under the system's temporary directory");
  path_ = path;
}

TemporaryFolder::~TemporaryFolder() {
  std::error_code ignored;
  fs::remove_all(path_, ignored);
}

std::string TemporaryFolder::read(const std::string& name) const {
  const std::string file = path_ + "/" + name;
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError("cannot read " + file);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError("cannot read " + file);
  return bytes;
}

}  // namespace dyncal::host
