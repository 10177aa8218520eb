#include "dyncal_host/drive/drive_server.hpp"

#include <arpa/inet.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

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

/// Checks the holding registers after a write (applied to a scratch copy). Returns a Modbus
/// exception code or 0.
int check_holding(const SimulatedDrive& d, const std::uint16_t* h, int address, int count, double control_rate) {
  const bool playing = d.state() == mm::DriveState::playing;
  if (overlaps(address, count, mm::kCommandReg, 1)) {
    const std::uint16_t c = h[mm::kCommandReg];
    if (c > static_cast<std::uint16_t>(mm::Command::commit_table)) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
    if (c == static_cast<std::uint16_t>(mm::Command::commit_table) && playing)
      return MODBUS_EXCEPTION_SLAVE_OR_SERVER_BUSY;
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
    if (!(fs >= 100 && fs <= 1000) || std::fabs(ratio - std::round(ratio)) > 1e-6)
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  if (overlaps(address, count, mm::kOmegaFReg, 2)) {
    const double f = mm::get_f32(h + mm::kOmegaFReg);
    if (!(f > 0 && f <= 10)) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  if (overlaps(address, count, mm::kHarmonicsReg, 1)) {
    if (h[mm::kHarmonicsReg] < 1 || h[mm::kHarmonicsReg] > mm::kMaxHarmonics)
      return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
  }
  if (overlaps(address, count, mm::kPeriodsReg, 1)) {
    if (h[mm::kPeriodsReg] < 1 || h[mm::kPeriodsReg] > 100) return MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE;
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
    for (int fd : clients_) ::close(fd);
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
    listen_fd_ = modbus_tcp_listen(ctx_, 4);
    if (listen_fd_ < 0) {
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
      advance();
    }
  }

 private:
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

  void poll_requests(long timeout_us) {
    fd_set set;
    FD_ZERO(&set);
    int maxfd = -1;
    auto add = [&](int fd) {
      FD_SET(fd, &set);
      maxfd = std::max(maxfd, fd);
    };
    if (!options_.rtu_device.empty()) {
      add(modbus_get_socket(ctx_));
    } else {
      add(listen_fd_);
      for (int fd : clients_) add(fd);
    }
    timeval tv{timeout_us / 1000000, timeout_us % 1000000};
    if (::select(maxfd + 1, &set, nullptr, nullptr, &tv) <= 0) return;
    if (!options_.rtu_device.empty()) {
      serve_one();
      return;
    }
    if (FD_ISSET(listen_fd_, &set)) {
      const int fd = ::accept(listen_fd_, nullptr, nullptr);
      if (fd >= 0) clients_.push_back(fd);
    }
    for (size_t i = 0; i < clients_.size();) {
      const int fd = clients_[i];
      if (FD_ISSET(fd, &set)) {
        modbus_set_socket(ctx_, fd);
        if (!serve_one()) {
          ::close(fd);
          clients_.erase(clients_.begin() + static_cast<long>(i));
          continue;
        }
      }
      ++i;
    }
  }

  /// Receives and answers one request. False when the connection closed.
  bool serve_one() {
    std::uint8_t query[MODBUS_RTU_MAX_ADU_LENGTH > MODBUS_TCP_MAX_ADU_LENGTH ? MODBUS_RTU_MAX_ADU_LENGTH
                                                                             : MODBUS_TCP_MAX_ADU_LENGTH];
    const int rc = modbus_receive(ctx_, query);
    if (rc == 0) return true;                         // RTU: addressed to another slave
    if (rc < 0) return !options_.rtu_device.empty();  // RTU: bad frame, keep serving
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
        exception = check_holding(drive_, scratch.data(), write_address, write_count, 1.0 / drive_.control_period());
      }
    }
    if (exception) {
      modbus_reply_exception(ctx_, query, static_cast<unsigned>(exception));
      return true;
    }
    if (modbus_reply(ctx_, query, rc, map_) < 0) return !options_.rtu_device.empty();
    if (write_count > 0) apply_write(write_address, write_count);
    return true;
  }

  void apply_write(int address, int count) {
    std::uint16_t* h = map_->tab_registers;
    if (overlaps(address, count, mm::kAckReg, 2)) drive_.ack(mm::get_u32(h + mm::kAckReg));
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
      case mm::Command::commit_table: {
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
  std::vector<int> clients_;
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
