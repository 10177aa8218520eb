#include "dyncal_host/common/output_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdlib>
#include <cstring>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {
namespace {

std::string folder_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return ".";
  return slash == 0 ? "/" : path.substr(0, slash);
}

[[noreturn]] void fail(const char* what, const std::string& path, const std::string& why) {
  throw InputError(std::string("cannot write the ") + what + " '" + path + "': " + why);
}

/// The path the bytes go to: `path`, or the regular file a symbolic link names. Refuses what is not
/// a regular file or a new name in an existing folder. *mode: the existing file's, else -1.
std::string target_of(const std::string& path, const char* what, int* mode) {
  if (path.empty()) fail(what, path, "empty path");
  *mode = -1;
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) {
    if (S_ISDIR(st.st_mode)) fail(what, path, "it is a folder; name a file");
    if (!S_ISREG(st.st_mode)) fail(what, path, "it exists and is not a regular file (a FIFO, device or socket)");
    *mode = static_cast<int>(st.st_mode & 07777);
    char resolved[PATH_MAX];
    if (::realpath(path.c_str(), resolved) == nullptr) fail(what, path, std::strerror(errno));
    return resolved;
  }
  if (errno != ENOENT) fail(what, path, std::strerror(errno));
  struct stat dir {};
  const std::string folder = folder_of(path);
  if (::stat(folder.c_str(), &dir) != 0 || !S_ISDIR(dir.st_mode)) fail(what, path, "no folder '" + folder + "'");
  if (path.back() == '/') fail(what, path, "it names a folder; name a file");
  return path;
}

mode_t process_umask() {
  const mode_t u = ::umask(022);
  ::umask(u);
  return u;
}

}  // namespace

void check_output_path(const std::string& path, const char* what) {
  int mode = -1;
  const std::string target = target_of(path, what, &mode);
  if (::access(folder_of(target).c_str(), W_OK) != 0)
    fail(what, path, "its folder '" + folder_of(target) + "' is not writable");
}

void write_output_file(const std::string& path, std::string_view bytes, const char* what) {
  int mode = -1;
  const std::string target = target_of(path, what, &mode);
  const std::string folder = folder_of(target);
  std::string tmp = target + ".XXXXXX";
  const int fd = ::mkstemp(tmp.data());
  if (fd < 0) fail(what, path, std::string("cannot create a temporary file beside it: ") + std::strerror(errno));
  const auto abandon = [&](const std::string& why) {
    ::close(fd);
    ::unlink(tmp.c_str());
    fail(what, path, why);
  };
  const mode_t wanted = mode >= 0 ? static_cast<mode_t>(mode) : (0666 & ~process_umask());
  if (::fchmod(fd, wanted) != 0) abandon(std::strerror(errno));
  size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) abandon(std::strerror(n < 0 ? errno : EIO));
    done += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) abandon(std::strerror(errno));
  if (::close(fd) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    fail(what, path, std::strerror(e));
  }
  if (::rename(tmp.c_str(), target.c_str()) != 0) {
    const int e = errno;
    ::unlink(tmp.c_str());
    fail(what, path, std::strerror(e));
  }
  const int dfd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace dyncal::host
