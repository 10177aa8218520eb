#pragma once
// SIGINT and SIGTERM while a host drives an arm: caught, so that the host stops the motion it
// started before it exits (docs/modbus.md "A host that stops stops the motion").

#include <string>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

/// While an InterruptScope lives, SIGINT and SIGTERM set a flag (interrupt_signal()) instead of
/// ending the process; system calls restart (SA_RESTART), so a Modbus transaction in flight
/// completes. Scopes nest; the outermost restores the handlers it found (Python's among them).
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
};

/// The signal caught inside the current InterruptScope (SIGINT, SIGTERM), 0 if none.
int interrupt_signal();

/// The run was ended by SIGINT or SIGTERM; the message says what was stopped. The CLI prints it
/// on one line and exits with 128 + signal() (130 for SIGINT, 143 for SIGTERM); Python raises
/// KeyboardInterrupt.
class Interrupted : public InputError {
 public:
  Interrupted(int signal, const std::string& what) : InputError(what), signal_(signal) {}
  int signal() const { return signal_; }

 private:
  int signal_;
};

/// The signal's name: "SIGINT", "SIGTERM".
std::string signal_name(int signal);

}  // namespace dyncal::host
