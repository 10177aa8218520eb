// libFuzzer target: the drive's whole Modbus request handler (host_sim/drive/src/modbus_request_handler.cpp)
// on any byte stream from one TCP client, on a simulated er20 drive: framing, lib/'s PDU server and its
// replies, the register map, the access and state rules, staging, commits to a real table file and
// the trajectory playing between requests. Each input starts from a fresh drive with no table file,
// so a finding replays. Checks, after every frame, what the drive promises (docs/reliability.md):
//   - every reply is one well-formed Modbus TCP frame answering that request (same transaction id,
//     protocol 0, the function code or its exception), and a request gets at most one;
//   - the active table always decodes (format, CRC) and belongs to this robot;
//   - a table is committed only after the unlock key was written;
//   - no request stalls the drive (a 10 s time-out per input in scripts/fuzz).
// Crashes, leaks, ASan and UBSan findings abort as well. Corpus: tests/fuzz/corpus/modbus_request,
// request streams recorded from a drive (unlock, stage and commit its own table; start, read the ring,
// acknowledge, stop; refused and ignored requests).
#include <sys/socket.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "modbus_request_handler.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using dyncal::drive::be16;
using dyncal::drive::MbapFrame;

void fail(const char* what) {
  std::fprintf(stderr, "fuzz_modbus_request: %s\n", what);
  std::abort();
}

// What stays for the whole run: the robot and a socket pair (the handler replies into one end, the
// target reads the other).
struct Fixture {
  dyncal::host::RobotDescription robot = dyncal::host::load_robot(DYNCAL_SOURCE_DIR "/robots", "er20");
  dyncal::host::Scenario scenario = dyncal::host::default_scenario(robot);
  std::string table_path;
  int fds[2] = {-1, -1};
  Fixture() {
    char dir[] = "/tmp/dyncal_fuzz_XXXXXX";
    if (!::mkdtemp(dir)) fail("mkdtemp");
    table_path = std::string(dir) + "/drive.table";
    if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK, 0, fds) != 0) fail("socket pair");
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

// Reads what the handler sent for one request frame and checks it.
void check_replies(const std::uint8_t* request, const MbapFrame& f) {
  std::uint8_t reply[4096];
  const ssize_t n = ::recv(fixture().fds[1], reply, sizeof reply, 0);
  if (n <= 0) return;  // ignored (another protocol or unit)
  const MbapFrame r = dyncal::drive::next_mbap_frame(reply, static_cast<std::size_t>(n));
  if (r.status != MbapFrame::Status::complete || r.bytes != static_cast<std::size_t>(n))
    fail("a reply is not exactly one Modbus TCP frame");
  if (f.protocol != 0 || (f.unit != 0xFF && f.unit != 1)) fail("a frame for another protocol or unit was answered");
  if (be16(reply) != be16(request) || r.protocol != 0) fail("a reply does not answer its request's transaction");
  const std::uint8_t function = request[dyncal::drive::kMbapHeaderBytes];
  const std::uint8_t answered = reply[dyncal::drive::kMbapHeaderBytes];
  if (answered != function && answered != (function | 0x80)) {
    std::fprintf(stderr, "request function %d, reply function %d\n", function, answered);
    fail("a reply names another function");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Fixture& fx = fixture();
  ::unlink(fx.table_path.c_str());
  dyncal::host::SimulatedDrive drive(fx.robot, fx.scenario, fx.table_path);
  dyncal::host::ModbusRequestHandler handler(drive, -1, 1, nullptr);
  const int client = fx.fds[0];
  bool unlocked = false;
  std::size_t used = 0;
  while (used < size) {
    const MbapFrame f = dyncal::drive::next_mbap_frame(data + used, size - used);
    if (f.status != MbapFrame::Status::complete) {
      // A partial or invalid frame: the handler consumes nothing of it (and drops the client when invalid).
      const auto r = handler.serve_tcp(data + used, size - used, client);
      if (r.used != 0 || r.frames != 0 || r.keep != (f.status == MbapFrame::Status::incomplete))
        fail("a partial or invalid frame was consumed");
      break;
    }
    const std::uint8_t* frame = data + used;
    used += f.bytes;
    const std::uint32_t generation = drive.table_generation();
    const auto r = handler.serve_tcp(frame, f.bytes, client);
    if (r.used != f.bytes || r.frames != 1) fail("one complete frame was not consumed as one frame");
    if (!r.keep) break;  // the reply could not be sent: the server would close the connection
    check_replies(frame, f);
    // Did this frame write the unlock key? (function 6 or 16 covering kUnlockReg with the key)
    const std::uint8_t* pdu = frame + dyncal::drive::kMbapHeaderBytes;
    const std::size_t pdu_bytes = f.bytes - dyncal::drive::kMbapHeaderBytes;
    if (pdu_bytes >= 5 && pdu[0] == 6 && be16(pdu + 1) == mm::kUnlockReg && be16(pdu + 3) == mm::kUnlockKey)
      unlocked = true;
    if (pdu_bytes >= 6 && pdu[0] == 16) {
      const int address = be16(pdu + 1), count = be16(pdu + 3);
      const int k = mm::kUnlockReg - address;
      if (k >= 0 && k < count && pdu_bytes >= 6 + 2 * static_cast<std::size_t>(k) + 2 &&
          be16(pdu + 6 + 2 * k) == mm::kUnlockKey)
        unlocked = true;
    }
    if (drive.table_generation() != generation && !unlocked) fail("a table was committed without the unlock key");
    dyncal::ParameterTable t;
    const auto& bytes = drive.active_table_bytes();
    if (dyncal::decode_table(bytes.data(), static_cast<int>(bytes.size()), t) != dyncal::TableStatus::ok ||
        t.robot_id != drive.robot_id())
      fail("the active table does not decode or belongs to another robot");
    // The trajectory plays between requests, as in the server's lockstep loop.
    for (int k = 0; k < 5 && drive.state() == mm::DriveState::playing && !drive.ring_full(); ++k) drive.step();
  }
  // Whatever is left unread belongs to this input only.
  std::uint8_t sink[4096];
  while (::recv(fx.fds[1], sink, sizeof sink, 0) > 0) {
  }
  return 0;
}
