#include "modbus_request_handler.hpp"

#include <sys/socket.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <exception>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/ring_window.hpp"

namespace dyncal::host {
namespace {

namespace mm = dyncal::modbus_map;
using drive::kMaxTcpAduBytes;
using drive::kMbapHeaderBytes;
using drive::MbapFrame;
using drive::next_mbap_frame;

}  // namespace

void DriveRegisters::publish_inputs(std::uint16_t* in) const {
  const SimulatedDrive& d = d_;
  long& table_generation = table_generation_;
  in[mm::kMapVersionReg] = mm::kMapVersion;
  const int n_joints = d.num_joints();
  in[mm::kNumJointsReg] = static_cast<std::uint16_t>(n_joints);
  mm::set_u32(in + mm::kRobotIdReg, d.robot_id());
  mm::set_u32(in + mm::kActiveModelIdReg, d.active_table().model_id);
  in[mm::kActiveCountReg] = d.active_table().count;
  in[mm::kStateReg] = static_cast<std::uint16_t>(d.state());
  mm::set_f32(in + mm::kSimTimeReg, static_cast<float>(d.time()));
  mm::set_u32(in + mm::kProducedReg, d.produced());
  mm::set_u32(in + mm::kOverrunReg, d.overruns());
  const auto err = d.model_error_rms();
  for (int j = 0; j < n_joints; ++j) mm::set_f32(in + mm::kModelErrorReg + 2 * j, static_cast<float>(err[j]));
  in[mm::kFaultReg] = static_cast<std::uint16_t>(d.fault());
  in[mm::kFaultJointReg] = static_cast<std::uint16_t>(d.fault_joint());
  mm::set_f32(in + mm::kFaultValueReg, static_cast<float>(d.fault_value()));
  // The control law of the run started last: what IDIM-IV simulates (identify --method iv --law).
  mm::set_f32(in + mm::kControlRateReg, static_cast<float>(d.control_rate_hz()));
  const JointArray kp = d.kp(), kd = d.kd();
  for (int j = 0; j < n_joints; ++j) {
    mm::set_f32(in + mm::kGainKpReg + 2 * j, static_cast<float>(kp[j]));
    mm::set_f32(in + mm::kGainKdReg + 2 * j, static_cast<float>(kd[j]));
  }
  in[mm::kPayloadStateReg] = static_cast<std::uint16_t>(d.payload_state());
  in[mm::kMonitorStateReg] = static_cast<std::uint16_t>(d.monitor_state());
  for (int i = 0; i < 10; ++i) {
    mm::set_f32(in + mm::kPayloadReg + 2 * i, static_cast<float>(d.payload().value[i]));
    mm::set_f32(in + mm::kPayloadStdReg + 2 * i, static_cast<float>(d.payload().std[i]));
  }
  // The table registers change only with the table: copy them when it changed.
  if (table_generation != static_cast<long>(d.table_generation())) {
    const auto& bytes = d.active_table_bytes();
    mm::set_u32(in + mm::kActiveCrcReg, dyncal::detail::get_u32(bytes.data() + bytes.size() - 4));
    in[mm::kActiveTableSizeReg] = static_cast<std::uint16_t>(bytes.size());
    std::memset(in + mm::kActiveTableReg, 0, 2 * mm::kTableWords);
    mm::bytes_to_regs(bytes.data(), static_cast<int>(bytes.size()), in + mm::kActiveTableReg);
    table_generation = static_cast<long>(d.table_generation());
  }
  in[mm::kRingFormatReg] = static_cast<std::uint16_t>(d.ring_format_in_use());
  mm::set_u32(in + mm::kRingCapacityReg, static_cast<std::uint32_t>(d.ring_capacity));
  for (int j = 0; j < n_joints; ++j) {
    mm::set_f32(in + mm::kQResolutionReg + 2 * j, static_cast<float>(d.q_resolution(j)));
    mm::set_f32(in + mm::kTauResolutionReg + 2 * j, static_cast<float>(d.tau_resolution(j)));
  }
}

void DriveRegisters::publish_window(std::uint16_t* window) const {
  const int n_joints = d_.num_joints();
  drive::RingResolution res;
  for (int j = 0; j < n_joints; ++j) {
    res.q[j] = static_cast<float>(d_.q_resolution(j));
    res.tau[j] = static_cast<float>(d_.tau_resolution(j));
  }
  drive::RingWindowHeader header;
  header.state = d_.state();
  header.produced = d_.produced();
  header.overruns = d_.overruns();
  drive::encode_ring_window(d_.ring(), d_.ring().size(), header, n_joints, d_.ring_format_in_use(), res, window);
}

bool DriveRegisters::start(mm::Command c, const drive::RunSettings& run, const drive::MonitorSettings& monitor) {
  d_.sample_rate_hz = run.sample_rate_hz;
  d_.periods = run.periods;
  d_.trajectory = run.trajectory;
  // The register server applied the same rule (check_monitor_settings) before the reply, so a
  // refusal here means the drive's state changed in between: the run does not start, the log says why.
  if (const std::string why = d_.set_monitor(monitor); !why.empty()) {
    if (log_) std::fprintf(log_, "dyncal drive: run not started: collision monitor: %s\n", why.c_str());
    return false;
  }
  if (c == mm::Command::identify_payload)
    d_.start_payload();
  else
    d_.start();
  return true;
}

TableStatus DriveRegisters::commit(const std::uint8_t* bytes, int size) {
  TableStatus st;
  try {
    st = d_.commit(bytes, size);
  } catch (const std::exception& e) {
    if (log_) std::fprintf(log_, "dyncal drive: flash write failed: %s\n", e.what());
    st = TableStatus::store_failed;  // the store's own failure, not the table's (the active one stays)
  }
  if (log_) {
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
