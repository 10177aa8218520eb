// A minimal drive as a drive maker writes one with dyncal (docs/firmware.md "Building a drive"):
// lib/'s RTU receiver and register server over the drive's own type, here a table held in RAM
// (no arm, no flash: see port/cortex_m/app/drive.cpp for the flash A/B store and a real UART).
// The serial line is played by a scripted host that sends its requests in irregular pieces, as a
// line delivers them; the image checks each reply (CRC, function, values) and exits 0 when the
// host could read the drive's identity, stage a table of the er20's model in a session, commit it,
// and read back the drive's verdict and the active table's CRC.
#include <cstdint>

#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/ring_window.hpp"
#include "dyncal/drive/rtu_receiver.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "er20_identification.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using Model = example::Model;

/// The drive type lib/'s register server asks (register_server.hpp): the rules' queries, the
/// commands, and what the registers show.
struct MinimalDrive {
  dyncal::ParameterTable active{}, staged{};
  std::uint8_t bytes[dyncal::kTableMaxBytes] = {};
  int size = 0;

  mm::DriveState state() const { return mm::DriveState::idle; }
  std::uint32_t acked() const { return 0; }
  std::uint32_t produced() const { return 0; }
  long ring_capacity_samples() const { return 0; }
  long run_samples(double periods, double period_s, double fs) const {
    return static_cast<long>(periods * period_s * fs);
  }
  double control_rate_hz() const { return 1000.0; }
  void ack(std::uint32_t) {}
  bool start(mm::Command, const dyncal::drive::RunSettings&, const dyncal::drive::MonitorSettings&) { return false; }
  void stop() {}
  void reset() {}
  dyncal::TableStatus commit(const std::uint8_t* b, int n) {
    dyncal::TableStatus st = dyncal::decode_table(b, n, staged);
    if (st == dyncal::TableStatus::ok) st = dyncal::check_table<Model>(staged);
    if (st != dyncal::TableStatus::ok) return st;
    active = staged;  // a real drive writes its flash here (FlashParameterStore)
    return dyncal::encode_table(active, bytes, dyncal::kTableMaxBytes, &size);
  }
  void publish_inputs(std::uint16_t* in) const {
    in[mm::kMapVersionReg] = mm::kMapVersion;
    in[mm::kNumJointsReg] = Model::kNumJoints;
    mm::set_u32(in + mm::kRobotIdReg, Model::RobotType::kRobotId);
    mm::set_u32(in + mm::kActiveCrcReg, size >= 4 ? dyncal::detail::get_u32(bytes + size - 4) : 0);
  }
  void publish_window(std::uint16_t* w) const {
    const dyncal::port::DriveSample* none = nullptr;
    dyncal::drive::encode_ring_window(none, 0, dyncal::drive::RingWindowHeader{}, Model::kNumJoints,
                                      mm::RingFormat::float32, dyncal::drive::RingResolution{}, w);
  }
};

MinimalDrive g_drive;
dyncal::drive::RegisterServer<MinimalDrive> g_server{g_drive, 1000.0};
dyncal::drive::RtuReceiver<> g_line{1, 50000};
std::uint64_t g_now = 0;  ///< the drive's clock [us]; a real drive reads a timer

// --- the scripted host: its requests out, the drive's replies in
std::uint8_t g_request[dyncal::drive::kMaxRtuAduBytes];
std::uint8_t g_reply[dyncal::drive::kMaxRtuAduBytes];
std::size_t g_reply_size = 0;

/// The drive's side of the line: what a drive's "write bytes" call does.
void line_write(const std::uint8_t* b, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) g_reply[k] = b[k];
  g_reply_size = n;
}

/// One request answered by the drive (the receiver hands it over): address, PDU, CRC.
void answer(const std::uint8_t* adu, std::size_t n) {
  static std::uint8_t reply[dyncal::drive::kMaxRtuAduBytes];
  const std::size_t pdu = g_server.answer(adu + 1, n - 3, 0, g_now, reply + 1).reply_bytes;
  reply[0] = adu[0];
  line_write(reply, dyncal::drive::append_crc16(reply, 1 + pdu));
}

