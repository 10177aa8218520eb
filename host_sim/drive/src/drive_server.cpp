#include "dyncal_host/drive/drive_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <vector>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/drive/rtu_receiver.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "modbus_request_handler.hpp"

namespace dyncal::host {
namespace {

namespace mm = dyncal::modbus_map;
using Clock = std::chrono::steady_clock;

/// The serial line `device` opened non-blocking, raw, 8N1 at `baud` [bit/s] (a pseudo-terminal
/// ignores the rate). Throws InputError naming the device and the reason.
int open_serial_line(const std::string& device, int baud) {
  static const std::pair<int, speed_t> rates[] = {{9600, B9600},     {19200, B19200},   {38400, B38400},
                                                  {57600, B57600},   {115200, B115200}, {230400, B230400},
                                                  {460800, B460800}, {921600, B921600}};
  speed_t speed = 0;
  for (const auto& [b, s] : rates)
    if (b == baud) speed = s;
  if (speed == 0) throw InputError("RTU baud rate " + std::to_string(baud) + " is not a standard rate");
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) throw InputError("cannot open RTU device " + device + ": " + std::strerror(errno));
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    const int e = errno;
    ::close(fd);
    throw InputError("cannot open RTU device " + device + ": " + std::strerror(e));
  }
  ::cfmakeraw(&t);
  t.c_cflag |= CLOCAL | CREAD;
  t.c_cflag &= ~static_cast<tcflag_t>(PARENB | CSTOPB);
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  ::cfsetispeed(&t, speed);
  ::cfsetospeed(&t, speed);
  if (::tcsetattr(fd, TCSANOW, &t) != 0) {
    const int e = errno;
    ::close(fd);
    throw InputError("cannot configure RTU device " + device + ": " + std::strerror(e));
  }
  return fd;
}

/// A non-blocking listening TCP socket on host:port (port 0: any free port). Throws
/// InputError naming the address and the reason.
int listen_tcp(const std::string& host, int port) {
  const std::string where = host + ":" + std::to_string(port);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  if (::inet_pton(AF_INET, host.c_str(), &addr.sin_addr) != 1)
    throw InputError("cannot listen on " + where + ": not an IPv4 address");
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  const int yes = 1;
  if (fd < 0 || ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes) != 0 ||
      ::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd, 64) != 0 ||
      ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) | O_NONBLOCK) != 0) {
    const int e = errno;
    if (fd >= 0) ::close(fd);
    throw InputError("cannot listen on " + where + ": " + std::strerror(e));
  }
  return fd;
}

class Server {
 public:
  Server(SimulatedDrive& drive, const DriveServerOptions& o) : drive_(drive), options_(o) {}
  ~Server() {
    for (const auto& c : clients_) ::close(c.fd);
    if (listen_fd_ >= 0) ::close(listen_fd_);
    handler_.reset();
    if (rtu_fd_ >= 0) ::close(rtu_fd_);
  }

