#pragma once
// Modbus TCP framing: the MBAP header and the request PDU lengths the drive serves (Modbus
// Application Protocol v1.1b3, Modbus Messaging on TCP/IP Implementation Guide v1.0b, sec. 3.1.3).
// Pure functions on bytes, so the framing is tested and fuzzed without a socket.

#include <cstddef>
#include <cstdint>

namespace dyncal::host {

/// MBAP header: transaction id (2), protocol id (2, 0 = Modbus), length (2: bytes that follow,
/// unit id + PDU), unit id (1). Big-endian.
inline constexpr std::size_t kMbapHeaderBytes = 7;
/// Largest ADU on TCP (7-byte header + 253-byte PDU).
inline constexpr std::size_t kMaxTcpAduBytes = 260;

struct MbapFrame {
  enum class Status {
    incomplete,  ///< fewer bytes than the header or than its length field says: wait for more
    complete,    ///< one frame of `bytes` bytes starts the buffer
    invalid,     ///< the length field is outside 2..254: framing is lost, close the connection
  };
  Status status = Status::incomplete;
  std::size_t bytes = 0;  ///< ADU length (header + PDU) when complete
  std::uint16_t protocol = 0;
  std::uint8_t unit = 0;
};

/// A big-endian 16-bit field (Modbus sends every field high byte first).
inline std::uint16_t be16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

/// The first frame in `buf[0, n)`.
MbapFrame next_mbap_frame(const std::uint8_t* buf, std::size_t n) noexcept;

/// Whether a request PDU (function code first) has exactly the length its function implies:
/// 5 bytes for reads (0x01-0x04) and single writes (0x05, 0x06); 6 + byte count for multiple writes
/// (0x0F, 0x10), with the byte count matching the quantity; 1 for report server id (0x11). Other
/// function codes: true when at least the code is there (the drive answers illegal function).
bool request_pdu_consistent(const std::uint8_t* pdu, std::size_t n) noexcept;

}  // namespace dyncal::host
