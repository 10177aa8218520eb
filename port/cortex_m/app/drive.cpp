// Firmware application: a drive that serves Modbus RTU on its serial line — the drive image that
// scripts/firmware-drive runs under qemu with UART0 on a pty. lib/'s drive application receives the
// requests (dyncal/drive/rtu_receiver.hpp: length + CRC framing, resync after a silence) and
// answers them (register_server.hpp: the register map, its access and state rules, the staging
// session, the commit) over the er20's table in the flash A/B store (table_drive.hpp). The flash
// region persists in a file across restarts of qemu: read at boot, written (to a temporary file,
// then renamed) at every commit, through semihosting; the file is the second word of the command
// line (qemu -semihosting-config ...,arg=drive.elf,arg=FILE), none: the flash starts erased.
// Without a valid table in the flash the factory table is active: the robot file's nominal base
// parameters, no friction (as the simulated drive's). Prints "dyncal firmware drive: ready" on the
// semihosting console once it serves. No arm yet: a start is refused (issue 69 continues).
#include <cstdint>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/rtu_receiver.hpp"
#include "dyncal_cortex_m/flash_parameter_store.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/serial_mps2.hpp"
#include "er20_joint_ratings.hpp"
#include "table_drive.hpp"

extern "C" std::uint8_t __param_store_start[];
extern "C" std::uint8_t __param_store_end[];

namespace {

namespace sh = dyncal::cortex_m;
using dyncal::cortex_m::TableDrive;
using Model = TableDrive::Model;
using Robot = Model::RobotType;

/// The RTU line: 115 200 baud 8N1, unit 1; a frame that cannot be taken is dropped until the line
/// has been silent for 50 ms (under qemu the gaps inside one frame reach several ms; real
/// hardware would use t3.5, drive::rtu_silence_us).
constexpr std::uint32_t kBaud = 115200;
constexpr std::uint8_t kUnit = 1;
constexpr std::uint64_t kResyncUs = 50000;

char g_flash_file[200] = {};
TableDrive g_drive{sh::flash_parameter_store<Model>()};
dyncal::drive::RegisterServer<TableDrive> g_server{g_drive, 1000.0};
dyncal::drive::RtuReceiver<> g_line{kUnit, kResyncUs};
std::uint8_t g_reply[dyncal::drive::kMaxRtuAduBytes];

int region_size() {
  return static_cast<int>(__param_store_end - __param_store_start);
}

/// The flash region into its file (atomically: the old file stays when the write fails).
bool save_flash() {
  if (g_flash_file[0] == 0) return true;
  if (sh::write_file_atomically(g_flash_file, __param_store_start, region_size())) return true;
  sh::write("dyncal firmware drive: cannot write the flash file ");
  sh::write(g_flash_file);
  sh::write("\n");
  return false;
}

/// The flash file named on the command line, read into the region; erased (0xFF) where it gives
/// nothing.
void load_flash() {
  for (int i = 0; i < region_size(); ++i) __param_store_start[i] = 0xFF;
  static char line[256];
  if (!sh::command_line(line, sizeof line)) return;
  int i = 0;
  while (line[i] != 0 && line[i] != ' ') ++i;  // the image's name
  while (line[i] == ' ') ++i;
  int n = 0;
  while (line[i] != 0 && line[i] != ' ' && n + 1 < static_cast<int>(sizeof g_flash_file)) g_flash_file[n++] = line[i++];
  g_flash_file[n] = 0;
  if (n == 0) return;
  const int read = sh::read_file(g_flash_file, __param_store_start, region_size());
  if (read >= 0 && read < region_size())
    for (int k = read; k < region_size(); ++k) __param_store_start[k] = 0xFF;
}

/// The factory table: the robot file's nominal (CAD) base parameters, no friction.
dyncal::ParameterTable factory_table() {
  Eigen::Matrix<double, Robot::kNumStandard, 1> standard;
  for (int i = 0; i < Robot::kNumStandard; ++i) standard[i] = dyncal::generated::er20::kNominalStandard[i];
  Eigen::Matrix<double, Robot::kNumBase, 1> base;
  dyncal::generated::er20::standard_to_base(standard, base);
  Eigen::Matrix<double, Model::kNumParams, 1> phi = Eigen::Matrix<double, Model::kNumParams, 1>::Zero();
  phi.head<Robot::kNumBase>() = base;
  dyncal::ParameterTable t;
  dyncal::make_table<Model>(phi, t);
  return t;
}

/// One request (address, PDU, CRC) answered on the line.
void answer(const std::uint8_t* adu, std::size_t n) {
  const std::size_t pdu = g_server.answer(adu + 1, n - 3, 0, sh::clock_us(), g_reply + 1).reply_bytes;
  if (pdu == 0) return;
  g_reply[0] = adu[0];
  sh::serial_write(g_reply, dyncal::drive::append_crc16(g_reply, 1 + pdu));
}

}  // namespace

int main() {
  static_assert(Model::kNumJoints == 6, "the er20");
  g_drive.store.set_ratings(dyncal::replay::ratings());
  load_flash();
  g_drive.persist = save_flash;
  if (g_drive.load() != dyncal::TableStatus::ok) {
    static dyncal::ParameterTable factory;
    factory = factory_table();
    g_drive.activate(factory);
    sh::write("dyncal firmware drive: no valid table in the flash: the factory table is active\n");
  }
  sh::serial_start(kBaud);
  sh::write("dyncal firmware drive: ready (er20, Modbus RTU unit 1 on UART0)\n");
  std::uint8_t bytes[64];
  for (;;) {
    const std::size_t n = sh::serial_read(bytes, sizeof bytes);
    const std::uint64_t now = sh::clock_us();
    g_line.push(bytes, n, now);
    g_line.poll(now, answer);
    if (n == 0) sh::wait_for_interrupt();
  }
}
