#pragma once

#include <cstddef>
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

/// A piece of the user's input as a message quotes it: at most `max_chars` characters of it, then
/// "... (N bytes)", so that one line stays one readable line whatever the input holds (a 50 MB CSV
/// cell is not echoed whole).
inline std::string excerpt(const std::string& text, std::size_t max_chars = 64) {
  if (text.size() <= max_chars) return text;
  return text.substr(0, max_chars) + "... (" + std::to_string(text.size()) + " bytes)";
}

}  // namespace dyncal::host
