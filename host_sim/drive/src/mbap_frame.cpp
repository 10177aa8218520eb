#include "mbap_frame.hpp"

namespace dyncal::host {

MbapFrame next_mbap_frame(const std::uint8_t* buf, std::size_t n) noexcept {
  MbapFrame f;
  if (n < 6) return f;
  const std::size_t length = be16(buf + 4);
  if (length < 2 || length > kMaxTcpAduBytes - 6) {
    f.status = MbapFrame::Status::invalid;
    return f;
  }
  if (n < 6 + length) return f;
  f.status = MbapFrame::Status::complete;
  f.bytes = 6 + length;
  f.protocol = be16(buf + 2);
  f.unit = buf[6];
  return f;
}

bool request_pdu_consistent(const std::uint8_t* pdu, std::size_t n) noexcept {
  if (n < 1) return false;
  switch (pdu[0]) {
    case 0x01:
    case 0x02:
    case 0x03:
    case 0x04:
    case 0x05:
    case 0x06:
      return n == 5;
    case 0x0F: {  // write multiple coils: quantity bits in byte_count = ceil(quantity / 8) bytes
      if (n < 6) return false;
      const std::size_t quantity = be16(pdu + 3);
      return pdu[5] == (quantity + 7) / 8 && n == 6 + static_cast<std::size_t>(pdu[5]);
    }
    case 0x10: {  // write multiple registers: byte_count = 2 quantity
      if (n < 6) return false;
      const std::size_t quantity = be16(pdu + 3);
      return pdu[5] == 2 * quantity && n == 6 + static_cast<std::size_t>(pdu[5]);
    }
    case 0x11:
      return n == 1;
    case 0x17: {  // read/write multiple registers: byte_count = 2 write quantity
      if (n < 10) return false;
      const std::size_t quantity = be16(pdu + 7);
      return pdu[9] == 2 * quantity && n == 10 + static_cast<std::size_t>(pdu[9]);
    }
    default:
      return true;
  }
}

}  // namespace dyncal::host
