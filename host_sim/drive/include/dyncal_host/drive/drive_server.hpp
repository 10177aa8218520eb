#pragma once
// The simulated drive's Modbus server (lib/'s drive framing and PDU server): TCP on a host/port or
// RTU on a serial device (for example one end of a socat pty pair), one register map
// (dyncal/modbus_map.hpp).

#include <atomic>
#include <string>

#include "dyncal_host/drive/simulated_drive.hpp"

namespace dyncal::host {

struct DriveServerOptions {
  std::string tcp_host = "127.0.0.1";
  int tcp_port = 1502;     ///< 0: any free port (reported in the ready line and the ready file)
  std::string rtu_device;  ///< non-empty: serve Modbus RTU on this device instead of TCP
  int rtu_baud = 115200;
  int rtu_slave = 1;       ///< the drive's unit id (RTU slave address; on TCP, 0xFF is accepted too)
  std::string ready_file;  ///< written (atomically) with the drive's URI once it serves requests
  /// TCP clients served at once. A newcomer beyond it replaces the least recently used client that
  /// neither started the trajectory nor holds a staging session (docs/reliability.md).
  int max_connections = 16;
  /// A TCP client whose frame is still incomplete after this long is disconnected [s] (a whole
  /// Modbus TCP frame is at most 260 bytes: one segment).
  double frame_timeout_s = 1.0;
  /// A TCP client that sends no complete request for this long is disconnected [s].
  double idle_timeout_s = 60.0;
  /// Communication watchdog [s]: while a trajectory plays, no complete request from the client that
  /// started it for this long stops it with fault communication_lost. 0 disables it.
  double watchdog_s = 2.0;
};

/// Serves `drive` until `stop` becomes true (checked at least every 50 ms). The simulation never
/// waits on the network: TCP sockets are non-blocking and polled (no fd_set limit), each client's
/// bytes are framed by its MBAP header and served when a frame is complete, with the limits of
/// DriveServerOptions; frames with a protocol id other than 0 or another unit id are ignored, a
/// PDU whose length contradicts its function gets exception 3 (illegal data value). In lockstep mode
/// (drive.lockstep) simulated time advances as fast as the host consumes samples; otherwise with
/// the wall clock, dropping samples (counted as overruns) when the host falls behind.
/// Prints "dyncal drive: ready <uri> pid <pid>" on stdout when it accepts requests. Throws
/// std::runtime_error when the transport cannot be opened.
void serve_drive(SimulatedDrive& drive, const DriveServerOptions& options, const std::atomic<bool>& stop);

}  // namespace dyncal::host
