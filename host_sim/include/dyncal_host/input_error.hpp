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

}  // namespace dyncal::host
