// Firmware application: the drive application's Modbus server on the MCU — lib/'s register server
// (dyncal/drive/register_server.hpp: the register map, its access and state rules, the staging
// session, the commit) behind lib/'s RTU framing (modbus_frames.hpp), over the er20 drive of the
// drive image (dyncal/drive/drive_application.hpp on port/replay/er20_drive.hpp) with its table in
// the flash A/B parameter store (dyncal_cortex_m/flash_parameter_store.hpp). It serves a host's
// requests as RTU frames: a status read (04), a settings read (03), the unlock (06), a calibrated
// table staged in 16-writes of at most 123 registers, the commit (06), the active table read back
// (04), a table for another robot staged and committed (refused, the active one kept), and the ring
// transaction (23: an acknowledgement written, the sample window read). Prints the instructions per
// request type and per table commit (qemu -icount) and the peak stack, and exits 0 only when every
// reply is the one the Modbus Application Protocol lays out, the tables read back are the ones the
// store holds, and a corrupted frame is refused. No run plays here (the ring window is empty);
// app/drive_period.cpp counts the control period.
#include <cstdint>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/ring_window.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_cortex_m/flash_parameter_store.hpp"
#include "dyncal_cortex_m/instruction_counter.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/stack_usage.hpp"
#include "er20_drive.hpp"
#include "er20_joint_ratings.hpp"
#include "er20_replay_data.hpp"
#include "replay.hpp"

