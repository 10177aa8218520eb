// lib/'s Modbus PDU server (dyncal/drive/modbus_pdu_server.hpp) on a register bank of its own: each
// function's reply as the Modbus Application Protocol v1.1b3 lays it out (sec. 6.3, 6.4, 6.6, 6.12,
// 6.17) and each exception of sec. 7, byte for byte. The drive's own bank (register map, access and
// state rules) is served by the same function and tested against libmodbus in test_drive_modbus.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "dyncal/drive/modbus_pdu_server.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace modbus_pdu_server_suite {

using dyncal::drive::ModbusException;

/// 200 holding and 200 input registers; register 7 refuses writes (busy) and 150..199 do not exist.
struct ToyBank {
  std::array<std::uint16_t, 200> holding{}, input{};
  int writes = 0;
  ModbusException read(bool in, std::uint16_t address, std::uint16_t count, std::uint16_t* out) const {
    if (address + count > 150) return ModbusException::illegal_data_address;
    for (int k = 0; k < count; ++k) out[k] = (in ? input : holding)[static_cast<size_t>(address + k)];
    return ModbusException::none;
  }
  ModbusException check_write(std::uint16_t address, std::uint16_t count, const std::uint8_t*) const {
    if (address + count > 150) return ModbusException::illegal_data_address;
    if (address <= 7 && 7 < address + count) return ModbusException::server_device_busy;
    return ModbusException::none;
  }
  void write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values) {
    for (int k = 0; k < count; ++k)
      holding[static_cast<size_t>(address + k)] = static_cast<std::uint16_t>((values[2 * k] << 8) | values[2 * k + 1]);
    ++writes;
  }
};

std::vector<std::uint8_t> serve(ToyBank& bank, std::vector<std::uint8_t> request) {
  std::uint8_t reply[dyncal::drive::kMaxPduBytes];
  const std::size_t n = dyncal::drive::serve_pdu(bank, request.data(), request.size(), reply);
  return std::vector<std::uint8_t>(reply, reply + n);
}

using Bytes = std::vector<std::uint8_t>;

TEST(ModbusPduServer, RepliesAsTheApplicationProtocolLaysThemOut) {
  ToyBank bank;
  for (int k = 0; k < 200; ++k) bank.holding[k] = static_cast<std::uint16_t>(0x0100 + k), bank.input[k] = 0xA000 + k;
  // 03: function, byte count, values high byte first.
  EXPECT_EQ(serve(bank, {0x03, 0x00, 0x6B, 0x00, 0x02}), (Bytes{0x03, 0x04, 0x01, 0x6B, 0x01, 0x6C}));
  EXPECT_EQ(serve(bank, {0x04, 0x00, 0x08, 0x00, 0x01}), (Bytes{0x04, 0x02, 0xA0, 0x08}));
  // 06: the request echoed, the register written.
  EXPECT_EQ(serve(bank, {0x06, 0x00, 0x01, 0x00, 0x03}), (Bytes{0x06, 0x00, 0x01, 0x00, 0x03}));
  EXPECT_EQ(bank.holding[1], 0x0003);
  // 16: function, address, quantity.
  EXPECT_EQ(serve(bank, {0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02}),
            (Bytes{0x10, 0x00, 0x01, 0x00, 0x02}));
  EXPECT_EQ(bank.holding[1], 0x000A);
  EXPECT_EQ(bank.holding[2], 0x0102);
  // 23: the write first, then the read, which shows it.
  EXPECT_EQ(serve(bank, {0x17, 0x00, 0x0E, 0x00, 0x02, 0x00, 0x0F, 0x00, 0x01, 0x02, 0xBE, 0xEF}),
            (Bytes{0x17, 0x04, 0x01, 0x0E, 0xBE, 0xEF}));
}

TEST(ModbusPduServer, RefusesWithTheExceptionOfSection7AndChangesNothing) {
  ToyBank bank;
  auto refused = [&](Bytes request, std::uint8_t function, ModbusException e) {
    const int writes = bank.writes;
    EXPECT_EQ(serve(bank, request), (Bytes{function, static_cast<std::uint8_t>(e)}));
    EXPECT_EQ(bank.writes, writes);
  };
  refused({0x03, 0x00, 0x00, 0x00, 0x00}, 0x83, ModbusException::illegal_data_value);  // quantity 0
  refused({0x03, 0x00, 0x00, 0x00, 126}, 0x83, ModbusException::illegal_data_value);   // above 125
  EXPECT_EQ(serve(bank, {0x03, 0x00, 0x00, 0x00, 125}).size(), 2u + 250u);
  refused({0x03, 0x00, 0x00, 0x00}, 0x83, ModbusException::illegal_data_value);          // a short PDU
  refused({0x03, 0x00, 0x95, 0x00, 0x02}, 0x83, ModbusException::illegal_data_address);  // beyond the map
  refused({0x06, 0x00, 0x07, 0x00, 0x01}, 0x86, ModbusException::server_device_busy);    // the bank's rule
  refused({0x10, 0x00, 0x06, 0x00, 0x02, 0x04, 0, 1, 0, 2}, 0x90, ModbusException::server_device_busy);
  refused({0x10, 0x00, 0x01, 0x00, 0x02, 0x03, 0, 1, 0}, 0x90, ModbusException::illegal_data_value);  // byte count
  refused({0x10, 0x00, 0x01, 0x00, 124}, 0x90, ModbusException::illegal_data_value);
  // 23: a refused read address writes nothing.
  refused({0x17, 0x00, 0x95, 0x00, 0x02, 0x00, 0x0F, 0x00, 0x01, 0x02, 0xBE, 0xEF}, 0x97,
          ModbusException::illegal_data_address);
  EXPECT_EQ(bank.holding[15], 0);
  refused({0x17, 0x00, 0x00, 0x00, 0x01, 0x00, 0x0F, 0x00, 122, 0x02, 0xBE, 0xEF}, 0x97,
          ModbusException::illegal_data_value);
  // No coils: a read of a valid quantity is an illegal address, a write an illegal function.
  refused({0x01, 0x00, 0x00, 0x00, 0x08}, 0x81, ModbusException::illegal_data_address);
  refused({0x02, 0x00, 0x00, 0x07, 0xD1}, 0x82, ModbusException::illegal_data_value);  // 2001 bits
  refused({0x05, 0x00, 0x00, 0xFF, 0x00}, 0x85, ModbusException::illegal_function);
  refused({0x0F, 0x00, 0x00, 0x00, 0x08, 0x01, 0xFF}, 0x8F, ModbusException::illegal_function);
  refused({0x11}, 0x91, ModbusException::illegal_function);
  refused({0x2B, 0x0E, 0x01, 0x00}, 0xAB, ModbusException::illegal_function);
  // A code reserved for exception replies is answered under its own code.
  refused({0x83, 0x00, 0x00, 0x00, 0x01}, 0x83, ModbusException::illegal_function);
  EXPECT_TRUE(serve(bank, {}).empty());
}

}  // namespace modbus_pdu_server_suite
}  // namespace
