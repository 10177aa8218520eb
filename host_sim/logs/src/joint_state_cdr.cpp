#include "dyncal_host/logs/joint_state_cdr.hpp"

#include <cstring>

namespace dyncal::host {
namespace {

class CdrReader {
 public:
  CdrReader(const std::uint8_t* p, std::size_t n, bool little) : p_(p), n_(n), little_(little) {}

  bool u32(std::uint32_t& v, const char* what) {
    if (!take(4, what)) return false;
    v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(byte(i)) << (8 * (little_ ? i : 3 - i));
    at_ += 4;
    return true;
  }
  bool f64(double& v, const char* what) {
    if (!take(8, what)) return false;
    std::uint64_t bits = 0;
    for (int i = 0; i < 8; ++i) bits |= static_cast<std::uint64_t>(byte(i)) << (8 * (little_ ? i : 7 - i));
    std::memcpy(&v, &bits, 8);
    at_ += 8;
    return true;
  }
  bool string(std::string& s, const char* what) {
    std::uint32_t len = 0;
    if (!u32(len, what)) return false;
    if (len > n_ - at_)
      return fail(std::string(what) + ": a string of " + std::to_string(len) + " bytes runs past the end");
    if (len == 0 || p_[at_ + len - 1] != 0) return fail(std::string(what) + ": a string without its terminating NUL");
    s.assign(reinterpret_cast<const char*>(p_ + at_), len - 1);
    at_ += len;
    return true;
  }
  bool doubles(std::vector<double>& v, const char* what) {
    std::uint32_t count = 0;
    if (!u32(count, what)) return false;
    if (count > 0 && !align(8, what)) return false;
    if (count > (n_ - at_) / 8)
      return fail(std::string(what) + ": " + std::to_string(count) + " values run past the end");
    v.resize(count);
    for (auto& x : v)
      if (!f64(x, what)) return false;
    return true;
  }
  bool strings(std::vector<std::string>& v, const char* what) {
    std::uint32_t count = 0;
    if (!u32(count, what)) return false;
    if (count > (n_ - at_) / 5)
      return fail(std::string(what) + ": " + std::to_string(count) + " strings run past the end");
    v.resize(count);
    for (auto& s : v)
      if (!string(s, what)) return false;
    return true;
  }
  std::string error;

 private:
  std::uint8_t byte(int i) const { return p_[at_ + static_cast<std::size_t>(i)]; }
  bool align(std::size_t a, const char* what) {
    const std::size_t pad = (a - at_ % a) % a;
    if (pad > n_ - at_) return fail(std::string(what) + ": the message ends at byte " + std::to_string(n_ + 4));
    at_ += pad;
    return true;
  }
  bool take(std::size_t bytes, const char* what) {
    if (!align(bytes, what)) return false;
    if (bytes > n_ - at_) return fail(std::string(what) + ": the message ends at byte " + std::to_string(n_ + 4));
    return true;
  }
  bool fail(const std::string& e) {
    error = e;
    return false;
  }
  const std::uint8_t* p_;
  std::size_t n_, at_ = 0;  // offsets count from after the encapsulation header (CDR alignment origin)
  bool little_;
};

}  // namespace

bool decode_joint_state(const std::uint8_t* data, std::size_t size, JointStateMessage& out, std::string& error) {
  if (size < 4) {
    error = "shorter than the 4-byte CDR encapsulation header";
    return false;
  }
  // Encapsulation kinds CDR_BE (0x0000) and CDR_LE (0x0001); the options bytes are ignored.
  if (data[0] != 0 || data[1] > 1) {
    error =
        "encapsulation " + std::to_string(data[0]) + "," + std::to_string(data[1]) + " is not plain CDR (0,0 or 0,1)";
    return false;
  }
  CdrReader r(data + 4, size - 4, data[1] == 1);
  std::uint32_t sec = 0;
  std::string frame_id;
  const bool ok = r.u32(sec, "header.stamp.sec") && r.u32(out.stamp_nanosec, "header.stamp.nanosec") &&
                  r.string(frame_id, "header.frame_id") && r.strings(out.name, "name") &&
                  r.doubles(out.position, "position") && r.doubles(out.velocity, "velocity") &&
                  r.doubles(out.effort, "effort");
  if (!ok) {
    error = r.error;
    return false;
  }
  out.stamp_sec = static_cast<std::int32_t>(sec);
  if (out.stamp_nanosec >= 1000000000u) {
    error = "header.stamp.nanosec " + std::to_string(out.stamp_nanosec) + " is not below 1e9";
    return false;
  }
  return true;
}

}  // namespace dyncal::host
