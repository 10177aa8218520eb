// A drive killed (SIGKILL) at random moments of a flash restarts with the old or the new table,
// never a mix: the simulated flash is replaced atomically. Each drive is a real process serving
// Modbus TCP on loopback, ready by its ready file, stopped by PID.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>
#include <vector>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "support/encoded_table.hpp"
#include "support/test_paths.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using dyncal::linux_port::ModbusDrive;
using Model = dyncal::IdentificationModel<dyncal::generated::er20::Robot, dyncal::kFrictionEq7>;

struct DriveProcess {
  pid_t pid = -1;
  std::string uri;
};

DriveProcess start_drive(const fs::path& dir, int delay_ms) {
  const fs::path ready = dir / "drive.ready";
  fs::remove(ready);
  const std::string table = (dir / "drive.table").string(), ready_s = ready.string(), delay = std::to_string(delay_ms);
  std::vector<std::string> args = {dyncal::test::dyncal_binary(),
                                   "drive",
                                   "--tcp",
                                   "127.0.0.1:0",
                                   "--lockstep",
                                   "--table",
                                   table,
                                   "--ready-file",
                                   ready_s,
                                   "--flash-delay-ms",
                                   delay};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  DriveProcess p;
  EXPECT_EQ(posix_spawn(&p.pid, argv[0], &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  // Readiness handshake: the drive writes its URI atomically once it serves requests.
  for (int i = 0; i < 3000 && !fs::exists(ready); ++i) {
    int status = 0;
    if (waitpid(p.pid, &status, WNOHANG) == p.pid) {
      ADD_FAILURE() << "drive exited before it was ready";
      return p;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::ifstream in(ready);
  std::getline(in, p.uri);
  return p;
}

void kill_drive(DriveProcess& p) {
  kill(p.pid, SIGKILL);
  int status = 0;
  waitpid(p.pid, &status, 0);
}

std::vector<std::uint8_t> active_bytes(const std::string& uri) {
  std::string error;
  auto d = ModbusDrive::connect(uri, &error);
  EXPECT_TRUE(d) << error;
  if (!d) return {};
  std::uint8_t b[dyncal::kTableMaxBytes];
  int size = 0;
  EXPECT_EQ(d->read_active_bytes(b, sizeof b, &size), dyncal::port::PortStatus::ok) << d->error();
  return std::vector<std::uint8_t>(b, b + size);
}

TEST(FlashKill, RestartAlwaysYieldsTheOldOrTheNewTable) {
  const fs::path dir = fs::temp_directory_path() / ("dyncal_flash_kill_" + std::to_string(getpid()));
  fs::create_directories(dir);
  dyncal::ParameterTable a, b;
  Model::ParamVector<double> phi = Model::ParamVector<double>::Constant(1.0);
  dyncal::make_table<Model>(phi, a);
  phi.setConstant(2.0);
  dyncal::make_table<Model>(phi, b);
  const auto bytes_a = dyncal::test::encoded_table(a), bytes_b = dyncal::test::encoded_table(b);
  constexpr int kDelayMs = 3;  // per 64 bytes written: a flash takes a few tens of ms

  // Table A, flashed to completion; measure how long a flash takes.
  DriveProcess p = start_drive(dir, kDelayMs);
  ASSERT_FALSE(p.uri.empty());
  std::string error;
  double flash_seconds = 0;
  {
    auto d = ModbusDrive::connect(p.uri, &error);
    ASSERT_TRUE(d) << error;
    dyncal::TableStatus reason;
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_EQ(d->write(a, &reason), dyncal::port::PortStatus::ok) << d->error();
    flash_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  kill_drive(p);

  std::mt19937 rng(2026);
  std::uniform_real_distribution<double> when(0.0, 1.3 * flash_seconds);
  int saw_old = 0, saw_new = 0;
  for (int round = 0; round < 20; ++round) {
    p = start_drive(dir, kDelayMs);
    ASSERT_FALSE(p.uri.empty());
    const auto old_bytes = active_bytes(p.uri);
    ASSERT_TRUE(old_bytes == bytes_a || old_bytes == bytes_b) << "round " << round;
    const dyncal::ParameterTable& next = old_bytes == bytes_a ? b : a;
    const auto& new_bytes = old_bytes == bytes_a ? bytes_b : bytes_a;
    std::thread flasher([&] {
      std::string e;
      auto d = ModbusDrive::connect(p.uri, &e);
      if (!d) return;
      dyncal::TableStatus reason;
      d->write(next, &reason);  // fails when the drive dies under it
    });
    std::this_thread::sleep_for(std::chrono::duration<double>(when(rng)));
    kill_drive(p);
    flasher.join();
    p = start_drive(dir, kDelayMs);
    ASSERT_FALSE(p.uri.empty());
    const auto after = active_bytes(p.uri);
    kill_drive(p);
    ASSERT_TRUE(after == old_bytes || after == new_bytes) << "round " << round << ": a mixed or default table";
    (after == old_bytes ? saw_old : saw_new) += 1;
  }
  // The random kill points covered both outcomes.
  EXPECT_GT(saw_old, 0);
  EXPECT_GT(saw_new, 0);
  fs::remove_all(dir);
}

}  // namespace

namespace {

// Issue 67: a flash store the drive cannot write (its folder gone: "cannot create ..." in its log)
// is reported as the store's failure, commit_result 11, not as the table's ("size does not match
// the parameter count"); the active table stays.
TEST(FlashKill, AStoreTheDriveCannotWriteIsNamedAndTheActiveTableStays) {
  const fs::path dir = fs::temp_directory_path() / ("dyncal_store_fail_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  DriveProcess p = start_drive(dir, 0);
  ASSERT_FALSE(p.uri.empty());
  const auto before = active_bytes(p.uri);
  fs::remove_all(dir);  // the store's folder: the next write cannot create its temporary file
  dyncal::ParameterTable t;
  dyncal::make_table<Model>(Model::ParamVector<double>::Constant(1.0), t);
  std::string error;
  auto d = ModbusDrive::connect(p.uri, &error);
  ASSERT_TRUE(d) << error;
  dyncal::TableStatus reason = dyncal::TableStatus::ok;
  EXPECT_EQ(d->write(t, &reason), dyncal::port::PortStatus::rejected) << d->error();
  EXPECT_EQ(reason, dyncal::TableStatus::store_failed) << dyncal::to_string(reason);
  EXPECT_EQ(active_bytes(p.uri), before);
  kill_drive(p);
}

}  // namespace
