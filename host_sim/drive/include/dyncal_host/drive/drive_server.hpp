#pragma once
// The simulated drive's Modbus server (libmodbus): TCP on a host/port or RTU on a serial device
// (for example one end of a socat pty pair), one register map (dyncal/modbus_map.hpp).

#include <atomic>
#include <string>

#include "dyncal_host/drive/simulated_drive.hpp"

namespace dyncal::host {

struct DriveServerOptions {
  std::string tcp_host = "127.0.0.1";
  int tcp_port = 1502;     ///< 0: any free port (reported in the ready line and the ready file)
  std::string rtu_device;  ///< non-empty: serve Modbus RTU on this device instead of TCP
  int rtu_baud = 115200;
  int rtu_slave = 1;
  std::string ready_file;  ///< written (atomically) with the drive's URI once it serves requests
};

/// Serves `drive` until `stop` becomes true (checked at least every 50 ms). In lockstep mode
/// (drive.lockstep) simulated time advances as fast as the host consumes samples; otherwise with
/// the wall clock, dropping samples (counted as overruns) when the host falls behind.
/// Prints "dyncal drive: ready <uri> pid <pid>" on stdout when it accepts requests. Throws
/// std::runtime_error when the transport cannot be opened.
void serve_drive(SimulatedDrive& drive, const DriveServerOptions& options, const std::atomic<bool>& stop);

}  // namespace dyncal::host