namespace {

namespace sh = dyncal::cortex_m;
namespace mm = dyncal::modbus_map;
namespace data = dyncal::replay::data;
using dyncal::TableStatus;
using Counter = sh::InstructionCounter;
using Model = dyncal::replay::LinearModel;
using Application = dyncal::replay::Er20Drive<DYNCAL_FW_SCALAR, 64>;

std::uint8_t g_request[dyncal::drive::kMaxRtuAduBytes];
std::uint8_t g_reply[dyncal::drive::kMaxRtuAduBytes];
sh::FlashParameterStore<dyncal::replay::DriveModels>& g_store =
    sh::flash_parameter_store<dyncal::replay::DriveModels>();
dyncal::replay::SimulatedArm<dyncal::replay::Er20, DYNCAL_FW_SCALAR> g_arm{dyncal::replay::arm_physics(1)};
Application g_drive{g_store, g_arm, dyncal::replay::drive_settings<Application>()};
dyncal::drive::RegisterServer<Application> g_server{g_drive, 1000.0};
/// The server's clock [us]: this image advances it 1 ms per request (the drive image reads a timer).
dyncal::drive::Microseconds g_now = 0;

/// An RTU request for server 1: PDU `pdu[0, n)` with its CRC, into g_request; its length.
std::size_t frame(const std::uint8_t* pdu, std::size_t n) {
  g_request[0] = 1;
  for (std::size_t k = 0; k < n; ++k) g_request[1 + k] = pdu[k];
  return dyncal::drive::append_crc16(g_request, 1 + n);
}

/// What a drive does with the bytes of one request: frame, check, answer, append the CRC. The
/// reply's length (0: the frame is discarded).
std::size_t serve(std::size_t n) {
  const dyncal::drive::RtuFrame f = dyncal::drive::next_rtu_request(g_request, n);
  if (f.status != dyncal::drive::RtuFrame::Status::complete || !f.crc_ok || f.address != 1) return 0;
  g_now += 1000;
  const std::size_t pdu = g_server.answer(g_request + 1, f.bytes - 3, 0, g_now, g_reply + 1).reply_bytes;
  g_reply[0] = 1;
  return dyncal::drive::append_crc16(g_reply, 1 + pdu);
}

std::uint8_t hi(int v) {
  return static_cast<std::uint8_t>((v >> 8) & 0xFF);
}
std::uint8_t lo(int v) {
  return static_cast<std::uint8_t>(v & 0xFF);
}

/// Instructions of the last request served by ask().
std::uint32_t g_instructions = 0;

/// Frames PDU pdu[0, n), serves it (counting its instructions) and checks the reply's CRC and
/// function (or its exception); the reply ADU's length, or 0 when it is not a well-formed answer.
std::size_t ask(const std::uint8_t* pdu, std::size_t n) {
  const std::size_t request = frame(pdu, n);
  const std::uint32_t t0 = Counter::ticks();
  const std::size_t reply = serve(request);
  g_instructions = Counter::elapsed(t0, Counter::ticks()) * Counter::kInstructionsPerTick;
  const bool answers = g_reply[1] == pdu[0] || g_reply[1] == (pdu[0] | 0x80);  // the reply or its exception
  return reply >= 5 && dyncal::drive::crc16_holds(g_reply, reply) && answers ? reply : 0;
}

/// 16: regs[0, count) (count <= 123) to holding registers from `address`; whether the echo came.
bool write_registers(int address, const std::uint16_t* regs, int count) {
  std::uint8_t pdu[6 + 2 * dyncal::drive::kMaxWriteRegisters] = {
      0x10, hi(address), lo(address), 0, lo(count), static_cast<std::uint8_t>(2 * count)};
  for (int k = 0; k < count; ++k) {
    pdu[6 + 2 * k] = hi(regs[k]);
    pdu[7 + 2 * k] = lo(regs[k]);
  }
  return ask(pdu, 6 + 2 * static_cast<std::size_t>(count)) == 8;
}

/// 06: one holding register; whether the echo came.
bool write_register(int address, int value) {
  const std::uint8_t pdu[5] = {0x06, hi(address), lo(address), hi(value), lo(value)};
  return ask(pdu, 5) == 8;
}

/// 04: input registers [address, address + count) into out (count <= 125).
bool read_inputs(int address, int count, std::uint16_t* out) {
  const std::uint8_t pdu[5] = {0x04, hi(address), lo(address), 0, lo(count)};
  if (ask(pdu, 5) != 5 + 2 * static_cast<std::size_t>(count)) return false;
  for (int k = 0; k < count; ++k) out[k] = dyncal::drive::be16(g_reply + 3 + 2 * k);
  return true;
}

/// Running mean of instructions per request type.
struct Tally {
  const char* name;
  long long sum = 0;
  int n = 0;
  void add() {
    sum += g_instructions;
    ++n;
  }
  void print() const {
    sh::write("  ");
    sh::write(name);
    sh::write(": ");
    sh::write_int(n > 0 ? sum / n : 0);
    sh::write("\n");
  }
};

Tally g_unlock{"06 write a register (unlock)"};
static_assert(Model::kNumParams == 48, "the tally's name gives the table's size");
Tally g_stage{"16 write 108 registers (staging_size and a 48-parameter table)"},
    g_commit{"06 commit (check, A/B flash write, verify)"};

/// A host's flash transaction: unlock, the encoded table staged (staging_size and its bytes, in
/// writes of at most 123 registers), commit; the commit_result the drive gives (-1: a request failed).
int flash(const dyncal::ParameterTable& table) {
  static std::uint16_t regs[1 + mm::kTableWords];
  static std::uint8_t bytes[dyncal::kTableMaxBytes];
  int size = 0;
  if (dyncal::encode_table(table, bytes, dyncal::kTableMaxBytes, &size) != TableStatus::ok) return -1;
  regs[0] = static_cast<std::uint16_t>(size);
  mm::bytes_to_regs(bytes, size, regs + 1);
  if (!write_register(mm::kUnlockReg, mm::kUnlockKey)) return -1;
  g_unlock.add();
  const int words = 1 + (size + 1) / 2;
  for (int k = 0; k < words; k += dyncal::drive::kMaxWriteRegisters) {
    const int count = words - k < dyncal::drive::kMaxWriteRegisters ? words - k : dyncal::drive::kMaxWriteRegisters;
    if (!write_registers(mm::kStagingSizeReg + k, regs + k, count)) return -1;
    g_stage.add();
  }
  if (!write_register(mm::kCommandReg, static_cast<int>(mm::Command::commit_table))) return -1;
  g_commit.add();
  std::uint16_t result = 0;
  return read_inputs(mm::kCommitResultReg, 1, &result) ? result : -1;
}

/// The active table as a host reads it (active_table_size and the bytes, in reads of at most 125
/// registers), compared with `expected`'s encoding, and the active_crc register with its CRC field.
bool reads_back(const dyncal::ParameterTable& expected) {
  static std::uint16_t regs[1 + mm::kTableWords];
  static std::uint8_t bytes[dyncal::kTableMaxBytes], read[dyncal::kTableMaxBytes];
  int size = 0;
  if (dyncal::encode_table(expected, bytes, dyncal::kTableMaxBytes, &size) != TableStatus::ok) return false;
  for (int k = 0; k < 1 + mm::kTableWords; k += 125) {
    const int count = 1 + mm::kTableWords - k < 125 ? 1 + mm::kTableWords - k : 125;
    if (!read_inputs(mm::kActiveTableSizeReg + k, count, regs + k)) return false;
  }
  if (regs[0] != size) return false;
  mm::regs_to_bytes(regs + 1, size, read);
  for (int i = 0; i < size; ++i)
    if (read[i] != bytes[i]) return false;
  std::uint16_t crc[2];
  return read_inputs(mm::kActiveCrcReg, 2, crc) && mm::get_u32(crc) == dyncal::detail::get_u32(bytes + size - 4);
}

}  // namespace

