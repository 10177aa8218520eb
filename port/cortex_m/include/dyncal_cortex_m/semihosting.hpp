#pragma once
// Semihosting console and exit status (qemu: -semihosting-config enable=on,target=native).
#include <cstdint>

namespace dyncal::cortex_m {

/// Writes a NUL-terminated string to the host console (SYS_WRITE0).
void write(const char* text);
/// Writes a signed integer in decimal.
void write_int(long long value);
/// Writes a number with `digits` significant decimals in scientific notation, no printf (newlib's
/// floating-point printf may allocate).
void write_float(double value, int digits = 6);
/// Ends the program with `status` (SYS_EXIT: 0 = success, anything else = failure). Never returns.
[[noreturn]] void exit(int status);

}  // namespace dyncal::cortex_m
