// CRC-32 (IEEE 802.3 / zlib: reflected polynomial 0xEDB88320, init and final xor 0xFFFFFFFF).
#pragma once

#include <cstddef>
#include <cstdint>

namespace dyncal {

namespace detail {

struct Crc32Table {
  std::uint32_t entry[256];
  constexpr Crc32Table() : entry() {
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      entry[i] = c;
    }
  }
};

inline constexpr Crc32Table kCrc32Table{};

}  // namespace detail

/// CRC-32 of `size` bytes, continuing from `crc` (pass the previous result to chain blocks; 0 to
/// start). crc32("123456789") == 0xCBF43926. Table in flash (1 KiB), no heap.
inline std::uint32_t crc32(const std::uint8_t* data, std::size_t size, std::uint32_t crc = 0) noexcept {
  crc = ~crc;
  for (std::size_t i = 0; i < size; ++i) crc = detail::kCrc32Table.entry[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

}  // namespace dyncal
