#pragma once
// Measured stack use: paint() fills the unused part of the stack with a pattern (call it first in
// main), peak_bytes() finds the deepest word that no longer holds it. This measures the run that
// happened, including library calls -fstack-usage cannot see through.
#include <cstdint>

extern "C" std::uint32_t __stack_bottom[];
extern "C" std::uint32_t __stack_top[];

namespace dyncal::cortex_m {

class StackUsage {
 public:
  static constexpr std::uint32_t kPattern = 0xA5C3A5C3u;

  /// Paints from the bottom of the stack up to 64 bytes below the current stack pointer.
  static void paint() noexcept {
    std::uint32_t marker = 0;
    volatile std::uint32_t* p = __stack_bottom;
    const std::uintptr_t limit = reinterpret_cast<std::uintptr_t>(&marker) - 64;
    while (reinterpret_cast<std::uintptr_t>(p) < limit) *p++ = kPattern;
  }
  /// Bytes between the top of the stack and the deepest overwritten word.
  static int peak_bytes() noexcept {
    const volatile std::uint32_t* p = __stack_bottom;
    while (p < __stack_top && *p == kPattern) ++p;
    return static_cast<int>(reinterpret_cast<std::uintptr_t>(__stack_top) - reinterpret_cast<std::uintptr_t>(p));
  }
  /// Size of the stack reservation of the linker script.
  static int reserved_bytes() noexcept {
    return static_cast<int>(reinterpret_cast<std::uintptr_t>(__stack_top) -
                            reinterpret_cast<std::uintptr_t>(__stack_bottom));
  }
};

}  // namespace dyncal::cortex_m
