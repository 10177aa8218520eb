#pragma once
// The simulated drive's Modbus request handler without its transport: the register map
// (dyncal/modbus_map.hpp), the access and state rules and the staging session (docs/modbus.md
// "Access and states"), served by lib/'s PDU server and framing (dyncal/drive/modbus_pdu_server.hpp,
// modbus_frames.hpp: the drive application's, no libmodbus in the replies). The server
// (drive_server.cpp) receives the bytes and hands over what a client sent; the fuzz target
// tests/fuzz/fuzz_modbus_request.cpp hands over any bytes at all.

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "dyncal_host/drive/simulated_drive.hpp"

namespace dyncal::host {

/// `s` seconds as a steady-clock duration (the drive's time-outs and session length are in seconds).
inline std::chrono::steady_clock::duration seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
}

class ModbusRequestHandler {
 public:
  using Clock = std::chrono::steady_clock;
  /// The client id of the RTU line (one point-to-point client); TCP clients are their sockets.
  static constexpr int kRtuClient = -2;

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
  /// answers it, applying a write that passes the access and state rules (else the Modbus
  /// exception they give). False when the reply could not be sent in full.
  bool answer(const std::uint8_t* adu, int length, int client);

  /// `client`'s connection closed: a session it held ends and it no longer owns the trajectory (its
  /// id may be reused by a new client). The watchdog still counts the owner's silence from its last
  /// request: a host that died mid-run trips it.
  void client_closed(int client);

  /// The last complete request of the client that started the trajectory (the owner; the time of
  /// the start if it has sent nothing since). The watchdog watches this client only: another
  /// client's polling says nothing about the host that commands the run.
  Clock::time_point owner_last_request() const { return owner_last_request_; }
  /// `client` must not be disconnected to make room for a newcomer: it owns the trajectory, or
  /// holds an open staging session.
  bool holds_a_role(int client) const;
  /// When the last start command was applied (real-time mode follows the wall clock from there).
  Clock::time_point started() const { return started_; }

 private:
  struct Bank;  ///< the registers as lib/'s PDU server reads and writes them
  friend struct Bank;
  void apply_write(int address, int count);
  bool session_open() const;
  bool session_held_by_another() const;

  static constexpr int kNoClient = -1;
  SimulatedDrive& drive_;
  int rtu_fd_;
  int unit_id_;
  std::FILE* log_;
  std::array<std::uint16_t, dyncal::modbus_map::kHoldingWords> holding_{};  ///< the holding registers
  std::array<std::uint16_t, dyncal::modbus_map::kInputWords> input_{};      ///< the input registers
  int current_client_ = kNoClient;  ///< the client whose request is being answered
  int session_client_ = kNoClient;  ///< the client holding the staging session
  int owner_client_ = kNoClient;    ///< the client that started the trajectory (while connected)
  Clock::time_point session_until_ = Clock::now();
  Clock::time_point owner_last_request_ = Clock::now();
  Clock::time_point started_ = Clock::now();
  long table_generation_ = -1;  ///< the drive's table generation last copied into the registers
};

}  // namespace dyncal::host