int main() {
  sh::StackUsage::paint();
  static_assert(Model::kNumJoints == 6, "the er20");
  // The store checks each table against the models; the application has checked it against the ratings too.
  g_drive.load();  // the table the flash holds, if any
  Counter::start();
  bool ok = true;
  constexpr int kRepeats = 50;
  sh::write(
      "dyncal firmware Modbus RTU server (lib/ drive register server, framing, flash A/B store; er20), "
      "instructions per request (frame, CRC check, answer, reply CRC; qemu -icount, +-40):\n");
  // Reads: the state, counters and model error; the trajectory settings.
  Tally status{"04 read 60 input registers"}, settings{"03 read 125 holding registers"};
  const std::uint8_t read_status[5] = {0x04, 0, 0, 0, 60}, read_settings[5] = {0x03, 0, 0, 0, 125};
  for (int i = 0; i < kRepeats; ++i) {
    ok = ok && ask(read_status, 5) == 3 + 2 + 120;
    status.add();
    ok = ok && ask(read_settings, 5) == 3 + 2 + 250;
    settings.add();
  }
  // A calibrated table (the KF replay's estimate), flashed three times: both slots written.
  static dyncal::ParameterTable table, other;  // static: a table is 0.9 kB, the stack 4 kB
  dyncal::make_table<Model>(Eigen::Map<const Eigen::Matrix<double, Model::kNumParams, 1>>(data::kReferenceKf), table);
  for (int i = 0; i < 3; ++i) ok = ok && flash(table) == static_cast<int>(TableStatus::ok);
  ok = ok && reads_back(table) && g_store.generation() >= 3;
  // A table for another robot: refused, the active one stays (in flash and in the registers).
  other = table;
  other.robot_id ^= 1u;
  ok = ok && flash(other) == static_cast<int>(TableStatus::wrong_robot) && reads_back(table);
  // Staging without a session: refused with 01, nothing staged.
  const std::uint8_t stage_locked[5] = {0x06, hi(mm::kStagingSizeReg), lo(mm::kStagingSizeReg), 0, 4};
  ok = ok && ask(stage_locked, 5) == 5 && g_reply[1] == 0x86 && g_reply[2] == 0x01;
  // The longest write: 123 registers of staging, in a session.
  Tally longest{"16 write 123 registers"};
  static std::uint16_t words[dyncal::drive::kMaxWriteRegisters];
  for (int k = 0; k < dyncal::drive::kMaxWriteRegisters; ++k) words[k] = static_cast<std::uint16_t>(k * 7 + 3);
  ok = ok && write_register(mm::kUnlockReg, mm::kUnlockKey);
  for (int i = 0; i < kRepeats; ++i) {
    ok = ok && write_registers(mm::kStagingTableReg, words, dyncal::drive::kMaxWriteRegisters);
    longest.add();
  }
  // The ring transaction: ack 0 written, the (empty) window read.
  Tally ring{"23 write 2, read 125 registers"};
  const std::uint8_t ring_pdu[14] = {
      0x17, hi(mm::kRingReg), lo(mm::kRingReg), 0, 125, hi(mm::kAckReg), lo(mm::kAckReg), 0, 2, 4, 0, 0, 0, 0};
  for (int i = 0; i < kRepeats; ++i) {
    ok = ok && ask(ring_pdu, 14) == 3 + 2 + 250;
    ring.add();
  }
  status.print();
  settings.print();
  g_unlock.print();
  longest.print();
  g_stage.print();
  g_commit.print();
  ring.print();
  // A corrupted frame: discarded without a reply.
  const std::size_t n = frame(read_status, 5);
  g_request[3] ^= 0x10;
  ok = ok && serve(n) == 0;
  sh::write("  stack: peak ");
  sh::write_int(sh::StackUsage::peak_bytes());
  sh::write(" bytes of ");
  sh::write_int(sh::StackUsage::reserved_bytes());
  sh::write(ok ? " reserved; every reply as the protocol lays it out, the tables read back as the flash holds them\n"
               : " reserved; a reply or a table read back is wrong\n");
  return ok ? 0 : 1;
}
