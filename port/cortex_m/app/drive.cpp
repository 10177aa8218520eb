// Firmware application: a drive that serves Modbus RTU on its serial line and plays runs on a
// simulated arm — the drive image that scripts/firmware-drive runs under qemu with UART0 on a pty.
// lib/'s drive application does the work: the RTU receiver frames the requests
// (dyncal/drive/rtu_receiver.hpp: length + CRC framing, resync after a silence), the register
// server answers them (register_server.hpp: the register map, its access and state rules, the
// staging session, the commit), and the drive application (drive_application.hpp) runs the table,
// the run control, the control law and the sample ring over two ports: the flash A/B store, and
// the arm (simulated_arm.hpp: the er20 of the host simulated drive's default scenario). Runs play
// in lockstep: a control period runs only while the ring has room, between requests. The
// watchdog stops a run whose host has been silent for 2 s (communication_lost), as `dyncal drive`.
// The flash region persists in a file across restarts of qemu: read at boot, written (to a
// temporary file, then renamed) at every commit, through semihosting; the file is the second word
// of the command line (qemu -semihosting-config ...,arg=drive.elf,arg=FILE), none: the flash starts
// erased. Without a valid table in the flash the factory table is active: the robot file's nominal
// base parameters, no friction (as the simulated drive's). Prints "dyncal firmware drive: ready" on
// the semihosting console once it serves. Scalar: DYNCAL_FW_SCALAR (float on the M4F, double on
// the M7).
#include <cstdint>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/rtu_receiver.hpp"
#include "dyncal/inertial_parameters.hpp"
#include "dyncal_cortex_m/flash_parameter_store.hpp"
#include "dyncal_cortex_m/semihosting.hpp"
#include "dyncal_cortex_m/serial_mps2.hpp"
#include "dyncal_cortex_m/stack_usage.hpp"
#include "er20_drive.hpp"

#ifndef DYNCAL_FW_SCALAR
#define DYNCAL_FW_SCALAR float
#endif

extern "C" std::uint8_t __param_store_start[];
extern "C" std::uint8_t __param_store_end[];

