// The simulated drive against hostile Modbus TCP clients (issue 23, faults 1 and 2), on a drive of
// its own started by a CTest fixture: more idle connections than an fd_set holds, a client that
// sends a frame one byte at a time, one that floods requests and never reads the replies, and
// frames with a wrong protocol id, unit id, length or PDU. Throughout, a real host (ModbusDrive)
// streams a trajectory: every sample arrives, in order, none lost.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "dyncal/modbus_map.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "support/drive_uri.hpp"
#include "support/one_harmonic_run.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using dyncal::linux_port::ModbusDrive;
using dyncal::port::PortStatus;

std::string uri() {
  return fixture_drive_uri("DYNCAL_DRIVE_HOSTILE_READY");
}

int port_of(const std::string& u) {
  return std::stoi(u.substr(u.rfind(':') + 1));
}

// A plain TCP connection to the fixture drive (-1 when refused).
int raw_connect() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port_of(uri())));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    ::close(fd);
    return -1;
  }
  return fd;
}

// True when the peer closed `fd` within `seconds` (recv returns 0 or an error).
bool closed_by_peer(int fd, double seconds) {
  pollfd p{fd, POLLIN, 0};
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  for (auto now = std::chrono::steady_clock::now(); now < deadline; now = std::chrono::steady_clock::now()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now).count();
    if (::poll(&p, 1, static_cast<int>(std::min<long long>(50, std::max<long long>(left, 1)))) > 0) {
      char b[512];
      const ssize_t n = ::recv(fd, b, sizeof b, MSG_DONTWAIT);
      if (n <= 0) return true;
    }
  }
  return false;
}

// A read request (function 4: input registers, 3: holding registers) as raw MBAP bytes.
std::vector<std::uint8_t> read_request(std::uint16_t tid, std::uint16_t protocol, std::uint8_t unit, int address,
                                       int count, std::uint8_t function = 4) {
  return {static_cast<std::uint8_t>(tid >> 8),
          static_cast<std::uint8_t>(tid),
          static_cast<std::uint8_t>(protocol >> 8),
          static_cast<std::uint8_t>(protocol),
          0,
          6,
          unit,
          function,
          static_cast<std::uint8_t>(address >> 8),
          static_cast<std::uint8_t>(address),
          static_cast<std::uint8_t>(count >> 8),
          static_cast<std::uint8_t>(count)};
}

// The reply to one request on `fd` within `seconds`, or empty.
std::vector<std::uint8_t> reply(int fd, double seconds) {
  pollfd p{fd, POLLIN, 0};
  std::vector<std::uint8_t> out;
  if (::poll(&p, 1, static_cast<int>(seconds * 1000)) <= 0) return out;
  std::uint8_t b[300];
  const ssize_t n = ::recv(fd, b, sizeof b, 0);
  if (n > 0) out.assign(b, b + n);
  return out;
}

// Streams a 2-period trajectory (2000 samples) from the drive with a real host and checks that every
// sample arrives in order with none lost, while `attack` runs on other connections.
void stream_while(const std::function<void(std::atomic<bool>&)>& attack) {
  std::atomic<bool> stop{false};
  std::thread attacker([&] { attack(stop); });
  struct Join {  // an assertion below returns early: the attacker still ends
    std::atomic<bool>& stop;
    std::thread& t;
    ~Join() {
      stop = true;
      t.join();
    }
  } join{stop, attacker};
  std::string error;
  auto drive = ModbusDrive::connect(uri(), &error);
  ASSERT_NE(drive, nullptr) << error;
  ASSERT_NO_FATAL_FAILURE(start_one_harmonic_run(*drive, 1.0, 2));
  dyncal::port::DriveSample block[16];
  long received = 0;
  std::uint32_t next = 0;
  for (;;) {
    int n = 0;
    const PortStatus st = drive->read(block, 16, &n);
    ASSERT_TRUE(st == PortStatus::ok || st == PortStatus::no_data || st == PortStatus::end_of_stream)
        << static_cast<int>(st) << ": " << drive->error();
    for (int k = 0; k < n; ++k) EXPECT_EQ(block[k].seq, next++);
    received += n;
    if (st == PortStatus::end_of_stream) break;
  }
  EXPECT_EQ(received, 2000);
  EXPECT_EQ(drive->lost(), 0U);
}

