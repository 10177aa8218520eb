#include "dyncal_host/common/interrupt.hpp"

#include <csignal>

namespace dyncal::host {
namespace {

volatile std::sig_atomic_t caught = 0;
int depth = 0;
struct sigaction previous_int {
}, previous_term{};

extern "C" void on_interrupt(int signal) {
  caught = signal;
}

}  // namespace

InterruptScope::InterruptScope() {
  if (depth++ > 0) return;
  caught = 0;
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = SA_RESTART;
  sigaction(SIGINT, &sa, &previous_int);
  sigaction(SIGTERM, &sa, &previous_term);
}

InterruptScope::~InterruptScope() {
  if (--depth > 0) return;
  sigaction(SIGINT, &previous_int, nullptr);
  sigaction(SIGTERM, &previous_term, nullptr);
}

int interrupt_signal() {
  return static_cast<int>(caught);
}

std::string signal_name(int signal) {
  return signal == SIGINT ? "SIGINT" : signal == SIGTERM ? "SIGTERM" : "signal " + std::to_string(signal);
}

}  // namespace dyncal::host
