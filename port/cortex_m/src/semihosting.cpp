#include "dyncal_cortex_m/semihosting.hpp"

#include <cmath>
#include <cstring>

#include "dyncal/assert.hpp"

namespace dyncal::cortex_m {
namespace {

int call(int op, const void* arg) {
  int result;
  __asm volatile(
      "mov r0, %1\n"
      "mov r1, %2\n"
      "bkpt 0xAB\n"
      "mov %0, r0\n"
      : "=r"(result)
      : "r"(op), "r"(arg)
      : "r0", "r1", "memory");
  return result;
}

}  // namespace

void write(const char* text) {
  call(0x04, text);
}

void write_int(long long value) {
  char buf[24];
  int i = 23;
  buf[i] = 0;
  const bool negative = value < 0;
  unsigned long long v = negative ? static_cast<unsigned long long>(-value) : static_cast<unsigned long long>(value);
  do {
    buf[--i] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v != 0 && i > 1);
  if (negative) buf[--i] = '-';
  write(buf + i);
}

void write_float(double value, int digits) {
  if (std::isnan(value)) return write("nan");
  if (std::isinf(value)) return write(value < 0 ? "-inf" : "inf");
  if (value < 0) {
    write("-");
    value = -value;
  }
  int exponent = 0;
  if (value != 0) {
    exponent = static_cast<int>(std::floor(std::log10(value)));
    value /= std::pow(10.0, exponent);
    if (value >= 10.0) {
      value /= 10.0;
      ++exponent;
    }
  }
  const long long scaled = static_cast<long long>(std::llround(value * std::pow(10.0, digits - 1)));
  char buf[32];
  int n = 0;
  long long div = 1;
  for (int k = 1; k < digits; ++k) div *= 10;
  buf[n++] = static_cast<char>('0' + (scaled / div) % 10);
  buf[n++] = '.';
  for (long long d = div / 10; d >= 1; d /= 10) buf[n++] = static_cast<char>('0' + (scaled / d) % 10);
  buf[n++] = 'e';
  buf[n] = 0;
  write(buf);
  write_int(exponent);
}

namespace {

/// SYS_OPEN in `mode` (1 "rb", 5 "wb"): the handle, or -1.
int sys_open(const char* path, int mode) {
  const std::uintptr_t args[3] = {reinterpret_cast<std::uintptr_t>(path), static_cast<std::uintptr_t>(mode),
                                  static_cast<std::uintptr_t>(std::strlen(path))};
  return call(0x01, args);
}

int sys_close(int handle) {
  const std::uintptr_t args[1] = {static_cast<std::uintptr_t>(handle)};
  return call(0x02, args);
}

}  // namespace

bool command_line(char* buf, int size) {
  std::uintptr_t args[2] = {reinterpret_cast<std::uintptr_t>(buf), static_cast<std::uintptr_t>(size)};
  return call(0x15, args) == 0;
}

int read_file(const char* path, void* buf, int size) {
  const int h = sys_open(path, 1);
  if (h < 0) return -1;
  const std::uintptr_t args[3] = {static_cast<std::uintptr_t>(h), reinterpret_cast<std::uintptr_t>(buf),
                                  static_cast<std::uintptr_t>(size)};
  const int not_read = call(0x06, args);  // SYS_READ returns the bytes not read
  sys_close(h);
  return not_read < 0 || not_read > size ? -1 : size - not_read;
}

bool write_file_atomically(const char* path, const void* bytes, int size) {
  char tmp[256];
  const int n = static_cast<int>(std::strlen(path));
  if (n + 5 > static_cast<int>(sizeof tmp)) return false;
  for (int i = 0; i < n; ++i) tmp[i] = path[i];
  const char suffix[] = ".tmp";
  for (int i = 0; i < 5; ++i) tmp[n + i] = suffix[i];
  const int h = sys_open(tmp, 5);
  if (h < 0) return false;
  const std::uintptr_t args[3] = {static_cast<std::uintptr_t>(h), reinterpret_cast<std::uintptr_t>(bytes),
                                  static_cast<std::uintptr_t>(size)};
  const bool written = call(0x05, args) == 0;  // SYS_WRITE returns the bytes not written
  if (sys_close(h) != 0 || !written) return false;
  const std::uintptr_t rename[4] = {reinterpret_cast<std::uintptr_t>(tmp), static_cast<std::uintptr_t>(n + 4),
                                    reinterpret_cast<std::uintptr_t>(path), static_cast<std::uintptr_t>(n)};
  return call(0x0F, rename) == 0;
}

void exit(int status) {
  // SYS_EXIT with ADP_Stopped_ApplicationExit (0x20026) for success, RunTimeErrorUnknown otherwise.
  call(0x18, reinterpret_cast<const void*>(status == 0 ? 0x20026 : 0x20023));
  for (;;) {
  }
}

}  // namespace dyncal::cortex_m

// lib/'s assert hook (dyncal/assert.hpp, DYNCAL_ASSERT_MODE 2): the broken precondition on the console,
// then exit status 3.
extern "C" void dyncal_assert_failed(const char* file, int line, const char* expression) noexcept {
  dyncal::cortex_m::write("dyncal assert failed: ");
  dyncal::cortex_m::write(file);
  dyncal::cortex_m::write(":");
  dyncal::cortex_m::write_int(line);
  dyncal::cortex_m::write(": ");
  dyncal::cortex_m::write(expression);
  dyncal::cortex_m::write("\n");
  dyncal::cortex_m::exit(3);
}
