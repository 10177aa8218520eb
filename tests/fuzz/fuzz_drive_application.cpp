// libFuzzer target: the firmware drive's whole request path (port/cortex_m/app/drive.cpp without its
// UART and flash) on any byte stream of its RTU line: lib/'s RTU receiver, register server and drive
// application (dyncal/drive/drive_application.hpp: the table, run control, control law, collision
// monitor, payload run, sample ring) over the drive image's simulated er20 (port/replay/
// er20_drive.hpp) and a parameter store in memory. Between requests, and between the chunks the
// bytes arrive in, the drive runs the control periods it wants (at most 20 per chunk), as the
// image's loop does. Each input starts from a fresh drive on its factory table, so a finding
// replays. Checks after every chunk what the drive promises:
//   - every reply is one well-formed RTU frame from unit 1 (its CRC holds) answering its request's
//     function (or that function's exception);
//   - the active table passes the drive's own check (its robot, a model it runs, the ratings) and is
//     what the store holds once anything was stored;
//   - the store is written only after an unlock request reached the drive;
//   - lockstep: no sample is ever dropped (overruns 0), the ring never holds more than it can.
// Crashes, ASan and UBSan findings abort as well. Corpus: tests/fuzz/corpus/drive_application (the
// RTU corpus's requests, a run read through its ring, a watched payload run, a commit).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/rtu_receiver.hpp"
#include "support/er20_drive_in_memory.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using Application = dyncal::replay::Er20Drive<double, 64>;

void fail(const char* what) {
  std::fprintf(stderr, "fuzz_drive_application: %s\n", what);
  std::abort();
}

struct Drive {
  dyncal::test::er20_drive::MemoryStore store;
  dyncal::replay::SimulatedArm<dyncal::replay::Er20, double> arm{dyncal::replay::arm_physics(1)};
  Application app{store, arm, dyncal::replay::drive_settings<Application>()};
  dyncal::drive::RegisterServer<Application> server{app, 1000.0};
  dyncal::drive::RtuReceiver<> line{1, 50000};
  bool unlocked = false;
};

Drive* g_drive = nullptr;
std::uint64_t g_now = 0;

void answer(const std::uint8_t* adu, std::size_t n) {
  Drive& d = *g_drive;
  if (adu[1] == 0x06 && n >= 8 && (adu[2] << 8 | adu[3]) == mm::kUnlockReg) d.unlocked = true;
  if (adu[1] == 0x10 && n >= 9) {
    const int address = adu[2] << 8 | adu[3], count = adu[4] << 8 | adu[5];
    if (address <= mm::kUnlockReg && mm::kUnlockReg < address + count) d.unlocked = true;
  }
  std::uint8_t reply[dyncal::drive::kMaxRtuAduBytes];
  const std::size_t pdu = d.server.answer(adu + 1, n - 3, 0, g_now, reply + 1).reply_bytes;
  if (pdu == 0) return;
  reply[0] = adu[0];
  const std::size_t length = dyncal::drive::append_crc16(reply, 1 + pdu);
  if (!dyncal::drive::crc16_holds(reply, length) || reply[0] != 1) fail("a reply is not an RTU frame of unit 1");
  if (reply[1] != adu[1] && reply[1] != (adu[1] | 0x80)) fail("a reply names another function");
}

/// What holds after every chunk; `ratings`: the active table's plausibility too (its 64 rated
/// states: at the input's end only, the check is the costly part of an execution).
void check(const Drive& d, bool ratings = false) {
  const dyncal::ParameterTable& t = d.app.active_table();
  if ((ratings ? dyncal::replay::DriveModels::check(t, dyncal::replay::ratings())
               : dyncal::replay::DriveModels::check(t)) != dyncal::TableStatus::ok)
    fail("the active table does not pass the drive's own check");
  if (d.store.writes > 0 && !d.unlocked) fail("the store was written without an unlock");
  if (d.store.holds && (d.store.table.model_id != t.model_id || d.store.table.count != t.count))
    fail("the active table is not the stored one");
  static std::uint16_t in[mm::kInputWords];
  d.app.publish_inputs(in);
  if (mm::get_u32(in + mm::kOverrunReg) != 0) fail("a sample was dropped in lockstep");
  if (d.app.ring().size() > 64) fail("the ring holds more than it can");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto drive = std::make_unique<Drive>();
  g_drive = drive.get();
  g_now = 0;
  if (drive->app.activate(dyncal::replay::factory_table()) != dyncal::TableStatus::ok) fail("factory table");
  // The input is chunks: a length byte L, L line bytes, then a byte b: a line silence of
  // (b % 16 + 1) * 10 ms (a frame split over it, a resync after 50 ms).
  std::size_t k = 0;
  while (k < size) {
    const std::size_t length = data[k++];
    const std::size_t n = length < size - k ? length : size - k;
    drive->line.push(data + k, n, g_now);
    k += n;
    drive->line.poll(g_now, answer);
    for (int p = 0; p < 20 && drive->app.wants_period(); ++p) drive->app.period();
    check(*drive);
    if (k < size) g_now += (data[k++] % 16 + 1) * 10000ull;
    drive->line.poll(g_now, answer);
    check(*drive);
  }
  check(*drive, true);
  g_drive = nullptr;
  return 0;
}
