#include "dyncal_host/drive/file_parameter_store.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <chrono>
#include <exception>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <thread>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

std::vector<std::uint8_t> encoded_table(const ParameterTable& t) {
  std::vector<std::uint8_t> bytes(kTableMaxBytes);
  int size = 0;
  if (encode_table(t, bytes.data(), static_cast<int>(bytes.size()), &size) != TableStatus::ok) {
    throw std::logic_error("cannot encode a parameter table");
  }
  bytes.resize(static_cast<size_t>(size));
  return bytes;
}

FileParameterStore::FileParameterStore(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  const auto kind = std::filesystem::status(path_, ec).type();
  if (kind != std::filesystem::file_type::not_found && kind != std::filesystem::file_type::regular)
    throw InputError(path_ + ": the drive's table file is not a regular file");
}

bool FileParameterStore::exists() const {
  std::error_code ec;
  return std::filesystem::exists(path_, ec);
}

port::PortStatus FileParameterStore::write(const ParameterTable& table, TableStatus* reason) noexcept {
  if (reason) *reason = TableStatus::ok;
  error_.clear();
  try {
    write_file_atomically(path_, encoded_table(table), chunk_delay_ms);
    return port::PortStatus::ok;
  } catch (const std::exception& e) {
    error_ = e.what();
    return port::PortStatus::transport_error;
  }
}

port::PortStatus FileParameterStore::read(ParameterTable& table, TableStatus* reason) noexcept {
  TableStatus st = TableStatus::bad_magic;
  try {
    std::ifstream in(path_, std::ios::binary);
    if (in) {
      std::vector<std::uint8_t> bytes(static_cast<std::size_t>(kTableMaxBytes) + 1);
      in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
      bytes.resize(static_cast<std::size_t>(in.gcount()));
      st = decode_table(bytes.data(), static_cast<int>(bytes.size()), table);
    }
  } catch (const std::exception&) {
    st = TableStatus::bad_magic;  // out of memory for 856 bytes: as unreadable
  }
  if (reason) *reason = st;
  return st == TableStatus::ok ? port::PortStatus::ok : port::PortStatus::rejected;
}

void write_file_atomically(const std::string& path, const std::vector<std::uint8_t>& bytes, int chunk_delay_ms,
                           long cut_at) {
  const std::string tmp = path + ".tmp";
  const long size = static_cast<long>(bytes.size());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create " + tmp);
  for (size_t off = 0; off < bytes.size(); off += 64) {
    size_t n = std::min<size_t>(64, bytes.size() - off);
    const bool cut_here = cut_at >= 0 && cut_at <= static_cast<long>(off + n) && cut_at <= size;
    if (cut_here) n = static_cast<size_t>(cut_at) - off;  // the write in progress torn at cut_at
    if (::write(fd, bytes.data() + off, n) != static_cast<ssize_t>(n)) {
      ::close(fd);
      throw std::runtime_error("cannot write " + tmp);
    }
    if (cut_here) {
      ::close(fd);
      return;
    }
    if (chunk_delay_ms > 0) std::this_thread::sleep_for(std::chrono::milliseconds(chunk_delay_ms));
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) throw std::runtime_error("cannot sync " + tmp);
  if (cut_at == size + 1) return;
  if (::rename(tmp.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot replace " + path);
  if (cut_at == size + 2) return;
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash);
  const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

}  // namespace dyncal::host
