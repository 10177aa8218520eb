// Reset handler and vector table for Cortex-M (qemu MPS2 boards): enable the FPU before any float
// instruction, copy .data, clear .bss, run static constructors, call main, exit via semihosting.
#include <cstdint>

#include "dyncal_cortex_m/semihosting.hpp"

extern "C" {
extern std::uint32_t __data_load, __data_start, __data_end, __bss_start, __bss_end, __stack_top;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
void reset_handler();
void fault_handler();
}

namespace {
using Handler = void (*)();
}

// Interrupt handlers an image may define (weak: a fault until then). MPS2 AN386/AN500 (qemu):
// SysTick, and the CMSDK UART0's receive (IRQ 0) and transmit (IRQ 1) interrupts.
extern "C" {
void unhandled_interrupt();
void systick_handler() __attribute__((weak, alias("unhandled_interrupt")));
void uart0_rx_handler() __attribute__((weak, alias("unhandled_interrupt")));
void uart0_tx_handler() __attribute__((weak, alias("unhandled_interrupt")));
}

// Initial stack pointer, reset, NMI, HardFault, MemManage, BusFault, UsageFault, 4 reserved,
// SVCall, DebugMonitor, reserved, PendSV, SysTick, then the board's 32 external interrupts (IRQ 0
// first).
__attribute__((section(".vectors"), used)) const Handler g_vectors[16 + 32] = {
    reinterpret_cast<Handler>(&__stack_top),
    reset_handler,
    fault_handler,
    fault_handler,
    fault_handler,
    fault_handler,
    fault_handler,
    nullptr,
    nullptr,
    nullptr,
    nullptr,
    fault_handler,
    fault_handler,
    nullptr,
    fault_handler,
    systick_handler,
    uart0_rx_handler,
    uart0_tx_handler,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
    unhandled_interrupt,
};

extern "C" __attribute__((naked, noreturn)) void reset_handler() {
  // CPACR: full access to CP10 and CP11 (the FPU), then barriers, all before any C++ code.
  __asm volatile(
      "ldr r0, =0xE000ED88\n"
      "ldr r1, [r0]\n"
      "orr r1, r1, #(0xF << 20)\n"
      "str r1, [r0]\n"
      "dsb\n"
      "isb\n"
      "b reset_continue\n");
}

extern "C" __attribute__((noreturn, used)) void reset_continue() {
  for (std::uint32_t *src = &__data_load, *dst = &__data_start; dst < &__data_end;) *dst++ = *src++;
  for (std::uint32_t* p = &__bss_start; p < &__bss_end;) *p++ = 0;
  for (void (**f)() = __init_array_start; f < __init_array_end; ++f) (*f)();
  dyncal::cortex_m::exit(main());
}

extern "C" void unhandled_interrupt() {
  fault_handler();
}

extern "C" __attribute__((noreturn)) void fault_handler() {
  dyncal::cortex_m::write("dyncal firmware: fault\n");
  dyncal::cortex_m::exit(3);
}
