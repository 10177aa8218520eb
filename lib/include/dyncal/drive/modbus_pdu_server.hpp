#pragma once
// The Modbus PDU server of a drive: one request PDU in, its reply PDU out, for the functions a drive
// serves (Modbus Application Protocol v1.1b3: 03 read holding registers sec. 6.3, 04 read input
// registers 6.4, 06 write single register 6.6, 16 write multiple registers 6.12, 23 read/write
// multiple registers 6.17) and the exceptions of sec. 7. Transport-free (MBAP or RTU framing:
// modbus_frames.hpp), heap-free, exception-free. What the registers hold and which writes the
// drive accepts is the register bank's, a type the drive application supplies:
//
//   struct Bank {
//     // Registers [address, address + count) of the input (true) or holding bank into out[0, count),
//     // or the exception that refuses the read (02 for an address outside the map).
//     ModbusException read(bool input, std::uint16_t address, std::uint16_t count, std::uint16_t* out);
//     // Whether the holding registers [address, address + count) may take `values` (big-endian, two
//     // bytes each): none, or the exception the access and state rules give. No effect.
//     ModbusException check_write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values);
//     // Applies a write check_write accepted.
//     void write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values);
//   };

#include <cstddef>
#include <cstdint>

#include "dyncal/drive/modbus_frames.hpp"

namespace dyncal::drive {

/// Modbus exception codes (Modbus Application Protocol v1.1b3, sec. 7); none: the request succeeds.
enum class ModbusException : std::uint8_t {
  none = 0,
  illegal_function = 1,
  illegal_data_address = 2,
  illegal_data_value = 3,
  server_device_failure = 4,
  server_device_busy = 6,
};

/// Quantities per request (sec. 6.3, 6.4, 6.12, 6.17; coils 6.1, 6.2, 6.11).
inline constexpr int kMaxReadRegisters = 125;
inline constexpr int kMaxWriteRegisters = 123;
inline constexpr int kMaxReadWriteRead = 125;
inline constexpr int kMaxReadWriteWrite = 121;
inline constexpr int kMaxReadBits = 2000;
inline constexpr int kMaxWriteBits = 1968;
/// Largest PDU (sec. 4.1): the reply buffer serve_pdu needs.
inline constexpr std::size_t kMaxPduBytes = 253;

namespace detail {

inline std::size_t exception_reply(std::uint8_t function, ModbusException e, std::uint8_t* reply) noexcept {
  // A reserved code 0x80-0xFF stays as it is: function | 0x80 would be another request's exception.
  reply[0] = function >= 0x80 ? function : static_cast<std::uint8_t>(function | 0x80);
  reply[1] = static_cast<std::uint8_t>(e);
  return 2;
}

inline void put_be16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v >> 8);
  p[1] = static_cast<std::uint8_t>(v & 0xFF);
}

/// Registers of a read into reply (function, byte count, values), or the bank's exception.
template <typename Bank>
std::size_t read_reply(Bank& bank, bool input, std::uint8_t function, std::uint16_t address, std::uint16_t count,
                       std::uint8_t* reply) noexcept {
  std::uint16_t values[kMaxReadRegisters];
  const ModbusException e = bank.read(input, address, count, values);
  if (e != ModbusException::none) return exception_reply(function, e, reply);
  reply[0] = function;
  reply[1] = static_cast<std::uint8_t>(2 * count);
  for (std::uint16_t k = 0; k < count; ++k) put_be16(reply + 2 + 2 * k, values[k]);
  return 2 + 2 * static_cast<std::size_t>(count);
}

}  // namespace detail

/// Answers the request PDU req[0, n) (function code first) on `bank` into reply[0, kMaxPduBytes):
/// returns the reply PDU's length (>= 2). Exceptions (sec. 7): a PDU whose length contradicts its
/// function (request_pdu_consistent) or a quantity outside its function's range 03 ILLEGAL DATA
/// VALUE; the coil functions (the drive has no coils) 02 ILLEGAL DATA ADDRESS for a read of a valid
/// quantity, 01 ILLEGAL FUNCTION for a write; any other function 01, a reserved code 0x80-0xFF
/// under its own code; the bank's own for an address or a write it refuses. Function 23 writes
/// first and then reads (sec. 6.17), so the read shows the write's effect; a refused write reads
/// nothing. n = 0: no reply (0).
template <typename Bank>
std::size_t serve_pdu(Bank& bank, const std::uint8_t* req, std::size_t n, std::uint8_t* reply) noexcept {
  if (n == 0) return 0;
  const std::uint8_t function = req[0];
  using E = ModbusException;
  if (function >= 0x80) return detail::exception_reply(function, E::illegal_function, reply);
  if (!request_pdu_consistent(req, n)) return detail::exception_reply(function, E::illegal_data_value, reply);
  const std::uint16_t address = n >= 3 ? be16(req + 1) : 0;
  const std::uint16_t count = n >= 5 ? be16(req + 3) : 0;
  auto outside = [&](int max) { return count < 1 || count > max; };
  switch (function) {
    case 0x03:
    case 0x04:
      if (outside(kMaxReadRegisters)) return detail::exception_reply(function, E::illegal_data_value, reply);
      return detail::read_reply(bank, function == 0x04, function, address, count, reply);
    case 0x06: {
      const E e = bank.check_write(address, 1, req + 3);
      if (e != E::none) return detail::exception_reply(function, e, reply);
      bank.write(address, 1, req + 3);
      for (int k = 0; k < 5; ++k) reply[k] = req[k];  // the echo of the request (sec. 6.6)
      return 5;
    }
    case 0x10: {
      if (outside(kMaxWriteRegisters)) return detail::exception_reply(function, E::illegal_data_value, reply);
      const E e = bank.check_write(address, count, req + 6);
      if (e != E::none) return detail::exception_reply(function, e, reply);
      bank.write(address, count, req + 6);
      for (int k = 0; k < 5; ++k) reply[k] = req[k];  // function, address, quantity (sec. 6.12)
      return 5;
    }
    case 0x17: {
      const std::uint16_t write_address = be16(req + 5), write_count = be16(req + 7);
      if (outside(kMaxReadWriteRead) || write_count < 1 || write_count > kMaxReadWriteWrite)
        return detail::exception_reply(function, E::illegal_data_value, reply);
      const E e = bank.check_write(write_address, write_count, req + 10);
      if (e != E::none) return detail::exception_reply(function, e, reply);
      // The read's addresses are checked before anything is written: a refused read writes nothing.
      std::uint16_t probe[kMaxReadWriteRead];
      const E r = bank.read(false, address, count, probe);
      if (r != E::none) return detail::exception_reply(function, r, reply);
      bank.write(write_address, write_count, req + 10);
      return detail::read_reply(bank, false, function, address, count, reply);
    }
    case 0x01:
    case 0x02:
      return detail::exception_reply(function, outside(kMaxReadBits) ? E::illegal_data_value : E::illegal_data_address,
                                     reply);
    case 0x0F:
      return detail::exception_reply(function, outside(kMaxWriteBits) ? E::illegal_data_value : E::illegal_function,
                                     reply);
    default:
      return detail::exception_reply(function, E::illegal_function, reply);
  }
}

}  // namespace dyncal::drive
