// A serial line at a real baud rate for the RTU tests: two pseudo-terminals joined by a relay that
// lets each byte through only after its character time on the wire (8N1: 10 bits), in each
// direction independently, as a full-duplex RS-232/RS-485 line carries them. The drive opens one
// pty's device, the host the other's; what crosses takes as long as on a real line.
//
//   serial_line_relay BAUD DRIVE_LINK HOST_LINK READY_FILE
//
// DRIVE_LINK and HOST_LINK become symbolic links to the two devices; READY_FILE appears once both
// exist. Runs until killed. Errors: one line on stderr, exit 1.
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <string>

namespace {

using Clock = std::chrono::steady_clock;

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "serial_line_relay: %s: %s\n", what.c_str(), std::strerror(errno));
  std::exit(1);
}

// One pty: the relay reads and writes its master; its device (the slave) is set raw and kept open
// here, so the master never reads end-of-file while the drive or the host reopens the device.
struct Pty {
  int master = -1;
  int slave = -1;
};

Pty open_pty(const std::string& link) {
  Pty p;
  p.master = ::posix_openpt(O_RDWR | O_NOCTTY);
  if (p.master < 0 || ::grantpt(p.master) != 0 || ::unlockpt(p.master) != 0) die("cannot open a pty");
  const char* name = ::ptsname(p.master);
  if (!name) die("ptsname");
  p.slave = ::open(name, O_RDWR | O_NOCTTY);
  if (p.slave < 0) die(std::string("cannot open ") + name);
  termios t{};
  if (::tcgetattr(p.slave, &t) != 0) die("tcgetattr");
  ::cfmakeraw(&t);
  if (::tcsetattr(p.slave, TCSANOW, &t) != 0) die("tcsetattr");
  ::fcntl(p.master, F_SETFL, ::fcntl(p.master, F_GETFL) | O_NONBLOCK);
  ::unlink(link.c_str());
  if (::symlink(name, link.c_str()) != 0) die("cannot link " + link);
  return p;
}

// One direction of the line: bytes read from `from` leave for `to` at the end of their character
// time, one character after another.
struct Direction {
  int from = -1, to = -1;
  std::deque<std::pair<unsigned char, Clock::time_point>> queue;
  Clock::time_point line_free{};  // when the last queued character has crossed
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: serial_line_relay BAUD DRIVE_LINK HOST_LINK READY_FILE\n");
    return 1;
  }
  const double baud = std::atof(argv[1]);
  if (!(baud >= 300 && baud <= 4e6)) {
    std::fprintf(stderr, "serial_line_relay: baud rate '%s' is not 300..4000000\n", argv[1]);
    return 1;
  }
  const auto character = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(10.0 / baud));
  const Pty drive = open_pty(argv[2]), host = open_pty(argv[3]);
  {
    const std::string tmp = std::string(argv[4]) + ".tmp";
    FILE* f = std::fopen(tmp.c_str(), "w");
    if (!f || std::fprintf(f, "%s\n", argv[1]) < 0 || std::fclose(f) != 0 || std::rename(tmp.c_str(), argv[4]) != 0)
      die(std::string("cannot write ") + argv[4]);
  }
  Direction dir[2];
  dir[0].from = host.master, dir[0].to = drive.master;  // requests
  dir[1].from = drive.master, dir[1].to = host.master;  // replies
  for (;;) {
    Clock::time_point now = Clock::now();
    // Deliver every character whose time has come; wait for the next one or for new input.
    Clock::time_point next = now + std::chrono::seconds(1);
    for (Direction& d : dir) {
      unsigned char out[4096];
      std::size_t n = 0;
      while (!d.queue.empty() && d.queue.front().second <= now && n < sizeof out) {
        out[n++] = d.queue.front().first;
        d.queue.pop_front();
      }
      if (n > 0 && ::write(d.to, out, n) != static_cast<ssize_t>(n)) {
        // The device's input queue is full or nobody holds it: a line drops what it cannot deliver.
      }
      if (!d.queue.empty() && d.queue.front().second < next) next = d.queue.front().second;
    }
    pollfd fds[2] = {{dir[0].from, POLLIN, 0}, {dir[1].from, POLLIN, 0}};
    const long long wait =
        std::max(0LL, static_cast<long long>(std::chrono::duration_cast<std::chrono::nanoseconds>(next - now).count()));
    const timespec ts{static_cast<time_t>(wait / 1000000000), static_cast<long>(wait % 1000000000)};
    if (::ppoll(fds, 2, &ts, nullptr) < 0 && errno != EINTR) die("ppoll");
    now = Clock::now();
    for (int k = 0; k < 2; ++k) {
      if (!(fds[k].revents & POLLIN)) continue;
      unsigned char in[4096];
      const ssize_t got = ::read(fds[k].fd, in, sizeof in);
      for (ssize_t i = 0; i < got; ++i) {
        Direction& d = dir[k];
        d.line_free = std::max(d.line_free, now) + character;
        d.queue.emplace_back(in[i], d.line_free);
      }
    }
  }
}
