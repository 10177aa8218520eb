// CMSDK APB UART0 and SysTick on qemu's MPS2 boards (serial_mps2.hpp). Registers: ARM CMSDK
// Technical Reference Manual (DDI 0479), APB UART: DATA 0x00, STATE 0x04 (bit 0 TX full, bit 1
// RX full), CTRL 0x08 (TX/RX enable, TX/RX interrupt enable), INTSTATUS/INTCLEAR 0x0C (bit 0 TX,
// bit 1 RX), BAUDDIV 0x10; ARMv7-M Architecture Reference Manual for SysTick and the NVIC.
#include "dyncal_cortex_m/serial_mps2.hpp"

namespace dyncal::cortex_m {
namespace {

constexpr std::uintptr_t kUart = 0x40004000u;
constexpr std::uint32_t kSystemClockHz = 25000000u;
constexpr std::uint32_t kTicksPerMs = kSystemClockHz / 1000u;

volatile std::uint32_t& reg(std::uintptr_t a) {
  return *reinterpret_cast<volatile std::uint32_t*>(a);
}

constexpr std::size_t kRxCapacity = 1024;
std::uint8_t g_rx[kRxCapacity];
volatile std::size_t g_rx_head = 0, g_rx_tail = 0;  ///< written by the interrupt, read by the loop
volatile std::uint32_t g_rx_overruns = 0;
const std::uint8_t* volatile g_tx = nullptr;
volatile std::size_t g_tx_left = 0;
volatile std::uint64_t g_ms = 0;

}  // namespace

void serial_start(std::uint32_t baud) {
  reg(kUart + 0x10) = kSystemClockHz / baud;      // BAUDDIV (>= 16)
  reg(kUart + 0x08) = 0x1u | 0x2u | 0x4u | 0x8u;  // TX, RX, TX interrupt, RX interrupt
  reg(0xE000E100u) = 0x3u;                        // NVIC ISER0: IRQ 0 (RX) and 1 (TX)
  reg(0xE000E014u) = kTicksPerMs - 1;             // SysTick LOAD: 1 ms
  reg(0xE000E018u) = 0;
  reg(0xE000E010u) = 0x7u;  // enable, interrupt, processor clock
}

std::size_t serial_read(std::uint8_t* out, std::size_t capacity) {
  std::size_t n = 0;
  while (n < capacity && g_rx_tail != g_rx_head) {
    out[n++] = g_rx[g_rx_tail];
    g_rx_tail = (g_rx_tail + 1) % kRxCapacity;
  }
  return n;
}

void serial_write(const std::uint8_t* bytes, std::size_t n) {
  if (n == 0) return;
  __asm volatile("cpsid i" ::: "memory");
  g_tx = bytes + 1;
  g_tx_left = n - 1;
  reg(kUart + 0x00) = bytes[0];  // the rest from the transmit interrupt
  __asm volatile("cpsie i" ::: "memory");
  while (g_tx_left != 0 || (reg(kUart + 0x04) & 0x1u) != 0) wait_for_interrupt();
}

std::uint32_t serial_overruns() {
  return g_rx_overruns;
}

std::uint64_t clock_us() {
  // The counter may have wrapped with its interrupt not yet taken (qemu takes interrupts between
  // translated blocks): then the millisecond count is one behind the counter. SysTick's COUNTFLAG
  // (CSR bit 16, cleared by reading CSR) cannot tell it (the handler's entry does not clear it),
  // the pending bit can: ICSR.PENDSTSET (bit 26). And the clock never runs backwards.
  static std::uint64_t last = 0;
  for (;;) {
    const std::uint64_t ms = g_ms;
    const std::uint32_t val = reg(0xE000E018u);
    const bool wrapped = (reg(0xE000ED04u) & (1u << 26)) != 0;
    if (ms != g_ms) continue;
    std::uint64_t t = (ms + (wrapped ? 1u : 0u)) * 1000u + (kTicksPerMs - 1 - val) / (kTicksPerMs / 1000u);
    if (t < last) t = last;
    last = t;
    return t;
  }
}

void wait_for_interrupt() {
  __asm volatile("wfi" ::: "memory");
}

}  // namespace dyncal::cortex_m

extern "C" void systick_handler() {
  dyncal::cortex_m::g_ms = dyncal::cortex_m::g_ms + 1;
}

extern "C" void uart0_rx_handler() {
  using namespace dyncal::cortex_m;
  reg(kUart + 0x0C) = 0x2u;  // clear RX
  while ((reg(kUart + 0x04) & 0x2u) != 0) {
    const std::uint8_t byte = static_cast<std::uint8_t>(reg(kUart + 0x00));
    const std::size_t next = (g_rx_head + 1) % kRxCapacity;
    if (next == g_rx_tail) {
      g_rx_overruns = g_rx_overruns + 1;
      continue;
    }
    g_rx[g_rx_head] = byte;
    g_rx_head = next;
  }
}

extern "C" void uart0_tx_handler() {
  using namespace dyncal::cortex_m;
  reg(kUart + 0x0C) = 0x1u;  // clear TX
  if (g_tx_left == 0) return;
  reg(kUart + 0x00) = *g_tx;
  g_tx = g_tx + 1;
  g_tx_left = g_tx_left - 1;
}
