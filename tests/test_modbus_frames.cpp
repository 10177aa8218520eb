// lib/'s Modbus framing (dyncal/drive/modbus_frames.hpp) against independent references: the CRC-16
// examples of the MODBUS over Serial Line specification (v1.02, sec. 6.2.2 and its read-holding-
// registers example), and the RTU requests libmodbus itself writes to a serial line (a
// pseudo-terminal: libmodbus on its device, the test on its master side).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "dyncal/drive/modbus_frames.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace modbus_frames_suite {

using dyncal::drive::RtuFrame;

std::vector<std::uint8_t> bytes(std::initializer_list<int> b) {
  std::vector<std::uint8_t> out;
  for (const int x : b) out.push_back(static_cast<std::uint8_t>(x));
  return out;
}

// The specification's examples: 01 03 00 00 00 0A is sent with CRC C5 CD (low byte first), the
// read of three holding registers at 0x006B from server 0x11 with 76 87.
TEST(ModbusFrames, Crc16IsTheSerialLineSpecificationsExamples) {
  const auto a = bytes({0x01, 0x03, 0x00, 0x00, 0x00, 0x0A}), b = bytes({0x11, 0x03, 0x00, 0x6B, 0x00, 0x03});
  EXPECT_EQ(dyncal::drive::crc16(a.data(), a.size()), 0xCDC5);
  EXPECT_EQ(dyncal::drive::crc16(b.data(), b.size()), 0x8776);
  static_assert(dyncal::drive::crc16(nullptr, 0) == 0xFFFF, "the CRC's initial value");
  // t3.5: 3.5 characters of 11 bits, a fixed 1750 us above 19 200 baud (sec. 2.5.1.1).
  EXPECT_EQ(dyncal::drive::rtu_silence_us(9600), 4011u);
  EXPECT_EQ(dyncal::drive::rtu_silence_us(19200), 2006u);
  EXPECT_EQ(dyncal::drive::rtu_silence_us(115200), 1750u);
}

/// A pseudo-terminal with libmodbus's RTU client on its device (server address 17, a short
/// response time-out: nobody answers) and the master side open here, non-blocking.
struct Line {
  int master = -1;
  modbus_t* ctx = nullptr;
  Line() {
    master = ::posix_openpt(O_RDWR | O_NOCTTY);
    if (master < 0 || ::grantpt(master) != 0 || ::unlockpt(master) != 0) return;
    ::fcntl(master, F_SETFL, ::fcntl(master, F_GETFL) | O_NONBLOCK);
    ctx = modbus_new_rtu(::ptsname(master), 115200, 'N', 8, 1);
    if (!ctx || modbus_set_slave(ctx, 17) != 0 || modbus_connect(ctx) != 0) return;
    modbus_set_response_timeout(ctx, 0, 20000);
  }
  ~Line() {
    if (ctx) modbus_close(ctx), modbus_free(ctx);
    if (master >= 0) ::close(master);
  }
  /// What libmodbus wrote to the line while `request` ran (it times out: no server).
  std::vector<std::uint8_t> sent(const std::function<void(modbus_t*)>& request) {
    request(ctx);
    std::vector<std::uint8_t> out;
    std::uint8_t buf[512];
    for (ssize_t n; (n = ::read(master, buf, sizeof buf)) > 0;) out.insert(out.end(), buf, buf + n);
    return out;
  }
};

// Every request function a drive serves, as libmodbus frames it: next_rtu_request waits through
// every proper prefix, then finds the whole frame with its CRC right and its PDU consistent; a
// flipped bit anywhere in a frame of unchanged length makes the CRC wrong; two frames back to back
// are told apart.
TEST(ModbusFrames, LibmodbusRtuRequestsFrameByTheirLength) {
  Line line;
  ASSERT_NE(line.ctx, nullptr) << "cannot open a pseudo-terminal for libmodbus";
  std::uint16_t regs[125] = {};
  for (int k = 0; k < 125; ++k) regs[k] = static_cast<std::uint16_t>(0x1111 * k);
  const std::vector<std::pair<const char*, std::function<void(modbus_t*)>>> requests = {
      {"03 read holding registers", [&](modbus_t* c) { modbus_read_registers(c, 0x006B, 3, regs); }},
      {"04 read input registers", [&](modbus_t* c) { modbus_read_input_registers(c, 10, 125, regs); }},
      {"06 write single register", [&](modbus_t* c) { modbus_write_register(c, 300, 0xBEEF); }},
      {"16 write multiple registers, 1", [&](modbus_t* c) { modbus_write_registers(c, 5, 1, regs); }},
      {"16 write multiple registers, 123", [&](modbus_t* c) { modbus_write_registers(c, 5, 123, regs); }},
      {"23 read/write multiple registers",
       [&](modbus_t* c) { modbus_write_and_read_registers(c, 700, 121, regs, 900, 125, regs); }},
  };
  std::vector<std::uint8_t> stream;
  for (const auto& [name, request] : requests) {
    SCOPED_TRACE(name);
    const std::vector<std::uint8_t> adu = line.sent(request);
    ASSERT_GE(adu.size(), 8u);
    for (std::size_t n = 0; n < adu.size(); ++n)
      ASSERT_EQ(dyncal::drive::next_rtu_request(adu.data(), n).status, RtuFrame::Status::incomplete) << n;
    const RtuFrame f = dyncal::drive::next_rtu_request(adu.data(), adu.size());
    ASSERT_EQ(f.status, RtuFrame::Status::complete);
    EXPECT_EQ(f.bytes, adu.size());
    EXPECT_TRUE(f.crc_ok);
    EXPECT_EQ(f.address, 17);
    EXPECT_TRUE(dyncal::drive::request_pdu_consistent(adu.data() + 1, adu.size() - 3));
    int flipped = 0;
    for (std::size_t i = 0; i < adu.size(); ++i) {
      std::vector<std::uint8_t> bad = adu;
      bad[i] ^= static_cast<std::uint8_t>(1u << (i % 8));
      const RtuFrame g = dyncal::drive::next_rtu_request(bad.data(), bad.size());
      if (g.status != RtuFrame::Status::complete || g.bytes != adu.size()) continue;
      EXPECT_FALSE(g.crc_ok) << "byte " << i;
      ++flipped;
    }
    EXPECT_GE(flipped, static_cast<int>(adu.size()) - 2);  // all but a changed function or byte count
    stream.insert(stream.end(), adu.begin(), adu.end());
  }
  std::size_t used = 0;
  int frames = 0;
  while (used < stream.size()) {
    const RtuFrame f = dyncal::drive::next_rtu_request(stream.data() + used, stream.size() - used);
    ASSERT_EQ(f.status, RtuFrame::Status::complete);
    EXPECT_TRUE(f.crc_ok);
    used += f.bytes, ++frames;
  }
  EXPECT_EQ(frames, static_cast<int>(requests.size()));
  // A function whose request length the code does not give: the frame ends at the line's silence.
  const auto unknown = bytes({17, 0x2B, 0x0E, 0x01, 0x00});
  EXPECT_EQ(dyncal::drive::next_rtu_request(unknown.data(), unknown.size()).status, RtuFrame::Status::needs_silence);
}

}  // namespace modbus_frames_suite
}  // namespace