namespace {

namespace sh = dyncal::cortex_m;
namespace data = dyncal::replay::data;
using Scalar = DYNCAL_FW_SCALAR;
using Robot = dyncal::replay::Er20;
using Models = dyncal::replay::DriveModels;
/// Samples the ring holds (88 bytes each): a run of 2 periods of 10 s at 100 Hz whole.
constexpr std::size_t kRingSamples = 2048;
using Application = dyncal::replay::Er20Drive<Scalar, kRingSamples>;

/// The RTU line: 115 200 baud 8N1, unit 1; a frame that cannot be taken is dropped until the line
/// has been silent for 50 ms (under qemu the gaps inside one frame reach several ms; real
/// hardware would use t3.5, drive::rtu_silence_us).
constexpr std::uint32_t kBaud = 115200;
constexpr std::uint8_t kUnit = 1;
constexpr std::uint64_t kResyncUs = 50000;
/// The watchdog: a playing run stops when the host that started it is silent this long.
constexpr std::uint64_t kWatchdogUs = 2000000;

char g_flash_file[200] = {};

int region_size() {
  return static_cast<int>(__param_store_end - __param_store_start);
}

/// The flash A/B store whose region is saved to its file after every write (atomically: the old
/// file stays when saving fails, and the commit then reports store_failed).
struct PersistedStore final : dyncal::port::ParameterStore {
  sh::FlashParameterStore<Models>& flash = sh::flash_parameter_store<Models>();
  dyncal::port::PortStatus write(const dyncal::ParameterTable& t, dyncal::TableStatus* reason) noexcept override {
    const dyncal::port::PortStatus st = flash.write(t, reason);
    if (st != dyncal::port::PortStatus::ok || g_flash_file[0] == 0) return st;
    if (sh::write_file_atomically(g_flash_file, __param_store_start, region_size())) return st;
    sh::write("dyncal firmware drive: cannot write the flash file ");
    sh::write(g_flash_file);
    sh::write("\n");
    if (reason) *reason = dyncal::TableStatus::store_failed;
    return dyncal::port::PortStatus::transport_error;
  }
  dyncal::port::PortStatus read(dyncal::ParameterTable& t, dyncal::TableStatus* reason) noexcept override {
    return flash.read(t, reason);
  }
};

dyncal::replay::SimulatedArm<Robot, Scalar> g_arm{dyncal::replay::arm_physics(2026)};
PersistedStore g_store;
Application g_drive{g_store, g_arm, dyncal::replay::drive_settings<Application>()};
dyncal::drive::RegisterServer<Application> g_server{g_drive, data::kControlRateHz};
dyncal::drive::RtuReceiver<> g_line{kUnit, kResyncUs};
std::uint8_t g_reply[dyncal::drive::kMaxRtuAduBytes];

/// A decimal number at text[i] ([sign] digits [. digits] [e [sign] digits]), i moved past it;
/// false when there is none. (newlib's strtod allocates.)
bool parse_number(const char* text, int& i, double& value) {
  double sign = 1, mantissa = 0, scale = 1;
  if (text[i] == '-' || text[i] == '+') sign = text[i++] == '-' ? -1 : 1;
  const int first = i;
  while (text[i] >= '0' && text[i] <= '9') mantissa = 10 * mantissa + (text[i++] - '0');
  if (text[i] == '.') {
    ++i;
    while (text[i] >= '0' && text[i] <= '9') {
      mantissa = 10 * mantissa + (text[i++] - '0');
      scale *= 10;
    }
  }
  if (i == first || (i == first + 1 && text[first] == '.')) return false;
  int exponent = 0, exponent_sign = 1;
  if (text[i] == 'e' || text[i] == 'E') {
    ++i;
    if (text[i] == '-' || text[i] == '+') exponent_sign = text[i++] == '-' ? -1 : 1;
    if (!(text[i] >= '0' && text[i] <= '9')) return false;
    while (text[i] >= '0' && text[i] <= '9' && exponent < 300) exponent = 10 * exponent + (text[i++] - '0');
  }
  value = sign * mantissa / scale;
  for (int k = 0; k < exponent; ++k) value = exponent_sign > 0 ? value * 10 : value / 10;
  return true;
}

/// The arm's standard parameters with a point mass M [kg] at c [m] on the last link (its frame).
double g_loaded_standard[Robot::kNumStandard];
void load_the_arm(const double load[4]) {
  const double com[3] = {load[1], load[2], load[3]}, point_mass[6] = {};
  for (int i = 0; i < Robot::kNumStandard; ++i) g_loaded_standard[i] = dyncal::generated::er20::kNominalStandard[i];
  dyncal::add_rigid_load(g_loaded_standard + Robot::kNumStandard - 10, load[0], com, point_mass);
  g_arm.set_standard(g_loaded_standard);
}

/// The command line: the image's name, the flash file (read into the region; erased, 0xFF, where
/// it gives nothing), and optionally payload=M,CX,CY,CZ (a load on the simulated arm). False when
/// the line cannot be read as that.
bool read_command_line() {
  for (int i = 0; i < region_size(); ++i) __param_store_start[i] = 0xFF;
  static char line[256];
  if (!sh::command_line(line, sizeof line)) return true;
  int i = 0;
  while (line[i] != 0 && line[i] != ' ') ++i;  // the image's name
  while (line[i] == ' ') ++i;
  int n = 0;
  while (line[i] != 0 && line[i] != ' ' && n + 1 < static_cast<int>(sizeof g_flash_file)) g_flash_file[n++] = line[i++];
  g_flash_file[n] = 0;
  if (n > 0) {
    const int read = sh::read_file(g_flash_file, __param_store_start, region_size());
    if (read >= 0 && read < region_size())
      for (int k = read; k < region_size(); ++k) __param_store_start[k] = 0xFF;
  }
  while (line[i] == ' ') ++i;
  if (line[i] == 0) return true;
  const char* kPayload = "payload=";
  for (int k = 0; kPayload[k] != 0; ++k, ++i)
    if (line[i] != kPayload[k]) return false;
  double load[4];
  for (int k = 0; k < 4; ++k) {
    if (!parse_number(line, i, load[k])) return false;
    if (k < 3 && line[i++] != ',') return false;
  }
  if (line[i] != 0 && line[i] != ' ') return false;
  if (!(load[0] >= 0)) return false;
  load_the_arm(load);
  sh::write("dyncal firmware drive: the simulated arm carries a load of ");
  sh::write_float(load[0], 4);
  sh::write(" kg on its last link\n");
  return true;
}

/// One request (address, PDU, CRC) answered on the line.
void answer(const std::uint8_t* adu, std::size_t n) {
  const std::size_t pdu = g_server.answer(adu + 1, n - 3, 0, sh::clock_us(), g_reply + 1).reply_bytes;
  if (pdu == 0) return;
  g_reply[0] = adu[0];
  sh::serial_write(g_reply, dyncal::drive::append_crc16(g_reply, 1 + pdu));
}

/// A playing run whose host has been silent for kWatchdogUs stops (communication_lost).
void watch_communication(std::uint64_t now) {
  if (g_drive.state() != dyncal::modbus_map::DriveState::playing) return;
  const std::uint64_t last = g_server.owner_last_request();
  if (now <= last || now - last <= kWatchdogUs) return;
  g_drive.trip(dyncal::modbus_map::DriveFault::communication_lost, 0, static_cast<double>(now - last) * 1e-6);
  sh::write("dyncal firmware drive: the host that started the run is silent: stopped (communication lost)\n");
}

/// At a run's end (finished or fault), its samples and the deepest stack so far on the console.
void report_run_end() {
  static dyncal::modbus_map::DriveState last = dyncal::modbus_map::DriveState::idle;
  const dyncal::modbus_map::DriveState now = g_drive.state();
  if (now == last) return;
  last = now;
  if (now != dyncal::modbus_map::DriveState::finished && now != dyncal::modbus_map::DriveState::fault) return;
  sh::write(now == dyncal::modbus_map::DriveState::fault ? "dyncal firmware drive: run tripped after "
                                                         : "dyncal firmware drive: run finished after ");
  sh::write_int(g_drive.produced());
  sh::write(" samples; peak stack ");
  sh::write_int(sh::StackUsage::peak_bytes());
  sh::write(" of ");
  sh::write_int(sh::StackUsage::reserved_bytes());
  sh::write(" bytes\n");
}

}  // namespace

int main() {
  sh::StackUsage::paint();
  // The store checks each table against the models; the application has checked it against the ratings too.
  if (!read_command_line()) {
    sh::write("dyncal firmware drive: command line: FLASH_FILE [payload=M,CX,CY,CZ]\n");
    return 2;
  }
  if (g_drive.load() != dyncal::TableStatus::ok) {
    static dyncal::ParameterTable factory;
    factory = dyncal::replay::factory_table();
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
    watch_communication(now);
    report_run_end();
    if (g_drive.wants_period()) {
      g_drive.period();  // one period, then the line again: a request waits at most one period
      continue;
    }
    if (n == 0) sh::wait_for_interrupt();
  }
}
