#pragma once
// A parameter table's encoded bytes (dyncal/parameter_table.hpp), as the store writes them.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "dyncal/parameter_table.hpp"

namespace dyncal::test {

/// The bytes encode_table writes for `t` (a test failure if it refuses).
inline std::vector<std::uint8_t> encoded_table(const ParameterTable& t) {
  std::vector<std::uint8_t> b(kTableMaxBytes);
  int size = 0;
  EXPECT_EQ(encode_table(t, b.data(), static_cast<int>(b.size()), &size), TableStatus::ok);
  b.resize(static_cast<size_t>(size));
  return b;
}

}  // namespace dyncal::test
