// lib/'s register server (dyncal/drive/register_server.hpp) on a drive of its own, with the time in
// the test's hands: the rules whose truth is a time or an identity the loopback tests cannot set
// exactly — a staging session lasts modbus_map::kSessionSeconds and belongs to its client; a refused
// write changes no register; the run's owner alone acknowledges; a commit hands the drive the bytes
// staged, and the result registers show the drive's verdict. The Linux drive's whole server is
// tested against libmodbus in test_drive_modbus, the firmware's in the Cortex-M images.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

#include "dyncal/drive/register_server.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace register_server_suite {

namespace mm = dyncal::modbus_map;
using dyncal::drive::Microseconds;
using dyncal::drive::ModbusException;

/// A drive that records what the server asks of it.
struct RecordingDrive {
  mm::DriveState state_ = mm::DriveState::idle;
  std::uint32_t acked_ = 0, produced_ = 0;
  int starts = 0;
  std::vector<std::uint8_t> committed;
  dyncal::TableStatus verdict = dyncal::TableStatus::ok;

  mm::DriveState state() const { return state_; }
  std::uint32_t acked() const { return acked_; }
  std::uint32_t produced() const { return produced_; }
  long ring_capacity_samples() const { return 1000; }
  long run_samples(double periods, double period_s, double fs) const {
    return static_cast<long>(periods * period_s * fs);
  }
  double control_rate_hz() const { return 1000; }
  void ack(std::uint32_t seq) { acked_ = seq; }
  bool start(mm::Command, const dyncal::drive::RunSettings&, const dyncal::drive::MonitorSettings&) {
    ++starts;
    state_ = mm::DriveState::playing;
    produced_ = 40;
    return true;
  }
  void stop() { state_ = mm::DriveState::finished; }
  void reset() {}
  dyncal::TableStatus commit(const std::uint8_t* bytes, int size) {
    committed.assign(bytes, bytes + size);
    return verdict;
  }
  void publish_inputs(std::uint16_t* in) const { in[mm::kStateReg] = static_cast<std::uint16_t>(state_); }
  void publish_window(std::uint16_t* w) const {
    for (int k = 0; k < mm::kRingWords; ++k) w[k] = 0;
  }
};

using Bytes = std::vector<std::uint8_t>;
constexpr Microseconds kSecond = 1000000;

struct Fixture {
  RecordingDrive drive;
  dyncal::drive::RegisterServer<RecordingDrive> server{drive, 1000.0};

  Bytes ask(int client, Microseconds now, Bytes pdu) {
    std::uint8_t reply[dyncal::drive::kMaxPduBytes];
    const auto r = server.answer(pdu.data(), pdu.size(), client, now, reply);
    return Bytes(reply, reply + r.reply_bytes);
  }
  Bytes write1(int client, Microseconds now, int address, int value) {
    return ask(client, now,
               {0x06, static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
                static_cast<std::uint8_t>(value >> 8), static_cast<std::uint8_t>(value)});
  }
  int read1(bool input, int address) {
    const Bytes r = ask(9, 0,
                        {static_cast<std::uint8_t>(input ? 0x04 : 0x03), static_cast<std::uint8_t>(address >> 8),
                         static_cast<std::uint8_t>(address), 0, 1});
    return r.size() == 4 ? (r[2] << 8) | r[3] : -1;
  }
};

Bytes refused(int function, ModbusException e) {
  return {static_cast<std::uint8_t>(function | 0x80), static_cast<std::uint8_t>(e)};
}

TEST(RegisterServer, AStagingSessionLastsItsSecondsAndBelongsToItsClient) {
  Fixture f;
  const Microseconds session = static_cast<Microseconds>(mm::kSessionSeconds * kSecond);
  // Locked: staging is refused (01) and changes nothing.
  EXPECT_EQ(f.write1(1, 0, mm::kStagingSizeReg, 10), refused(0x06, ModbusException::illegal_function));
  EXPECT_EQ(f.read1(false, mm::kStagingSizeReg), 0);
  EXPECT_EQ(f.write1(1, 0, mm::kUnlockReg, mm::kUnlockKey).size(), 5u);
  // Its own client stages until the session's end; another client does not, nor takes it over.
  EXPECT_EQ(f.write1(1, session - 1, mm::kStagingSizeReg, 10).size(), 5u);
  EXPECT_EQ(f.write1(2, 1, mm::kStagingSizeReg, 12), refused(0x06, ModbusException::illegal_function));
  EXPECT_EQ(f.write1(2, 1, mm::kUnlockReg, mm::kUnlockKey), refused(0x06, ModbusException::server_device_busy));
  EXPECT_TRUE(f.server.holds_a_role(1, session - 1));
  EXPECT_FALSE(f.server.holds_a_role(1, session));
  EXPECT_EQ(f.write1(1, session, mm::kStagingSizeReg, 11), refused(0x06, ModbusException::illegal_function));
  EXPECT_EQ(f.read1(false, mm::kStagingSizeReg), 10);
  // Once it has ended, another client opens its own, which starts empty.
  EXPECT_EQ(f.write1(2, session, mm::kUnlockReg, mm::kUnlockKey).size(), 5u);
  EXPECT_EQ(f.read1(false, mm::kStagingSizeReg), 0);
  // A closed connection ends its session at once.
  f.server.client_closed(2);
  EXPECT_EQ(f.write1(2, session + 1, mm::kStagingSizeReg, 4), refused(0x06, ModbusException::illegal_function));
}

