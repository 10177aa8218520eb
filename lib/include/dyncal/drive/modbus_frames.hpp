#pragma once
// Modbus request framing as pure functions on bytes, for a drive's server on any transport: Modbus
// TCP's MBAP header (Modbus Messaging on TCP/IP Implementation Guide v1.0b, sec. 3.1.3) and RTU's
// address + PDU + CRC-16 (MODBUS over Serial Line v1.02, sec. 2.5.1, 6.2.2), with the request PDU
// lengths of the functions a drive serves (Modbus Application Protocol v1.1b3, sec. 6). Heap-free,
// exception-free, no I/O: the same code frames the Linux simulated drive's requests and a
// firmware drive's UART bytes, and is fuzzed alone.
//
// RTU frames by length, not by the t3.5 silence alone: a request's function code and, for the
// multiple writes, its byte count say where it ends, and its CRC says whether it arrived intact.
// A line whose bytes arrive with gaps (an emulated UART, a USB adapter) splits no frame, and a
// receiver resynchronises only after a silence of rtu_silence_us (a parameter of the transport).

#include <array>
#include <cstddef>
#include <cstdint>

namespace dyncal::drive {

/// A big-endian 16-bit field (Modbus sends every field high byte first; RTU's CRC is the exception).
inline std::uint16_t be16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

// ---------------------------------------------------------------------------------------------
// Modbus TCP

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

/// The first frame in `buf[0, n)`.
inline MbapFrame next_mbap_frame(const std::uint8_t* buf, std::size_t n) noexcept {
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

// ---------------------------------------------------------------------------------------------
// Request PDUs

/// The length a request PDU of function `pdu[0]` has, from its first `n` bytes: > 0 the length in
/// bytes (function code included); 0: not known yet (a multiple write before its byte count);
/// -1: a function whose request length the code alone does not give (not one of 0x01-0x06, 0x0F,
/// 0x10, 0x11, 0x17: an RTU receiver then ends the frame at the line's silence). Lengths: 5 for the
/// reads 0x01-0x04 and single writes 0x05, 0x06 (sec. 6.1-6.6); 6 + byte count for 0x0F, 0x10
/// (sec. 6.11, 6.12); 1 for 0x11 (sec. 6.13); 10 + byte count for 0x17 (sec. 6.17).
inline int request_pdu_length(const std::uint8_t* pdu, std::size_t n) noexcept {
  if (n < 1) return 0;
  switch (pdu[0]) {
    case 0x01:
    case 0x02:
    case 0x03:
    case 0x04:
    case 0x05:
    case 0x06:
      return 5;
    case 0x0F:
    case 0x10:
      return n < 6 ? 0 : 6 + pdu[5];
    case 0x11:
      return 1;
    case 0x17:
      return n < 10 ? 0 : 10 + pdu[9];
    default:
      return -1;
  }
}

/// Whether a request PDU (function code first) is exactly as long as its function implies
/// (request_pdu_length) and its byte count matches its quantity: ceil(quantity / 8) for 0x0F,
/// 2 quantity for 0x10 and for 0x17's write part. Other function codes: true when at least the
/// code is there (the server answers illegal function).
inline bool request_pdu_consistent(const std::uint8_t* pdu, std::size_t n) noexcept {
  const int length = request_pdu_length(pdu, n);
  if (length == -1) return n >= 1;
  if (length <= 0 || n != static_cast<std::size_t>(length)) return false;
  switch (pdu[0]) {
    case 0x0F:
      return pdu[5] == (be16(pdu + 3) + 7u) / 8u;
    case 0x10:
      return pdu[5] == 2u * be16(pdu + 3);
    case 0x17:
      return pdu[9] == 2u * be16(pdu + 7);
    default:
      return true;
  }
}

// ---------------------------------------------------------------------------------------------
// Modbus RTU

namespace detail {

/// CRC-16/MODBUS of every byte value, one byte at a time (the bitwise shift of sec. 6.2.2 done once).
constexpr std::array<std::uint16_t, 256> crc16_table() noexcept {
  std::array<std::uint16_t, 256> t{};
  for (unsigned v = 0; v < 256; ++v) {
    std::uint16_t crc = static_cast<std::uint16_t>(v);
    for (int bit = 0; bit < 8; ++bit) crc = static_cast<std::uint16_t>((crc & 1u) ? (crc >> 1) ^ 0xA001u : crc >> 1);
    t[v] = crc;
  }
  return t;
}
inline constexpr std::array<std::uint16_t, 256> kCrc16Table = crc16_table();

}  // namespace detail

/// CRC-16/MODBUS of bytes[0, n): polynomial 0xA001 (0x8005 reflected), initial value 0xFFFF (MODBUS
/// over Serial Line v1.02, sec. 6.2.2), a byte at a time from a 256-entry table (the same CRC as the
/// section's bit-by-bit procedure, 8 shifts a byte). An RTU frame carries it low byte first.
constexpr std::uint16_t crc16(const std::uint8_t* bytes, std::size_t n) noexcept {
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < n; ++i)
    crc = static_cast<std::uint16_t>((crc >> 8) ^ detail::kCrc16Table[(crc ^ bytes[i]) & 0xFFu]);
  return crc;
}

/// Writes the CRC of adu[0, n) at adu[n], adu[n + 1], low byte first (MODBUS over Serial Line
/// v1.02, sec. 2.5.1); the ADU's length with it, n + 2. adu must hold n + 2 bytes.
inline std::size_t append_crc16(std::uint8_t* adu, std::size_t n) noexcept {
  const std::uint16_t crc = crc16(adu, n);
  adu[n] = static_cast<std::uint8_t>(crc & 0xFFu);
  adu[n + 1] = static_cast<std::uint8_t>(crc >> 8);
  return n + 2;
}

/// Whether the last two bytes of adu[0, n) (n >= 2) are the CRC of the others, low byte first.
inline bool crc16_holds(const std::uint8_t* adu, std::size_t n) noexcept {
  const std::uint16_t crc = crc16(adu, n - 2);
  return adu[n - 2] == (crc & 0xFFu) && adu[n - 1] == (crc >> 8);
}

/// Largest RTU ADU: address (1) + PDU (253) + CRC (2) (sec. 2.5.1).
inline constexpr std::size_t kMaxRtuAduBytes = 256;

/// The silence that ends an RTU frame at `baud` [bit/s], in microseconds: 3.5 character times of
/// 11 bits (start, 8 data, parity or a second stop, stop), and a fixed 1750 us above 19 200 baud
/// (sec. 2.5.1.1). A transport whose bytes arrive with longer gaps inside a frame (an emulated UART)
/// sets its own larger value; framing by length (next_rtu_request) does not depend on it.
constexpr std::uint32_t rtu_silence_us(std::uint32_t baud) noexcept {
  return baud == 0 || baud > 19200 ? 1750u : static_cast<std::uint32_t>((3.5 * 11.0 * 1e6) / baud + 0.999);
}

struct RtuFrame {
  enum class Status {
    incomplete,     ///< the frame's length is not reached yet: wait for more bytes
    complete,       ///< one frame of `bytes` bytes (address, PDU, CRC) starts the buffer
    needs_silence,  ///< a function whose length is unknown: the frame ends at the line's silence
    invalid,        ///< a length beyond kMaxRtuAduBytes: not a frame, resynchronise after a silence
  };
  Status status = Status::incomplete;
  std::size_t bytes = 0;  ///< ADU length when complete
  bool crc_ok = false;    ///< complete: the last two bytes are crc16 of the others, low byte first
  std::uint8_t address = 0;
};

/// The request that starts `buf[0, n)` on an RTU line: its length from its function code (and byte
/// count), and whether its CRC is right. A frame whose CRC is wrong is complete with crc_ok false:
/// the server discards it without a reply (sec. 2.4.1) and the next byte starts the next frame.
inline RtuFrame next_rtu_request(const std::uint8_t* buf, std::size_t n) noexcept {
  RtuFrame f;
  if (n < 2) return f;
  f.address = buf[0];
  const int pdu = request_pdu_length(buf + 1, n - 1);
  if (pdu == -1) {
    f.status = RtuFrame::Status::needs_silence;
    return f;
  }
  if (pdu == 0) return f;
  const std::size_t length = 1 + static_cast<std::size_t>(pdu) + 2;
  if (length > kMaxRtuAduBytes) {
    f.status = RtuFrame::Status::invalid;
    return f;
  }
  if (n < length) return f;
  f.status = RtuFrame::Status::complete;
  f.bytes = length;
  f.crc_ok = crc16_holds(buf, length);
  return f;
}

}  // namespace dyncal::drive
