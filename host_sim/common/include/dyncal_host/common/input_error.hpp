#pragma once

#include <stdexcept>
#include <string>

namespace dyncal::host {

/// Bad user input (file, column, value, option): the CLI prints the message on one line and
/// exits with code 2.
class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& what) : std::runtime_error(what) {}
};

/// The drive stopped a trajectory on a fault (DriveFault). The message says which joint, which
/// limit and where the samples recorded before it were saved.
class DriveFaultError : public InputError {
 public:
  explicit DriveFaultError(const std::string& what) : InputError(what) {}
};

}  // namespace dyncal::host
