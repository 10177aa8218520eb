#include "modbus_request_handler.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>

#include "dyncal/drive/modbus_frames.hpp"

namespace dyncal::host {
namespace {

namespace mm = dyncal::modbus_map;
using drive::kMaxTcpAduBytes;
using drive::kMbapHeaderBytes;
using drive::MbapFrame;
using drive::next_mbap_frame;

}  // namespace

bool DriveRegisters::start(mm::Command c, const drive::RunSettings& run, const drive::MonitorSettings& monitor) {
  // The register server applied the same rule (check_monitor_settings) before the reply, so a
  // refusal here means the drive's state changed in between: the run does not start, the log says why.
  if (d_.start(c, run, monitor)) return true;
  if (log_) {
    std::fprintf(log_, "dyncal drive: run not started: collision monitor: %s\n",
                 monitor_settings_error(monitor, d_.control_period()).c_str());
    std::fflush(log_);
  }
  return false;
}

TableStatus DriveRegisters::commit(const std::uint8_t* bytes, int size) {
  const TableStatus st = d_.commit(bytes, size);
  if (log_) {
    if (st == TableStatus::store_failed && !d_.store_error().empty())
      std::fprintf(log_, "dyncal drive: flash write failed: %s\n", d_.store_error().c_str());
    std::fprintf(log_, "dyncal drive: commit %s\n", to_string(st));
    std::fflush(log_);
  }
  return st;
}

ModbusRequestHandler::ModbusRequestHandler(SimulatedDrive& drive, int rtu_fd, int unit_id, std::FILE* log)
    : drive_(drive, log), server_(drive_, drive.sample_rate_hz), rtu_fd_(rtu_fd), unit_id_(unit_id) {}

ModbusRequestHandler::TcpResult ModbusRequestHandler::serve_tcp(const std::uint8_t* bytes, std::size_t size,
                                                                int client) {
  TcpResult r;
  for (;;) {
    const MbapFrame f = next_mbap_frame(bytes + r.used, size - r.used);
    if (f.status == MbapFrame::Status::invalid) {
      r.keep = false;
      return r;
    }
    if (f.status == MbapFrame::Status::incomplete) return r;
    std::uint8_t frame[kMaxTcpAduBytes + 8] = {};  // zero beyond the frame: a short PDU reads zeros
    std::memcpy(frame, bytes + r.used, f.bytes);
    r.used += f.bytes;
    ++r.frames;
    // Protocol id 0 is Modbus; the unit id is 0xFF (the spec's value for a server addressed by its
    // IP address) or the drive's unit id. Other frames are not for this drive: ignored.
    if (f.protocol != 0 || (f.unit != 0xFF && f.unit != unit_id_)) continue;
    if (!answer(frame, static_cast<int>(f.bytes), client)) {
      r.keep = false;
      return r;
    }
  }
}

void ModbusRequestHandler::client_closed(int client) {
  server_.client_closed(client);
}

bool ModbusRequestHandler::answer(const std::uint8_t* adu, int length, int client) {
  // The PDU: after the MBAP header on TCP; after the address and before the CRC on RTU.
  const bool rtu = client == kRtuClient;
  const std::size_t header = rtu ? 1 : kMbapHeaderBytes, trailer = rtu ? 2 : 0;
  if (length < 0 || static_cast<std::size_t>(length) < header + trailer + 1) return true;  // nothing to answer
  std::uint8_t reply[kMbapHeaderBytes + drive::kMaxPduBytes + 2];
  const std::size_t pdu = server_
                              .answer(adu + header, static_cast<std::size_t>(length) - header - trailer, client,
                                      microseconds(Clock::now()), reply + header)
                              .reply_bytes;
  if (rtu) {  // the address, the PDU, the CRC low byte first (MODBUS over Serial Line v1.02, sec. 2.5.1)
    reply[0] = adu[0];
    const std::size_t n = drive::append_crc16(reply, 1 + pdu);
    return ::write(rtu_fd_, reply, n) == static_cast<ssize_t>(n);
  }
  // MBAP: the request's transaction id, protocol 0, the length of unit id + PDU, its unit id.
  reply[0] = adu[0];
  reply[1] = adu[1];
  reply[2] = 0;
  reply[3] = 0;
  reply[4] = static_cast<std::uint8_t>((pdu + 1) >> 8);
  reply[5] = static_cast<std::uint8_t>((pdu + 1) & 0xFF);
  reply[6] = adu[6];
  const std::size_t n = kMbapHeaderBytes + pdu;
  return ::send(client, reply, n, MSG_NOSIGNAL) == static_cast<ssize_t>(n);
}

}  // namespace dyncal::host