  std::string open() {
    if (!options_.rtu_device.empty()) {
      rtu_fd_ = open_serial_line(options_.rtu_device, options_.rtu_baud);
      handler_ = std::make_unique<ModbusRequestHandler>(drive_, rtu_fd_, options_.rtu_slave);
      rtu_ = std::make_unique<drive::RtuReceiver<>>(static_cast<std::uint8_t>(options_.rtu_slave),
                                                    static_cast<std::uint64_t>(kRtuResyncSeconds * 1e6));
      return "rtu:" + options_.rtu_device;
    }
    listen_fd_ = listen_tcp(options_.tcp_host, options_.tcp_port);
    handler_ = std::make_unique<ModbusRequestHandler>(drive_, -1, options_.rtu_slave);
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
          const double lag = drive_.time() - std::chrono::duration<double>(Clock::now() - handler_->started()).count();
          timeout_us = std::max(0L, std::lround(lag * 1e6));
        }
      }
      poll_requests(timeout_us);
      watch_communication();
      advance();
    }
  }

 private:
  // The host that started the trajectory streams while it plays: its silence for watchdog_s means
  // it is gone (other clients' requests do not count: a poller says nothing about that host).
  void watch_communication() {
    if (options_.watchdog_s <= 0 || drive_.state() != mm::DriveState::playing) return;
    const double silent = std::chrono::duration<double>(Clock::now() - handler_->owner_last_request()).count();
    if (silent <= options_.watchdog_s) return;
    drive_.trip(mm::DriveFault::communication_lost, silent);
    std::printf(
        "dyncal drive: no request from the host that started the trajectory for %.3f s: trajectory stopped "
        "(communication lost)\n",
        silent);
    std::fflush(stdout);
  }

  // Real time: simulated time since start() follows the wall clock since the start command.
  void advance() {
    if (drive_.state() != mm::DriveState::playing) return;
    if (drive_.lockstep) {
      for (int k = 0; k < 200 && !drive_.ring_full() && drive_.state() == mm::DriveState::playing; ++k) drive_.step();
    } else {
      const double wall = std::chrono::duration<double>(Clock::now() - handler_->started()).count();
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
      fds.push_back({rtu_fd_, POLLIN, 0});
    } else {
      fds.push_back({listen_fd_, POLLIN, 0});
      for (const auto& c : clients_) fds.push_back({c.fd, POLLIN, 0});
    }
    const timespec ts{timeout_us / 1000000, (timeout_us % 1000000) * 1000};
    const int ready = ::ppoll(fds.data(), fds.size(), &ts, nullptr);
    advance();  // as a drive's control loop runs beside its fieldbus: requests see every sample due
    if (!options_.rtu_device.empty()) {
      serve_rtu(ready > 0);
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

  // Accepts every pending connection. At max_connections the least recently used client makes room
  // (the one whose last complete request is oldest), unless it holds a role: the client that
  // started the trajectory and the holder of an open staging session are never evicted. Pollers
  // thus share the slots among themselves and cannot lock a host out. A newcomer is refused (closed
  // at once) only when every connected client holds a role.
  void accept_clients(Clock::time_point now) {
    for (;;) {
      const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;  // EAGAIN: none left (or a transient error; the next poll retries)
      if (static_cast<int>(clients_.size()) >= options_.max_connections) {
        auto lru = clients_.end();
        for (auto c = clients_.begin(); c != clients_.end(); ++c) {
          if (handler_->holds_a_role(c->fd)) continue;
          if (lru == clients_.end() || c->last_request < lru->last_request) lru = c;
        }
        if (lru != clients_.end()) disconnect(lru);
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
    const ModbusRequestHandler::TcpResult r = handler_->serve_tcp(c.in.data(), c.in.size(), c.fd);
    if (!r.keep) return false;
    if (r.frames > 0) c.last_request = now;
    const size_t used = r.used;
    c.in.erase(c.in.begin(), c.in.begin() + static_cast<long>(used));
    if (!c.in.empty() && used > 0) c.frame_start = now;  // the rest is the start of a new frame
    return true;
  }

  // RTU: one point-to-point line, received by lib/'s drive application (dyncal/drive/rtu_receiver.hpp):
  // a request ends where its function's length says, its CRC decides whether it is answered, and a
  // frame that cannot be taken is dropped until the line has been silent for kRtuResyncSeconds.
  void serve_rtu(bool readable) {
    const auto now = static_cast<std::uint64_t>(
        std::chrono::duration_cast<std::chrono::microseconds>(Clock::now() - rtu_epoch_).count());
    auto answer = [this](const std::uint8_t* adu, std::size_t n) {
      handler_->answer(adu, static_cast<int>(n), ModbusRequestHandler::kRtuClient);
    };
    if (readable) {
      // At most one ADU per read: the receiver holds a partial frame and the next one's bytes.
      std::uint8_t buf[drive::kMaxRtuAduBytes];
      for (ssize_t n; (n = ::read(rtu_fd_, buf, sizeof buf)) > 0;) {
        rtu_->push(buf, static_cast<std::size_t>(n), now);
        rtu_->poll(now, answer);
      }
    }
    rtu_->poll(now, answer);
  }

  SimulatedDrive& drive_;
  DriveServerOptions options_;
  int rtu_fd_ = -1;                                ///< RTU: the serial line (non-blocking, raw 8N1)
  std::unique_ptr<ModbusRequestHandler> handler_;  ///< created by open()
  /// RTU: a silence that ends a frame of unknown length and after which a dropped frame's bytes are
  /// over. Longer than t3.5 (1.75 ms at 115 200 baud, drive::rtu_silence_us): a pseudo-terminal or a
  /// USB adapter delivers one frame's bytes with gaps of several milliseconds.
  static constexpr double kRtuResyncSeconds = 0.05;
  Clock::time_point rtu_epoch_ = Clock::now();  ///< the receiver's clock starts here
  std::unique_ptr<drive::RtuReceiver<>> rtu_;   ///< RTU: the line's receiver (created by open())
  int listen_fd_ = -1;
  std::vector<Connection> clients_;
  long refused_ = 0;  ///< connections refused since the cap was last below its limit

  // Closes a client; its session ends with it (a later client may get the same descriptor).
  void disconnect(std::vector<Connection>::iterator c) {
    handler_->client_closed(c->fd);
    ::close(c->fd);
    clients_.erase(c);
  }
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