/// The host sends PDU pdu[0, n) to unit 1 in pieces of 1, 2, 3, ... bytes, 1 ms apart, the drive's
/// loop (push, poll) running after each; the reply's PDU length when its CRC holds, else 0.
std::size_t transact(const std::uint8_t* pdu, std::size_t n) {
  g_request[0] = 1;
  for (std::size_t k = 0; k < n; ++k) g_request[1 + k] = pdu[k];
  dyncal::drive::append_crc16(g_request, 1 + n);
  g_reply_size = 0;
  for (std::size_t sent = 0, piece = 1; sent < n + 3; sent += piece, ++piece) {
    if (piece > n + 3 - sent) piece = n + 3 - sent;
    g_now += 1000;
    g_line.push(g_request + sent, piece, g_now);  // the drive's loop: bytes in ...
    g_line.poll(g_now, answer);                   // ... requests answered
  }
  if (g_reply_size < 5) return 0;
  return dyncal::drive::crc16_holds(g_reply, g_reply_size) ? g_reply_size - 3 : 0;
}

std::uint8_t hi(int v) {
  return static_cast<std::uint8_t>((v >> 8) & 0xFF);
}
std::uint8_t lo(int v) {
  return static_cast<std::uint8_t>(v & 0xFF);
}
std::uint16_t reply_word(int k) {  // the k-th register of a read reply
  return static_cast<std::uint16_t>((g_reply[3 + 2 * k] << 8) | g_reply[4 + 2 * k]);
}

}  // namespace

int main() {
  namespace sh = dyncal::cortex_m;
  bool ok = true;
  // Identity: map version, joints, robot id.
  const std::uint8_t identity[5] = {0x04, 0, 0, 0, 4};
  ok = ok && transact(identity, 5) == 2 + 8 && reply_word(0) == mm::kMapVersion && reply_word(1) == Model::kNumJoints &&
       ((static_cast<std::uint32_t>(reply_word(2)) << 16) | reply_word(3)) == Model::RobotType::kRobotId;
  // A table of the model (the nominal-sized values 1, 2, ...): unlock, stage, commit.
  static dyncal::ParameterTable table;
  Eigen::Matrix<double, Model::kNumParams, 1> phi;
  for (int i = 0; i < Model::kNumParams; ++i) phi[i] = 1.0 + i;
  dyncal::make_table<Model>(phi, table);
  static std::uint8_t bytes[dyncal::kTableMaxBytes];
  static std::uint16_t words[1 + mm::kTableWords];
  int size = 0;
  ok = ok && dyncal::encode_table(table, bytes, dyncal::kTableMaxBytes, &size) == dyncal::TableStatus::ok;
  words[0] = static_cast<std::uint16_t>(size);
  mm::bytes_to_regs(bytes, size, words + 1);
  const std::uint8_t unlock[5] = {0x06, 0, mm::kUnlockReg, hi(mm::kUnlockKey), lo(mm::kUnlockKey)};
  ok = ok && transact(unlock, 5) == 5;
  const int count = 1 + (size + 1) / 2;  // one 16 write: a 48-parameter table fits in 123 registers
  static std::uint8_t stage[6 + 2 * 123];
  stage[0] = 0x10, stage[1] = hi(mm::kStagingSizeReg), stage[2] = lo(mm::kStagingSizeReg), stage[3] = 0;
  stage[4] = lo(count), stage[5] = static_cast<std::uint8_t>(2 * count);
  for (int k = 0; k < count; ++k) stage[6 + 2 * k] = hi(words[k]), stage[7 + 2 * k] = lo(words[k]);
  ok = ok && count <= 123 && transact(stage, 6 + 2 * static_cast<std::size_t>(count)) == 5;
  const std::uint8_t commit[5] = {0x06, 0, mm::kCommandReg, 0, static_cast<std::uint8_t>(mm::Command::commit_table)};
  ok = ok && transact(commit, 5) == 5;
  // The verdict (commit_result 0, commit_counter 1) and the active table's CRC field.
  const std::uint8_t verdict[5] = {0x04, 0, mm::kCommitResultReg, 0, 2};
  ok = ok && transact(verdict, 5) == 2 + 4 && reply_word(0) == 0 && reply_word(1) == 1;
  const std::uint8_t crc[5] = {0x04, 0, mm::kActiveCrcReg, 0, 2};
  ok = ok && transact(crc, 5) == 2 + 4 &&
       ((static_cast<std::uint32_t>(reply_word(0)) << 16) | reply_word(1)) == dyncal::detail::get_u32(bytes + size - 4);
  sh::write(ok ? "minimal drive: identity read, table staged, committed and its CRC read back over RTU\n"
               : "minimal drive: a reply was wrong\n");
  sh::exit(ok ? 0 : 1);
}
