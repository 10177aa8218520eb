#pragma once
// The MPS2 boards' serial line and clock as a drive port needs them (qemu mps2-an386 / mps2-an500):
// the CMSDK APB UART0 (0x40004000; receive IRQ 0, transmit IRQ 1), interrupt-driven both ways, and
// a microsecond clock from SysTick (1 ms interrupt on the 25 MHz system clock). A drive maker
// implements the same three calls on their MCU (docs/firmware.md "Building a drive"). The main
// loop sleeps (WFI) while it waits: a guest that spins on device registers starves qemu's I/O.
#include <cstddef>
#include <cstdint>

namespace dyncal::cortex_m {

/// Starts UART0 at `baud` (8N1) with its receive and transmit interrupts, and the SysTick clock.
void serial_start(std::uint32_t baud);
/// Moves up to `capacity` received bytes into `out`; their number. Bytes the receive buffer (1 KiB)
/// could not hold are counted in serial_overruns().
std::size_t serial_read(std::uint8_t* out, std::size_t capacity);
/// Sends bytes[0, n) and returns when the last byte has left (sleeping between interrupts).
void serial_write(const std::uint8_t* bytes, std::size_t n);
/// Bytes lost because the receive buffer was full.
std::uint32_t serial_overruns();
/// Microseconds since serial_start (monotonic).
std::uint64_t clock_us();
/// Sleeps until the next interrupt (a byte, the 1 ms tick).
void wait_for_interrupt();

}  // namespace dyncal::cortex_m
