#pragma once
// Instruction counter for qemu: with `-icount shift=0` every guest instruction advances the virtual
// clock by 1 ns, and SysTick on the processor clock (25 MHz on the MPS2 boards) then ticks once per
// 40 instructions. qemu models no cycles, so this counts instructions, not cycles.
#include <cstdint>

namespace dyncal::cortex_m {

class InstructionCounter {
 public:
  static constexpr std::uint32_t kInstructionsPerTick = 40;  // 1 GHz virtual / 25 MHz SysTick

  /// Starts SysTick free-running from its 24-bit maximum (no interrupt).
  static void start() {
    reg(kLoad) = 0x00FFFFFFu;
    reg(kVal) = 0;
    reg(kCtrl) = 0x5u;  // enable, processor clock
  }
  /// Current tick count (grows; wraps after 2^24 ticks = 671 M instructions).
  static std::uint32_t ticks() { return 0x00FFFFFFu - reg(kVal); }
  /// Ticks from `from` to `to`, modulo the 24-bit counter (correct across one wrap).
  static std::uint32_t elapsed(std::uint32_t from, std::uint32_t to) { return (to - from) & 0x00FFFFFFu; }

 private:
  static constexpr std::uintptr_t kCtrl = 0xE000E010u, kLoad = 0xE000E014u, kVal = 0xE000E018u;
  static volatile std::uint32_t& reg(std::uintptr_t a) { return *reinterpret_cast<volatile std::uint32_t*>(a); }
};

}  // namespace dyncal::cortex_m