// fault 1: 1025 idle connections crashed the drive (descriptors >= 1024 in an fd_set).
TEST(DriveHostileClients, ManyIdleConnectionsNeitherCrashNorLockOutTheHost) {
  rlimit lim{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &lim), 0);
  lim.rlim_cur = lim.rlim_max;
  ::setrlimit(RLIMIT_NOFILE, &lim);
  const int wanted = static_cast<int>(std::min<rlim_t>(1100, lim.rlim_cur - 64));
  std::vector<int> fds;
  for (int k = 0; k < wanted; ++k) {
    const int fd = raw_connect();
    if (fd >= 0) fds.push_back(fd);
  }
  EXPECT_GT(fds.size(), 1024U) << "could not open enough connections to reach the old fd_set limit";
  // The drive holds at most its cap: all others are closed by the drive.
  // Passes over the connections until the drive has closed all but its cap (it may lag behind
  // the burst on a loaded machine); closed ones are closed here too.
  std::vector<int> held = fds;
  for (int pass = 0; pass < 50 && held.size() > 16; ++pass) {
    std::vector<int> still;
    for (int fd : held) {
      if (closed_by_peer(fd, 0.001)) {
        ::close(fd);
      } else {
        still.push_back(fd);
      }
    }
    held.swap(still);
  }
  ASSERT_LE(held.size(), 16U);
  // The drive's slots are full of idle clients (this process's descriptors are below 1024 again:
  // libmodbus's client uses select). A host gets in at once (the least recently used makes room)
  // and streams.
  stream_while([](std::atomic<bool>&) {});
  for (int fd : held) ::close(fd);
}

