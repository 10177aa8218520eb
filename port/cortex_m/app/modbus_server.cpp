// Firmware application: the drive application's Modbus request path on the MCU (lib/
// dyncal/drive/modbus_frames.hpp and modbus_pdu_server.hpp) over the drive's register counts
// (dyncal/modbus_map.hpp): RTU requests as a host sends them — a status read (04), a settings read
// (03), a command write (06), a 123-register table staging write (16) and the ring transaction (23:
// an acknowledgement written, the sample window read) — framed by length, CRC-checked, answered,
// and the reply's CRC appended. Prints the instructions per request type (qemu -icount) and the
// peak stack, and exits 0 only when every reply is the one the Modbus Application Protocol lays
// out (function, byte count, echoed fields, the written values read back, a valid CRC) and a
// corrupted frame is refused.
#include <cstdint>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/modbus_pdu_server.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal_cortex_m/instruction_counter.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/stack_usage.hpp"

namespace {

namespace sh = dyncal::cortex_m;
namespace mm = dyncal::modbus_map;
using dyncal::drive::ModbusException;
using Counter = sh::InstructionCounter;

/// The drive's register banks at their real sizes, every address defined, every write accepted
/// (the access and state rules are the drive application's, not this image's).
struct Bank {
  std::uint16_t holding[mm::kHoldingWords];
  std::uint16_t input[mm::kInputWords];
  ModbusException read(bool in, std::uint16_t address, std::uint16_t count, std::uint16_t* out) const {
    if (address + count > (in ? mm::kInputWords : mm::kHoldingWords)) return ModbusException::illegal_data_address;
    const std::uint16_t* r = in ? input : holding;
    for (int k = 0; k < count; ++k) out[k] = r[address + k];
    return ModbusException::none;
  }
  ModbusException check_write(std::uint16_t address, std::uint16_t count, const std::uint8_t*) const {
    return address + count > mm::kHoldingWords ? ModbusException::illegal_data_address : ModbusException::none;
  }
  void write(std::uint16_t address, std::uint16_t count, const std::uint8_t* values) {
    for (int k = 0; k < count; ++k) holding[address + k] = dyncal::drive::be16(values + 2 * k);
  }
};

Bank g_bank;
std::uint8_t g_request[dyncal::drive::kMaxRtuAduBytes];
std::uint8_t g_reply[dyncal::drive::kMaxRtuAduBytes];

/// An RTU request for server 1: PDU `pdu[0, n)` with its CRC, into g_request; its length.
std::size_t frame(const std::uint8_t* pdu, std::size_t n) {
  g_request[0] = 1;
  for (std::size_t k = 0; k < n; ++k) g_request[1 + k] = pdu[k];
  const std::uint16_t crc = dyncal::drive::crc16(g_request, 1 + n);
  g_request[1 + n] = static_cast<std::uint8_t>(crc & 0xFF);
  g_request[2 + n] = static_cast<std::uint8_t>(crc >> 8);
  return 3 + n;
}

/// What a drive does with the bytes of one request: frame, check, answer, append the CRC. The
/// reply's length (0: the frame is discarded).
std::size_t serve(std::size_t n) {
  const dyncal::drive::RtuFrame f = dyncal::drive::next_rtu_request(g_request, n);
  if (f.status != dyncal::drive::RtuFrame::Status::complete || !f.crc_ok || f.address != 1) return 0;
  const std::size_t pdu = dyncal::drive::serve_pdu(g_bank, g_request + 1, f.bytes - 3, g_reply + 1);
  g_reply[0] = 1;
  const std::uint16_t crc = dyncal::drive::crc16(g_reply, 1 + pdu);
  g_reply[1 + pdu] = static_cast<std::uint8_t>(crc & 0xFF);
  g_reply[2 + pdu] = static_cast<std::uint8_t>(crc >> 8);
  return 3 + pdu;
}

bool reply_crc_ok(std::size_t n) {
  const std::uint16_t crc = dyncal::drive::crc16(g_reply, n - 2);
  return g_reply[n - 2] == (crc & 0xFF) && g_reply[n - 1] == (crc >> 8);
}

struct Request {
  const char* name;
  std::uint8_t pdu[dyncal::drive::kMaxPduBytes];
  std::size_t n;
  std::size_t reply;  ///< the reply ADU's length the protocol gives
};

std::uint8_t hi(int v) {
  return static_cast<std::uint8_t>((v >> 8) & 0xFF);
}
std::uint8_t lo(int v) {
  return static_cast<std::uint8_t>(v & 0xFF);
}

Request g_requests[5];

void build_requests() {
  Request& status = g_requests[0];  // 04: the state, counters and model error
  status = {"04 read 60 input registers", {0x04, 0, 0, 0, 60}, 5, 3 + 2 + 120};
  Request& settings = g_requests[1];  // 03: the trajectory settings
  settings = {"03 read 125 holding registers", {0x03, 0, 0, 0, 125}, 5, 3 + 2 + 250};
  Request& command = g_requests[2];  // 06: a command
  command = {"06 write a register", {0x06, hi(mm::kCommandReg), lo(mm::kCommandReg), 0, 1}, 5, 3 + 5};
  Request& staging = g_requests[3];  // 16: 123 registers of a table staged
  staging = {"16 write 123 registers",
             {0x10, hi(mm::kStagingTableReg), lo(mm::kStagingTableReg), 0, 123, 246},
             6 + 246,
             3 + 5};
  for (int k = 0; k < 246; ++k) staging.pdu[6 + k] = static_cast<std::uint8_t>(k * 7 + 3);
  Request& ring = g_requests[4];  // 23: the acknowledgement written, the sample window read
  ring = {
      "23 write 2, read 125 registers",
      {0x17, hi(mm::kRingReg), lo(mm::kRingReg), 0, 125, hi(mm::kAckReg), lo(mm::kAckReg), 0, 2, 4, 0, 0, 0x12, 0x34},
      14,
      3 + 2 + 250};
}

}  // namespace

