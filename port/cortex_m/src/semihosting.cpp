#include "dyncal_cortex_m/semihosting.hpp"

#include <cmath>

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
