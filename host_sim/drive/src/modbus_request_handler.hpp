#pragma once
// The simulated drive's Modbus request handler without its transport: lib/'s drive application
// serves the requests (dyncal/drive/register_server.hpp: the register map, the access and state
// rules, the staging session; framed by dyncal/drive/modbus_frames.hpp), over the simulated drive
// (SimulatedDrive, through the adapter below). The server (drive_server.cpp) receives the bytes and
// hands over what a client sent; the fuzz target tests/fuzz/fuzz_modbus_request.cpp hands over any
// bytes at all.

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "dyncal/drive/register_server.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"

namespace dyncal::host {

/// `s` seconds as a steady-clock duration (the drive's time-outs and session length are in seconds).
inline std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

/// The simulated drive as lib/'s register server sees it (register_server.hpp's Drive): lib/'s
/// drive application, whose commit's store failure is logged with its reason.
class DriveRegisters {
 public:
  DriveRegisters(SimulatedDrive& drive, std::FILE* log) : d_(drive), log_(log) {}
  modbus_map::DriveState state() const { return d_.state(); }
  std::uint32_t acked() const { return d_.acked(); }
  std::uint32_t produced() const { return d_.produced(); }
  long ring_capacity_samples() const { return d_.ring_capacity(); }
  long run_samples(double periods, double period_s, double fs) const { return d_.run_samples(periods, period_s, fs); }
  double control_rate_hz() const { return d_.control_rate_hz(); }
  void ack(std::uint32_t seq_end) { d_.ack(seq_end); }
  bool start(modbus_map::Command c, const drive::RunSettings& run, const drive::MonitorSettings& monitor);
  void stop() { d_.stop(); }
  void reset() { d_.reset(); }
  TableStatus commit(const std::uint8_t* bytes, int size);
  void publish_inputs(std::uint16_t* input) const { d_.publish_inputs(input); }
  void publish_window(std::uint16_t* window) const { d_.publish_window(window); }

 private:
  SimulatedDrive& d_;
  std::FILE* log_;
};

class ModbusRequestHandler {
 public:
  using Clock = std::chrono::steady_clock;
  /// The client id of the RTU line (one point-to-point client); TCP clients are their sockets.
  static constexpr int kRtuClient = -2;
  static_assert(kRtuClient != drive::RegisterServer<DriveRegisters>::kNoClient, "the RTU line is a client");

  /// `rtu_fd`: the RTU serial line the replies are written to (-1 on TCP, where each client's
  /// socket is), owned by the caller; `unit_id`: the drive's unit id (RTU slave address; on TCP 0xFF
  /// is accepted too);
  /// `log`: where commits are reported (nullptr: nowhere).
  ModbusRequestHandler(SimulatedDrive& drive, int rtu_fd, int unit_id, std::FILE* log = stdout);
  ModbusRequestHandler(const ModbusRequestHandler&) = delete;
  ModbusRequestHandler& operator=(const ModbusRequestHandler&) = delete;

  /// What serve_tcp did with a client's bytes.
  struct TcpResult {
    std::size_t used = 0;  ///< bytes of the complete frames consumed; the rest starts a partial frame
    int frames = 0;        ///< complete frames among them (answered or ignored)
    bool keep = true;      ///< false: framing lost or a reply not sent in full: close the connection
  };
  /// Answers every complete Modbus TCP frame at the start of bytes[0, size) sent by `client` (a
  /// socket: the replies go to it). A frame with a protocol id other than 0 or another unit id is
  /// ignored; the others are answered by answer().
  TcpResult serve_tcp(const std::uint8_t* bytes, std::size_t size, int client);

  /// Answers one complete request ADU of `length` bytes from `client`: MBAP header and PDU on TCP,
  /// address, PDU and CRC on RTU (client kRtuClient, the CRC already checked). lib/'s serve_pdu
  /// answers it through lib/'s register server (a write that passes the access and state rules is
  /// applied, else the Modbus exception they give). False when the reply could not be sent in full.
  bool answer(const std::uint8_t* adu, int length, int client);

  /// `client`'s connection closed: a session it held ends and it no longer owns the trajectory (its
  /// id may be reused by a new client). The watchdog still counts the owner's silence from its last
  /// request: a host that died mid-run trips it.
  void client_closed(int client);

  /// The last complete request of the client that started the trajectory (the owner; the time of
  /// the start if it has sent nothing since). The watchdog watches this client only: another
  /// client's polling says nothing about the host that commands the run.
  Clock::time_point owner_last_request() const { return at(server_.owner_last_request()); }
  /// `client` must not be disconnected to make room for a newcomer: it owns the trajectory, or
  /// holds an open staging session.
  bool holds_a_role(int client) const { return server_.holds_a_role(client, microseconds(Clock::now())); }
  /// When the last start command was applied (real-time mode follows the wall clock from there).
  Clock::time_point started() const { return at(server_.started()); }

 private:
  /// The server's clock: microseconds since the handler was made.
  drive::Microseconds microseconds(Clock::time_point t) const {
    return static_cast<drive::Microseconds>(std::chrono::duration_cast<std::chrono::microseconds>(t - epoch_).count());
  }
  Clock::time_point at(drive::Microseconds us) const { return epoch_ + std::chrono::microseconds(us); }

  Clock::time_point epoch_ = Clock::now();
  DriveRegisters drive_;
  drive::RegisterServer<DriveRegisters> server_;
  int rtu_fd_;
  int unit_id_;
};

}  // namespace dyncal::host
