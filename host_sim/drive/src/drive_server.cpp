#include "dyncal_host/drive/drive_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "mbap_frame.hpp"

namespace dyncal::host {
namespace {

namespace mm = dyncal::modbus_map;
using Clock = std::chrono::steady_clock;

std::uint16_t be16(const std::uint8_t* p) {
  return static_cast<std::uint16_t>((p[0] << 8) | p[1]);
}

/// Copies the drive's state into the input registers (the ring window starts at the ack).
/// `table_generation`: the drive's table generation last copied into the registers (-1: none yet).
void refresh_inputs(const SimulatedDrive& d, std::uint16_t* in, long& table_generation) {
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
  // The table registers change only with the table: copy them when it changed.
  if (table_generation != static_cast<long>(d.table_generation())) {
    const auto& bytes = d.active_table_bytes();
    mm::set_u32(in + mm::kActiveCrcReg, dyncal::detail::get_u32(bytes.data() + bytes.size() - 4));
    in[mm::kActiveTableSizeReg] = static_cast<std::uint16_t>(bytes.size());
    std::memset(in + mm::kActiveTableReg, 0, 2 * mm::kTableWords);
    mm::bytes_to_regs(bytes.data(), static_cast<int>(bytes.size()), in + mm::kActiveTableReg);
    table_generation = static_cast<long>(d.table_generation());
  }
  // Ring window: the oldest unacknowledged samples.
  std::uint16_t* w = in + mm::kRingReg;
  const auto& ring = d.ring();
  const int n = std::min<int>(mm::samples_per_block(n_joints), static_cast<int>(ring.size()));
  mm::set_u32(w, ring.empty() ? d.produced() : ring.front().seq);
  w[2] = static_cast<std::uint16_t>(n);
  std::uint16_t* p = w + 3;
  for (int k = 0; k < n; ++k) {
    const port::DriveSample& s = ring[static_cast<size_t>(k)];
    mm::set_u32(p, s.seq);
    for (int j = 0; j < n_joints; ++j) {
      mm::set_f32(p + 2 + 2 * j, s.q[j]);
      mm::set_f32(p + 2 + 2 * (n_joints + j), s.qd[j]);
      mm::set_f32(p + 2 + 2 * (2 * n_joints + j), s.tau[j]);
    }
    p += mm::sample_words(n_joints);
  }
}

/// Every register of [address, address + count) lies in a field of `bank`.
bool addresses_defined(mm::Bank bank, int address, int count) {
  for (int a = address; a < address + count; ++a) {
    if (!mm::find_field(bank, a)) return false;
  }
  return true;
}

/// A write may not split a u32/f32 element.
bool splits_element(int address, int count) {
  for (int edge : {address, address + count}) {
    const mm::Field* f = mm::find_field(mm::Bank::holding, edge);
    if (f && edge != f->address && (f->type == mm::Type::u32 || f->type == mm::Type::f32) &&
        (edge - f->address) % 2 != 0) {
      return true;
    }
  }
  return false;
}

bool overlaps(int address, int count, std::uint16_t reg, int words) {
  return address < reg + words && reg < address + count;
}

/// Checks the holding registers after a write (applied to a scratch copy) against the access and
/// state rules (docs/modbus.md "Access and states"). `session`: the writing connection holds an
/// open staging session. Returns a Modbus exception code or 0.
int check_holding(const SimulatedDrive& d, const std::uint16_t* h, int address, int count, double control_rate,
                  bool session) {
  const bool playing = d.state() == mm::DriveState::playing;
  const bool fault = d.state() == mm::DriveState::fault;
  // Staging and committing: only in a session, only while no trajectory plays and no fault stands.
  auto staging_rule = [&]() -> int {
    if (!session) return MODBUS_EXCEPTION_ILLEGAL_FUNCTION;  // locked: the server is in the wrong state for it
    if (playing) return MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY;
    if (fault) return MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE;
    return 0;
  };
  if (overlaps(address, count, mm::kCommandReg, 1)) {
    const std::uint16_t c = h[mm::kCommandReg];
    if (c > static_cast<std::uint16_t>(mm::Command::reset)) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
    if (c == static_cast<std::uint16_t>(mm::Command::commit_table)) {
      if (const int e = staging_rule()) return e;
    }
    if (c == static_cast<std::uint16_t>(mm::Command::start)) {
      if (playing) return MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY;   // would jump the arm back to the start pose
      if (fault) return MODBUS_EXCEPTION_SLAVE_OR_SERVER_FAILURE;  // only reset clears a fault
      if (!(mm::run_samples(h[mm::kPeriodsReg], mm::get_f32(h + mm::kOmegaFReg), mm::get_f32(h + mm::kSampleRateReg)) <=
            mm::kMaxRunSamples))
        return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;  // the run would outlast the sample counter's resolution
    }
  }
  if (overlaps(address, count, mm::kUnlockReg, 1) && h[mm::kUnlockReg] != mm::kUnlockKey)
    return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  if (overlaps(address, count, mm::kStagingSizeReg, mm::kHoldingWords - mm::kStagingSizeReg)) {
    if (const int e = staging_rule()) return e;
  }
  if (overlaps(address, count, mm::kAckReg, 2)) {
    const std::uint32_t a = mm::get_u32(h + mm::kAckReg);
    if (a < d.acked() || a > d.produced()) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  const bool settings =
      overlaps(address, count, mm::kSampleRateReg, mm::kCoefficientsReg + mm::kCoefficientWords - mm::kSampleRateReg);
  if (settings && playing) return MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY;
  if (overlaps(address, count, mm::kSampleRateReg, 2)) {
    const double fs = mm::get_f32(h + mm::kSampleRateReg);
    const double ratio = control_rate / fs;
    if (!(fs >= mm::kMinSampleRateHz && fs <= mm::kMaxSampleRateHz) || std::fabs(ratio - std::round(ratio)) > 1e-6)
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  if (overlaps(address, count, mm::kOmegaFReg, 2)) {
    const double f = mm::get_f32(h + mm::kOmegaFReg);
    if (!(f > 0 && f <= mm::kMaxFundamentalHz)) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  if (overlaps(address, count, mm::kHarmonicsReg, 1)) {
    if (h[mm::kHarmonicsReg] < 1 || h[mm::kHarmonicsReg] > mm::kMaxHarmonics)
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  if (overlaps(address, count, mm::kPeriodsReg, 1)) {
    if (h[mm::kPeriodsReg] < 1 || h[mm::kPeriodsReg] > mm::kMaxPeriods) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  for (int k = 0; k < mm::kCoefficientWords; k += 2) {
    if (overlaps(address, count, static_cast<std::uint16_t>(mm::kCoefficientsReg + k), 2) &&
        !std::isfinite(mm::get_f32(h + mm::kCoefficientsReg + k))) {
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
    }
  }
  if (overlaps(address, count, mm::kStagingSizeReg, 1) && h[mm::kStagingSizeReg] > kTableMaxBytes) {
    return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  return 0;
}

void load_trajectory(SimulatedDrive& d, const std::uint16_t* h) {
  d.sample_rate_hz = mm::get_f32(h + mm::kSampleRateReg);
  d.trajectory.f_f = mm::get_f32(h + mm::kOmegaFReg);
  d.trajectory.harmonics = h[mm::kHarmonicsReg];
  d.periods = h[mm::kPeriodsReg];
  for (int j = 0; j < mm::kMaxJoints; ++j) {  // every slot; the drive plays its robot's joints
    const std::uint16_t* c = h + mm::kCoefficientsReg + 2 * mm::kCoefficientsPerJoint * j;
    d.trajectory.q0[j] = mm::get_f32(c);
    for (int l = 0; l < mm::kMaxHarmonics; ++l) {
      d.trajectory.a(j, l) = mm::get_f32(c + 2 + 2 * l);
      d.trajectory.b(j, l) = mm::get_f32(c + 2 + 2 * mm::kMaxHarmonics + 2 * l);
    }
  }
}

class Server {
 public:
  Server(SimulatedDrive& drive, const DriveServerOptions& o) : drive_(drive), options_(o) {
    map_ = modbus_mapping_new_start_address(0, 0, 0, 0, 0, mm::kHoldingWords, 0, mm::kInputWords);
    if (!map_) throw std::runtime_error("cannot allocate the Modbus register map");
    // Defaults: the survey's excitation settings (Eq. 27: L = 5, f_f = 0.1 Hz), 2 periods.
    mm::set_f32(map_->tab_registers + mm::kSampleRateReg, static_cast<float>(drive.sample_rate_hz));
    mm::set_f32(map_->tab_registers + mm::kOmegaFReg, 0.1f);
    map_->tab_registers[mm::kHarmonicsReg] = 5;
    map_->tab_registers[mm::kPeriodsReg] = 2;
  }
  ~Server() {
    for (const auto& c : clients_) ::close(c.fd);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    if (ctx_) {
      if (!options_.rtu_device.empty()) modbus_close(ctx_);
      modbus_free(ctx_);
    }
    modbus_mapping_free(map_);
  }

  std::string open() {
    if (!options_.rtu_device.empty()) {
      ctx_ = modbus_new_rtu(options_.rtu_device.c_str(), options_.rtu_baud, 'N', 8, 1);
      if (!ctx_ || modbus_set_slave(ctx_, options_.rtu_slave) != 0 || modbus_connect(ctx_) != 0) {
        throw std::runtime_error("cannot open RTU device " + options_.rtu_device + ": " + modbus_strerror(errno));
      }
      return "rtu:" + options_.rtu_device;
    }
    ctx_ = modbus_new_tcp(options_.tcp_host.c_str(), options_.tcp_port);
    if (!ctx_) throw std::runtime_error("cannot create a Modbus TCP context");
    listen_fd_ = modbus_tcp_listen(ctx_, 64);
    if (listen_fd_ < 0 || ::fcntl(listen_fd_, F_SETFL, ::fcntl(listen_fd_, F_GETFL) | O_NONBLOCK) != 0) {
      throw std::runtime_error("cannot listen on " + options_.tcp_host + ":" + std::to_string(options_.tcp_port) +
                               ": " + modbus_strerror(errno));
    }
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    ::getsockname(listen_fd_, reinterpret_cast<sockaddr*>(&addr), &len);
    return "tcp://" + options_.tcp_host + ":" + std::to_string(ntohs(addr.sin_port));
  }

  void run(const std::atomic<bool>& stop) {
    while (!stop.load()) {
      long timeout_us = 50000;
      if (drive_.state() == mm::DriveState::playing) {
        if (drive_.lockstep) {
          timeout_us = drive_.ring_full() ? 50000 : 0;
        } else {
          const double lag = drive_.time() - std::chrono::duration<double>(Clock::now() - wall_start_).count();
          timeout_us = std::max(0L, std::lround(lag * 1e6));
        }
      }
      poll_requests(timeout_us);
      watch_communication();
      advance();
    }
  }

 private:
  // The host streams while a trajectory plays: silence for watchdog_s means it is gone.
  void watch_communication() {
    if (options_.watchdog_s <= 0 || drive_.state() != mm::DriveState::playing) return;
    const double silent = std::chrono::duration<double>(Clock::now() - last_request_).count();
    if (silent <= options_.watchdog_s) return;
    drive_.trip(mm::DriveFault::communication_lost, silent);
    std::printf("dyncal drive: no request for %.3f s while playing: trajectory stopped (communication lost)\n", silent);
    std::fflush(stdout);
  }

  // Real time: simulated time since start() follows the wall clock since the start command.
  void advance() {
    if (drive_.state() != mm::DriveState::playing) return;
    if (drive_.lockstep) {
      for (int k = 0; k < 200 && !drive_.ring_full() && drive_.state() == mm::DriveState::playing; ++k) drive_.step();
    } else {
      const double wall = std::chrono::duration<double>(Clock::now() - wall_start_).count();
      while (drive_.state() == mm::DriveState::playing && drive_.time() < wall) drive_.step();
    }
    if (drive_.state() == mm::DriveState::fault) {
      std::printf("dyncal drive: fault at t = %.3f s: joint %d, %s (%g)\n", drive_.time(), drive_.fault_joint(),
                  mm::to_string(drive_.fault()), drive_.fault_value());
      std::fflush(stdout);
    }
  }

  // One Modbus TCP client: its socket (non-blocking) and the bytes of its next frame so far.
  struct Connection {
    int fd = -1;
    std::vector<std::uint8_t> in;
    Clock::time_point frame_start;   ///< when the first byte of the pending partial frame arrived
    Clock::time_point last_request;  ///< accept time, then the last complete frame
  };

  // Waits at most timeout_us for requests and serves what has arrived. Never waits on one client:
  // sockets are non-blocking, each poll reads at most kReadBudget bytes per client, a partial frame
  // older than frame_timeout_s or a client silent for idle_timeout_s is disconnected, and a reply
  // that does not fit the client's send buffer (a client that does not read) disconnects it.
  void poll_requests(long timeout_us) {
    std::vector<pollfd> fds;
    if (!options_.rtu_device.empty()) {
      fds.push_back({modbus_get_socket(ctx_), POLLIN, 0});
    } else {
      fds.push_back({listen_fd_, POLLIN, 0});
      for (const auto& c : clients_) fds.push_back({c.fd, POLLIN, 0});
    }
    const timespec ts{timeout_us / 1000000, (timeout_us % 1000000) * 1000};
    const int ready = ::ppoll(fds.data(), fds.size(), &ts, nullptr);
    if (!options_.rtu_device.empty()) {
      if (ready > 0) serve_rtu();
      return;
    }
    const Clock::time_point now = Clock::now();
    std::vector<char> keep(clients_.size(), 1);
    for (size_t i = 0; i < clients_.size(); ++i) {
      if (ready > 0 && (fds[i + 1].revents & (POLLIN | POLLHUP | POLLERR))) keep[i] = read_and_serve(clients_[i], now);
      const Connection& c = clients_[i];
      if (keep[i] && !c.in.empty() && now - c.frame_start > seconds(options_.frame_timeout_s)) keep[i] = 0;
      if (keep[i] && now - c.last_request > seconds(options_.idle_timeout_s)) keep[i] = 0;
    }
    for (size_t i = clients_.size(); i-- > 0;) {
      if (!keep[i]) disconnect(clients_.begin() + static_cast<long>(i));
    }
    if (ready > 0 && (fds[0].revents & POLLIN)) accept_clients(now);
  }

  static Clock::duration seconds(double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  }

  // Accepts every pending connection. At max_connections, the client silent for longest makes room
  // if it has sent nothing for frame_timeout_s (a polling host is never that client); otherwise the
  // newcomer is closed at once: a clean refusal that leaves the connected clients served.
  void accept_clients(Clock::time_point now) {
    for (;;) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;  // EAGAIN: none left (or a transient error; the next poll retries)
      if (static_cast<int>(clients_.size()) >= options_.max_connections) {
        auto idlest = std::min_element(clients_.begin(), clients_.end(), [](const Connection& a, const Connection& b) {
          return a.last_request < b.last_request;
        });
        if (idlest != clients_.end() && now - idlest->last_request > seconds(options_.frame_timeout_s))
          disconnect(idlest);
      }
      if (static_cast<int>(clients_.size()) >= options_.max_connections) {
        ::close(fd);
        if (refused_++ == 0) {
          std::printf("dyncal drive: refusing connections beyond %d\n", options_.max_connections);
          std::fflush(stdout);
        }
        continue;
      }
      refused_ = 0;
      Connection c;
      c.fd = fd;
      c.last_request = now;
      clients_.push_back(std::move(c));
    }
  }

  // Reads what `c` has sent (at most kReadBudget bytes) and answers its complete frames. False when
  // the connection is to be closed: closed by the peer, framing lost, or a reply not sent in full.
  bool read_and_serve(Connection& c, Clock::time_point now) {
    constexpr size_t kReadBudget = 4096;
    std::uint8_t chunk[kReadBudget];
    const ssize_t got = ::recv(c.fd, chunk, sizeof chunk, 0);
    if (got == 0) return false;
    if (got < 0) return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
    if (c.in.empty()) c.frame_start = now;
    c.in.insert(c.in.end(), chunk, chunk + got);
    size_t used = 0;
    for (;;) {
      const MbapFrame f = next_mbap_frame(c.in.data() + used, c.in.size() - used);
      if (f.status == MbapFrame::Status::invalid) return false;
      if (f.status == MbapFrame::Status::incomplete) break;
      std::uint8_t frame[kMaxTcpAduBytes + 8] = {};  // zero beyond the frame: a short PDU reads zeros
      std::memcpy(frame, c.in.data() + used, f.bytes);
      used += f.bytes;
      c.last_request = now;
      // Protocol id 0 is Modbus; the unit id is 0xFF (the spec's value for a server addressed by its
      // IP address) or the drive's unit id. Other frames are not for this drive: ignored.
      if (f.protocol != 0 || (f.unit != 0xFF && f.unit != options_.rtu_slave)) continue;
      modbus_set_socket(ctx_, c.fd);
      current_client_ = c.fd;
      if (!request_pdu_consistent(frame + kMbapHeaderBytes, f.bytes - kMbapHeaderBytes)) {
        if (modbus_reply_exception(ctx_, frame, MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE) < 0) return false;
        continue;
      }
      if (!answer(frame, static_cast<int>(f.bytes))) return false;
    }
    c.in.erase(c.in.begin(), c.in.begin() + static_cast<long>(used));
    if (!c.in.empty() && used > 0) c.frame_start = now;  // the rest is the start of a new frame
    return true;
  }

  // RTU: one point-to-point line; libmodbus receives a frame (its byte time-out ends a partial one).
  void serve_rtu() {
    std::uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH];
    const int rc = modbus_receive(ctx_, query);
    current_client_ = kRtuClient;
    if (rc > 0) answer(query, rc);  // 0: addressed to another slave; < 0: bad frame, keep serving
  }

  /// Answers one complete request (ADU of `rc` bytes). False when the reply could not be sent in
  /// full (TCP: the connection is then closed).
  bool answer(const std::uint8_t* query, int rc) {
    last_request_ = Clock::now();
    const int off = modbus_get_header_length(ctx_);
    const int function = query[off];
    const int address = be16(query + off + 1);
    refresh_inputs(drive_, map_->tab_input_registers, table_generation_);
    map_->tab_registers[mm::kCommandReg] = 0;
    int exception = 0;
    int write_address = -1, write_count = 0;
    std::vector<std::uint16_t> scratch(map_->tab_registers, map_->tab_registers + mm::kHoldingWords);
    switch (function) {
      case MODBUS_FC_READ_INPUT_REGISTERS:
      case MODBUS_FC_READ_HOLDING_REGISTERS: {
        const int count = be16(query + off + 3);
        const auto bank = function == MODBUS_FC_READ_INPUT_REGISTERS ? mm::Bank::input : mm::Bank::holding;
        if (count >= 1 && count <= MODBUS_MAX_READ_REGISTERS && !addresses_defined(bank, address, count)) {
          exception = MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
        }
        break;
      }
      case MODBUS_FC_WRITE_SINGLE_REGISTER:
        write_address = address;
        write_count = 1;
        if (!addresses_defined(mm::Bank::holding, address, 1)) {
          exception = MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
        } else {
          scratch[static_cast<size_t>(address)] = be16(query + off + 3);
        }
        break;
      case MODBUS_FC_WRITE_MULTIPLE_REGISTERS: {
        write_address = address;
        write_count = be16(query + off + 3);
        if (write_count < 1 || write_count > MODBUS_MAX_WRITE_REGISTERS) break;  // libmodbus answers
        if (!addresses_defined(mm::Bank::holding, address, write_count)) {
          exception = MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
        } else {
          for (int k = 0; k < write_count; ++k)
            scratch[static_cast<size_t>(address + k)] = be16(query + off + 6 + 2 * k);
        }
        break;
      }
      case MODBUS_FC_READ_COILS:
      case MODBUS_FC_READ_DISCRETE_INPUTS:
      case MODBUS_FC_WRITE_SINGLE_COIL:
      case MODBUS_FC_WRITE_MULTIPLE_COILS:
      case MODBUS_FC_REPORT_SLAVE_ID:
        break;  // libmodbus answers (no coils: illegal data address)
      default:
        exception = MODBUS_EXCEPTION_ILLEGAL_FUNCTION;
    }
    if (!exception && write_count > 0 && write_address >= 0) {
      if (splits_element(write_address, write_count)) {
        exception = MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS;
      } else {
        exception = check_holding(drive_, scratch.data(), write_address, write_count, 1.0 / drive_.control_period(),
                                  session_open());
      }
    }
    if (exception) {
      return modbus_reply_exception(ctx_, query, static_cast<unsigned>(exception)) >= 0;
    }
    if (modbus_reply(ctx_, query, rc, map_) < 0) return false;
    if (write_count > 0) apply_write(write_address, write_count);
    return true;
  }

  void apply_write(int address, int count) {
    std::uint16_t* h = map_->tab_registers;
    if (overlaps(address, count, mm::kAckReg, 2)) drive_.ack(mm::get_u32(h + mm::kAckReg));
    if (overlaps(address, count, mm::kUnlockReg, 1)) {
      session_client_ = current_client_;
      session_until_ = Clock::now() + seconds(mm::kSessionSeconds);
      h[mm::kUnlockReg] = 0;
    }
    if (!overlaps(address, count, mm::kCommandReg, 1)) return;
    switch (static_cast<mm::Command>(h[mm::kCommandReg])) {
      case mm::Command::start:
        load_trajectory(drive_, h);
        drive_.start();
        wall_start_ = Clock::now();
        mm::set_u32(h + mm::kAckReg, 0);
        break;
      case mm::Command::stop:
        drive_.stop();
        break;
      case mm::Command::reset:
        drive_.reset();
        break;
      case mm::Command::commit_table: {
        session_client_ = kNoClient;  // a commit ends the session
        const int size = h[mm::kStagingSizeReg];
        std::vector<std::uint8_t> bytes(static_cast<size_t>(size));
        mm::regs_to_bytes(h + mm::kStagingTableReg, size, bytes.data());
        TableStatus st;
        try {
          st = drive_.commit(bytes.data(), size);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "dyncal drive: flash write failed: %s\n", e.what());
          st = TableStatus::bad_size;
        }
        map_->tab_input_registers[mm::kCommitResultReg] = static_cast<std::uint16_t>(st);
        ++map_->tab_input_registers[mm::kCommitCounterReg];
        std::printf("dyncal drive: commit %s\n", to_string(st));
        std::fflush(stdout);
        break;
      }
      case mm::Command::none:
        break;
    }
    h[mm::kCommandReg] = 0;
  }

  SimulatedDrive& drive_;
  DriveServerOptions options_;
  modbus_t* ctx_ = nullptr;
  modbus_mapping_t* map_ = nullptr;
  int listen_fd_ = -1;
  std::vector<Connection> clients_;
  long refused_ = 0;  ///< connections refused since the cap was last below its limit
  static constexpr int kNoClient = -1;
  static constexpr int kRtuClient = -2;  ///< the RTU line: one client
  int current_client_ = kNoClient;       ///< socket (or kRtuClient) of the request being answered
  int session_client_ = kNoClient;       ///< the client holding the staging session
  Clock::time_point session_until_ = Clock::now();

  bool session_open() const {
    return session_client_ != kNoClient && session_client_ == current_client_ && Clock::now() < session_until_;
  }
  // Closes a client; its session ends with it (a later client may get the same descriptor).
  void disconnect(std::vector<Connection>::iterator c) {
    if (session_client_ == c->fd) session_client_ = kNoClient;
    ::close(c->fd);
    clients_.erase(c);
  }
  Clock::time_point last_request_ = Clock::now();  ///< the last complete request of any client
  long table_generation_ = -1;
  Clock::time_point wall_start_ = Clock::now();
};

}  // namespace

void serve_drive(SimulatedDrive& drive, const DriveServerOptions& options, const std::atomic<bool>& stop) {
  Server server(drive, options);
  const std::string uri = server.open();
  if (!options.ready_file.empty()) {
    const std::string text = uri + "\n";
    write_file_atomically(options.ready_file, std::vector<std::uint8_t>(text.begin(), text.end()));
  }
  std::printf("dyncal drive: ready %s pid %d\n", uri.c_str(), static_cast<int>(::getpid()));
  std::fflush(stdout);
  server.run(stop);
}

}  // namespace dyncal::host