// Issue 47: 16 clients polling every 0.5 s locked every other client out for as long as they
// polled (a newcomer replaced only a client silent for 1 s). Least-recently-used eviction: 24
// pollers, every 0.1 s, reconnecting when evicted, while a host streams a whole run; the host is
// never evicted (it started the trajectory), and the pollers share the other slots.
TEST(DriveHostileClients, PollersShareTheSlotsAndCannotLockOutTheHost) {
  constexpr int kPollers = 24;
  std::vector<long> answered(kPollers, 0);
  std::atomic<int> rounds{0};
  std::atomic<bool> stop{false};
  std::thread pollers([&] {
    std::vector<int> fds(kPollers, -1);
    std::uint16_t tid = 0;
    while (!stop) {
      for (int i = 0; i < kPollers; ++i) {
        if (fds[i] < 0) fds[i] = raw_connect();
        if (fds[i] < 0) continue;
        const auto req = read_request(++tid, 0, 0xFF, mm::kMapVersionReg, 1);
        if (::send(fds[i], req.data(), req.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(req.size()) ||
            reply(fds[i], 0.05).size() != 11) {
          ::close(fds[i]);  // evicted: reconnect on the next round
          fds[i] = -1;
          continue;
        }
        ++answered[static_cast<size_t>(i)];
      }
      ++rounds;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    for (int fd : fds) {
      if (fd >= 0) ::close(fd);
    }
  });
  // Every slot is taken before the host connects.
  while (rounds < 5) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  stream_while([](std::atomic<bool>&) {});
  const int during = rounds;
  while (rounds < during + 3) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  stop = true;
  pollers.join();
  for (int i = 0; i < kPollers; ++i) EXPECT_GE(answered[static_cast<size_t>(i)], 4) << "poller " << i;
}

// fault 2: a frame sent one byte per 0.45 s froze the drive for everyone.
TEST(DriveHostileClients, ASlowSenderNeitherStallsTheHostNorKeepsItsConnection) {
  const int slow = raw_connect();
  ASSERT_GE(slow, 0);
  const auto frame = read_request(1, 0, 0xFF, mm::kMapVersionReg, 1);
  std::atomic<bool> dropped{false};
  stream_while([&](std::atomic<bool>& stop) {
    for (size_t k = 0; k < frame.size() && !stop; ++k) {
      if (::send(slow, &frame[k], 1, MSG_NOSIGNAL) != 1) {
        dropped = true;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(450));
    }
  });
  // The drive gives a partial frame at most its frame time-out (1 s) plus one poll.
  EXPECT_TRUE(dropped || closed_by_peer(slow, 3.0));
  ::close(slow);
}

// fault 2: a flood of requests whose replies are never read froze the drive in send().
TEST(DriveHostileClients, AFloodThatNeverReadsItsRepliesIsDisconnected) {
  const int flood = raw_connect();
  ASSERT_GE(flood, 0);
  int small = 4096;
  ::setsockopt(flood, SOL_SOCKET, SO_RCVBUF, &small, sizeof small);
  std::atomic<bool> disconnected{false};
  stream_while([&](std::atomic<bool>& stop) {
    std::vector<std::uint8_t> burst;
    for (int k = 0; k < 100; ++k) {
      const auto f = read_request(static_cast<std::uint16_t>(k), 0, 0xFF, mm::kRingReg, mm::kRingWords, 3);
      burst.insert(burst.end(), f.begin(), f.end());
    }
    while (!stop) {
      if (::send(flood, burst.data(), burst.size(), MSG_NOSIGNAL | MSG_DONTWAIT) < 0 && errno != EAGAIN) {
        disconnected = true;
        return;
      }
    }
  });
  EXPECT_TRUE(disconnected || closed_by_peer(flood, 3.0));
  ::close(flood);
}

// The MBAP header is checked: protocol id 0 and unit id 0xFF or the drive's (1) are answered,
// other protocol or unit ids are ignored (no reply, connection kept), a length outside 2..254
// closes the connection (framing lost), a PDU whose length contradicts its function gets
// exception 3 (illegal data value).
TEST(DriveHostileClients, MbapHeaderAndPduLengthAreValidated) {
  const int fd = raw_connect();
  ASSERT_GE(fd, 0);
  auto ask = [&](const std::vector<std::uint8_t>& f) {
    EXPECT_EQ(::send(fd, f.data(), f.size(), MSG_NOSIGNAL), static_cast<ssize_t>(f.size()));
    return reply(fd, 0.3);
  };
  auto ok = ask(read_request(1, 0, 0xFF, mm::kMapVersionReg, 1));
  ASSERT_EQ(ok.size(), 11U);
  EXPECT_EQ(ok[7], 4);
  EXPECT_EQ((ok[9] << 8) | ok[10], mm::kMapVersion);
  EXPECT_EQ(ask(read_request(2, 0, 1, mm::kMapVersionReg, 1)).size(), 11U);
  EXPECT_TRUE(ask(read_request(3, 7, 0xFF, mm::kMapVersionReg, 1)).empty());  // protocol id 7
  EXPECT_TRUE(ask(read_request(4, 0, 9, mm::kMapVersionReg, 1)).empty());     // unit id 9
  // A read request with one byte too many (length 7): exception 3, same transaction id.
  auto longer = read_request(5, 0, 0xFF, mm::kMapVersionReg, 1);
  longer[5] = 7;
  longer.push_back(0);
  const auto ex = ask(longer);
  ASSERT_EQ(ex.size(), 9U);
  EXPECT_EQ(ex[1], 5);
  EXPECT_EQ(ex[7], 0x84);
  EXPECT_EQ(ex[8], 3);
  // Still served after all that.
  EXPECT_EQ(ask(read_request(6, 0, 0xFF, mm::kMapVersionReg, 1)).size(), 11U);
  // A length field of 300: the connection is closed.
  auto bad = read_request(7, 0, 0xFF, mm::kMapVersionReg, 1);
  bad[4] = 0x01;
  bad[5] = 0x2C;
  ::send(fd, bad.data(), bad.size(), MSG_NOSIGNAL);
  EXPECT_TRUE(closed_by_peer(fd, 2.0));
  ::close(fd);
}

// Found by fuzz_modbus_request: a quantity out of range (read 0 or 126 registers, write 0 registers,
// read 2001 coils) made libmodbus sleep its response time-out (0.5 s) before answering, stalling the
// drive's single thread per request, and a function code 0x80-0xFF was answered as another
// function's exception (0xFF + 0x80 wrapped to 0x7F). Each now gets its exception at once.
TEST(DriveHostileClients, BadQuantitiesAndReservedFunctionsGetTheirExceptionAtOnce) {
  const int fd = raw_connect();
  ASSERT_GE(fd, 0);
  struct Case {
    std::vector<std::uint8_t> pdu;
    std::uint8_t function, code;
  };
  const std::vector<Case> cases = {
      {{4, 0, 0, 0, 0}, 0x84, 3},        // read 0 input registers
      {{3, 0, 0, 0, 126}, 0x83, 3},      // read 126 holding registers
      {{16, 0, 2, 0, 0, 0}, 0x90, 3},    // write 0 registers
      {{1, 0, 0, 0x07, 0xD1}, 0x81, 3},  // read 2001 coils
      {{15, 0, 0, 0, 0, 0}, 0x8F, 3},    // write 0 coils
      {{0x2B, 0x0E, 1, 0}, 0xAB, 1},     // an unserved function: illegal function
      {{0xFF, 0, 0, 0, 1}, 0xFF, 1},     // a reserved (exception) code: illegal function
  };
  std::uint16_t tid = 100;
  for (int round = 0; round < 3; ++round) {
    for (const Case& c : cases) {
      ++tid;
      std::vector<std::uint8_t> f = {static_cast<std::uint8_t>(tid >> 8),
                                     static_cast<std::uint8_t>(tid),
                                     0,
                                     0,
                                     0,
                                     static_cast<std::uint8_t>(c.pdu.size() + 1),
                                     0xFF};
      f.insert(f.end(), c.pdu.begin(), c.pdu.end());
      ASSERT_EQ(::send(fd, f.data(), f.size(), MSG_NOSIGNAL), static_cast<ssize_t>(f.size()));
      // Well within the 0.5 s libmodbus slept before (a loaded CI machine still answers in 0.3 s).
      const auto r = reply(fd, 0.3);
      ASSERT_EQ(r.size(), 9U) << "function " << int{c.pdu[0]} << ": no exception reply within 0.3 s";
      EXPECT_EQ((r[0] << 8) | r[1], tid);
      EXPECT_EQ(r[7], c.function);
      EXPECT_EQ(r[8], c.code);
    }
  }
  const auto version = read_request(1, 0, 0xFF, mm::kMapVersionReg, 1);  // the connection is still served
  ASSERT_EQ(::send(fd, version.data(), version.size(), MSG_NOSIGNAL), static_cast<ssize_t>(version.size()));
  EXPECT_EQ(reply(fd, 0.3).size(), 11U);
  ::close(fd);
}

// fault 5: a host that died after `start` left the drive playing with no one listening. The
// watchdog (2 s by default) stops it with fault communication_lost; the samples recorded before
// it are still delivered, then the fault. Issue 47: another client polling meanwhile kept the
// watchdog from tripping; the watchdog now watches the client that started the trajectory.
TEST(DriveHostileClients, ADrivePlayingForNoOneStopsOnItsWatchdog) {
  std::string error;
  auto drive = ModbusDrive::connect(uri(), &error);
  ASSERT_NE(drive, nullptr) << error;
  auto poller = ModbusDrive::connect(uri(), &error);
  ASSERT_NE(poller, nullptr) << error;
  ASSERT_NO_FATAL_FAILURE(start_one_harmonic_run(*drive, 0.1, 100));
  dyncal::linux_port::DriveInfo info;
  ASSERT_EQ(drive->read_info(info), PortStatus::ok);
  EXPECT_EQ(info.state, mm::DriveState::playing);
  for (int k = 0; k < 13; ++k) {  // the host is silent for more than the watchdog; a poller is not
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    ASSERT_EQ(poller->read_info(info), PortStatus::ok) << poller->error();
  }
  ASSERT_EQ(drive->read_info(info), PortStatus::ok);
  EXPECT_EQ(info.state, mm::DriveState::fault);
  EXPECT_EQ(info.fault, mm::DriveFault::communication_lost);
  EXPECT_GT(info.fault_value, 2.0);
  EXPECT_NE(dyncal::linux_port::describe_fault(info).find("communication lost"), std::string::npos);
  // Everything recorded before the stop is delivered, then the fault.
  dyncal::port::DriveSample block[16];
  long received = 0;
  PortStatus st = PortStatus::ok;
  for (int guard = 0; guard < 100000; ++guard) {
    int n = 0;
    st = drive->read(block, 16, &n);
    received += n;
    if (st != PortStatus::ok && st != PortStatus::no_data) break;
  }
  EXPECT_EQ(st, PortStatus::device_fault) << drive->error();
  EXPECT_GT(received, 0);
  EXPECT_LT(received, 1000000);
  EXPECT_EQ(drive->start(), PortStatus::rejected);  // in fault: only the reset command clears it
  EXPECT_EQ(drive->reset(), PortStatus::ok) << drive->error();
  ASSERT_EQ(drive->read_info(info), PortStatus::ok);
  EXPECT_EQ(info.state,
            mm::DriveState::idle);  // the run would have been 10^6 samples (the lockstep ring holds far fewer)
}

}  // namespace