TEST(RegisterServer, ACommitHandsTheDriveTheStagedBytesAndShowsItsVerdict) {
  Fixture f;
  ASSERT_EQ(f.write1(1, 0, mm::kUnlockReg, mm::kUnlockKey).size(), 5u);
  // 16: staging_size 3 and the bytes 0xA1 0xB2 0xC3 (two per register, the first high).
  EXPECT_EQ(f.ask(1, 1, {0x10, 0x01, 0x2C, 0x00, 0x03, 0x06, 0x00, 0x03, 0xA1, 0xB2, 0xC3, 0x00}).size(), 5u);
  f.drive.verdict = dyncal::TableStatus::bad_crc;
  EXPECT_EQ(f.write1(1, 2, mm::kCommandReg, static_cast<int>(mm::Command::commit_table)).size(), 5u);
  EXPECT_EQ(f.drive.committed, (Bytes{0xA1, 0xB2, 0xC3}));
  EXPECT_EQ(f.read1(true, mm::kCommitResultReg), static_cast<int>(dyncal::TableStatus::bad_crc));
  EXPECT_EQ(f.read1(true, mm::kCommitCounterReg), 1);
  // The commit ended the session: a second commit is refused and hands the drive nothing.
  f.drive.committed.clear();
  EXPECT_EQ(f.write1(1, 3, mm::kCommandReg, static_cast<int>(mm::Command::commit_table)),
            refused(0x06, ModbusException::illegal_function));
  EXPECT_TRUE(f.drive.committed.empty());
  EXPECT_EQ(f.read1(true, mm::kCommitCounterReg), 1);
}

TEST(RegisterServer, TheRunsOwnerAloneAcknowledgesAndSettingsWaitForTheRunsEnd) {
  Fixture f;
  EXPECT_EQ(f.write1(1, 0, mm::kCommandReg, static_cast<int>(mm::Command::start)).size(), 5u);
  EXPECT_EQ(f.drive.starts, 1);
  EXPECT_EQ(f.server.started(), 0u);
  // Another client's ack is refused (06) and frees nothing; the owner's beyond produced is 03.
  EXPECT_EQ(f.ask(2, 5, {0x10, 0x00, 0x02, 0x00, 0x02, 0x04, 0x00, 0x00, 0x00, 0x0A}),
            refused(0x10, ModbusException::server_device_busy));
  EXPECT_EQ(f.drive.acked_, 0u);
  EXPECT_EQ(f.ask(1, 6, {0x10, 0x00, 0x02, 0x00, 0x02, 0x04, 0x00, 0x00, 0x00, 41}),
            refused(0x10, ModbusException::illegal_data_value));
  EXPECT_EQ(f.ask(1, 7, {0x10, 0x00, 0x02, 0x00, 0x02, 0x04, 0x00, 0x00, 0x00, 40}).size(), 5u);
  EXPECT_EQ(f.drive.acked_, 40u);
  EXPECT_EQ(f.server.owner_last_request(), 7u);
  // Another client's requests do not feed the watchdog.
  f.read1(true, mm::kStateReg);
  EXPECT_EQ(f.server.owner_last_request(), 7u);
  // While it plays: the settings are busy (06), a second start too; the registers keep their values.
  const int periods = f.read1(false, mm::kPeriodsReg);
  EXPECT_EQ(f.write1(1, 8, mm::kPeriodsReg, 3), refused(0x06, ModbusException::server_device_busy));
  EXPECT_EQ(f.write1(1, 8, mm::kCommandReg, static_cast<int>(mm::Command::start)),
            refused(0x06, ModbusException::server_device_busy));
  EXPECT_EQ(f.read1(false, mm::kPeriodsReg), periods);
  EXPECT_EQ(f.drive.starts, 1);
  EXPECT_EQ(f.write1(1, 9, mm::kCommandReg, static_cast<int>(mm::Command::stop)).size(), 5u);
  EXPECT_EQ(f.write1(1, 9, mm::kPeriodsReg, 3).size(), 5u);
  EXPECT_EQ(f.read1(false, mm::kPeriodsReg), 3);
}

TEST(RegisterServer, ARefusedMultipleWriteChangesNoRegister) {
  Fixture f;
  // harmonics 3, periods 0: the whole write is refused (03) and harmonics keeps its 5.
  EXPECT_EQ(f.ask(1, 0, {0x10, 0x00, 0x08, 0x00, 0x02, 0x04, 0x00, 0x03, 0x00, 0x00}),
            refused(0x10, ModbusException::illegal_data_value));
  EXPECT_EQ(f.read1(false, mm::kHarmonicsReg), 5);
  EXPECT_EQ(f.read1(false, mm::kPeriodsReg), 2);
  // Half of an f32 (omega_f's high word alone) is an illegal address.
  EXPECT_EQ(f.write1(1, 0, mm::kOmegaFReg + 1, 0), refused(0x06, ModbusException::illegal_data_address));
}

}  // namespace register_server_suite
}  // namespace
