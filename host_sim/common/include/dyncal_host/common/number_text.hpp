#pragma once
// Numbers in user messages: short, exact enough to find the value in the input.

#include <cstdio>
#include <string>

namespace dyncal::host {

/// `v` with `digits` significant digits (%g): "0.05", "1e+300", "2.5".
inline std::string number_text(double v, int digits = 4) {
  char text[40];
  std::snprintf(text, sizeof text, "%.*g", digits, v);
  return text;
}

}  // namespace dyncal::host
