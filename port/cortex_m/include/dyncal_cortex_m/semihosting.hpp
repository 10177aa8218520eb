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
/// The program's command line (SYS_GET_CMDLINE; qemu: -semihosting-config ...,arg=A,arg=B gives
/// "A B") into buf[0, size), NUL-terminated; false when the host gives none or it does not fit.
bool command_line(char* buf, int size);
/// Reads the file `path` into buf[0, size): the bytes read, -1 when it cannot be opened (SYS_OPEN
/// "rb", SYS_READ, SYS_CLOSE).
int read_file(const char* path, void* buf, int size);
/// Writes bytes[0, size) to `path` atomically: to `path`.tmp, closed, then renamed over `path`
/// (SYS_OPEN "wb", SYS_WRITE, SYS_CLOSE, SYS_RENAME). False on any failure; `path` then holds its
/// old content.
bool write_file_atomically(const char* path, const void* bytes, int size);
/// Ends the program with `status` (SYS_EXIT: 0 = success, anything else = failure). Never returns.
[[noreturn]] void exit(int status);

}  // namespace dyncal::cortex_m