int main() {
  sh::StackUsage::paint();
  for (int k = 0; k < mm::kHoldingWords; ++k) g_bank.holding[k] = static_cast<std::uint16_t>(k);
  for (int k = 0; k < mm::kInputWords; ++k) g_bank.input[k] = static_cast<std::uint16_t>(0x8000 + k);
  build_requests();
  Counter::start();
  bool ok = true;
  constexpr int kRepeats = 50;
  sh::write(
      "dyncal firmware Modbus RTU request path (lib/ drive framing and PDU server), instructions per "
      "request (frame, CRC check, answer, reply CRC; qemu -icount, +-40):\n");
  for (const Request& r : g_requests) {
    std::uint32_t ticks = 0;
    std::size_t reply = 0;
    for (int i = 0; i < kRepeats; ++i) {
      const std::size_t n = frame(r.pdu, r.n);
      const std::uint32_t t0 = Counter::ticks();
      reply = serve(n);
      ticks += Counter::elapsed(t0, Counter::ticks());
    }
    // The reply the protocol lays out: its length, the request's function, a valid CRC.
    ok = ok && reply == r.reply && g_reply[1] == r.pdu[0] && reply_crc_ok(reply);
    sh::write("  ");
    sh::write(r.name);
    sh::write(": ");
    sh::write_int(static_cast<long long>(ticks) * Counter::kInstructionsPerTick / kRepeats);
    sh::write("\n");
  }
  // What the writes left: the staged bytes and the acknowledgement read back.
  for (int k = 0; k < 123; ++k)
    ok = ok && g_bank.holding[mm::kStagingTableReg + k] == dyncal::drive::be16(g_requests[3].pdu + 6 + 2 * k);
  ok = ok && g_bank.holding[mm::kAckReg + 1] == 0x1234;
  // A corrupted frame: discarded without a reply.
  const std::size_t n = frame(g_requests[0].pdu, g_requests[0].n);
  g_request[3] ^= 0x10;
  ok = ok && serve(n) == 0;
  sh::write("  stack: peak ");
  sh::write_int(sh::StackUsage::peak_bytes());
  sh::write(" bytes of ");
  sh::write_int(sh::StackUsage::reserved_bytes());
  sh::write(ok ? " reserved; every reply as the protocol lays it out\n" : " reserved; a reply is wrong\n");
  return ok ? 0 : 1;
}
