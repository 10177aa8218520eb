// The simulated drive over Modbus TCP on loopback (a real libmodbus server started by a CTest
// fixture): register round trips, Modbus exceptions, table flash checks.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <thread>
#include <vector>

#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/generated/tx40/robot.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_port/modbus_drive.hpp"
#include "support/drive_uri.hpp"

namespace {

namespace mm = dyncal::modbus_map;
using dyncal::linux_port::ModbusDrive;
using Er20 = dyncal::generated::er20::Robot;

class DriveModbus : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string uri = fixture_drive_uri("DYNCAL_DRIVE_READY");
    ASSERT_FALSE(uri.empty()) << "DYNCAL_DRIVE_READY not set or empty: run through ctest";
    std::string error;
    drive_ = ModbusDrive::connect(uri, &error);
    ASSERT_TRUE(drive_) << error;
  }
  // A libmodbus context of our own for raw requests (exceptions are visible in errno).
  modbus_t* raw() {
    const std::string uri = fixture_drive_uri("DYNCAL_DRIVE_READY");
    const auto colon = uri.rfind(':');
    modbus_t* ctx = modbus_new_tcp(uri.substr(6, colon - 6).c_str(), std::stoi(uri.substr(colon + 1)));
    EXPECT_EQ(modbus_connect(ctx), 0);
    return ctx;
  }
  std::unique_ptr<ModbusDrive> drive_;
};

TEST_F(DriveModbus, IdentifiesItself) {
  dyncal::linux_port::DriveInfo info;
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok) << drive_->error();
  EXPECT_EQ(info.map_version, mm::kMapVersion);
  EXPECT_EQ(info.num_joints, 6);
  EXPECT_EQ(info.robot_id, Er20::kRobotId);
}

TEST_F(DriveModbus, EveryRegisterTypeRoundTrips) {
  // u16
  const std::uint16_t harmonics = 3;
  ASSERT_EQ(drive_->write_holding(mm::kHarmonicsReg, 1, &harmonics), dyncal::port::PortStatus::ok) << drive_->error();
  std::uint16_t back = 0;
  ASSERT_EQ(drive_->read_holding(mm::kHarmonicsReg, 1, &back), dyncal::port::PortStatus::ok);
  EXPECT_EQ(back, 3);
  // f32 (two registers, high word first)
  std::uint16_t f[2], fb[2];
  mm::set_f32(f, 0.125f);
  ASSERT_EQ(drive_->write_holding(mm::kOmegaFReg, 2, f), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->read_holding(mm::kOmegaFReg, 2, fb), dyncal::port::PortStatus::ok);
  EXPECT_EQ(mm::get_f32(fb), 0.125f);
  // f32 array across more than one Modbus frame
  std::vector<std::uint16_t> c(mm::kCoefficientWords), cb(mm::kCoefficientWords);
  for (int k = 0; k < mm::kCoefficientWords / 2; ++k) mm::set_f32(&c[2 * k], 0.001f * static_cast<float>(k));
  ASSERT_EQ(drive_->write_holding(mm::kCoefficientsReg, mm::kCoefficientWords, c.data()), dyncal::port::PortStatus::ok)
      << drive_->error();
  ASSERT_EQ(drive_->read_holding(mm::kCoefficientsReg, 120, cb.data()), dyncal::port::PortStatus::ok);
  ASSERT_EQ(drive_->read_holding(mm::kCoefficientsReg + 120, mm::kCoefficientWords - 120, cb.data() + 120),
            dyncal::port::PortStatus::ok);
  EXPECT_EQ(c, cb);
  // u32 (ack: the only legal value while nothing was produced is the produced count)
  dyncal::linux_port::DriveInfo info;
  ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
  std::uint16_t a[2], ab[2];
  mm::set_u32(a, info.produced);
  ASSERT_EQ(drive_->write_holding(mm::kAckReg, 2, a), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->read_holding(mm::kAckReg, 2, ab), dyncal::port::PortStatus::ok);
  EXPECT_EQ(mm::get_u32(ab), info.produced);
  // bytes (staging bank; a session first)
  const std::uint16_t key = mm::kUnlockKey;
  ASSERT_EQ(drive_->write_holding(mm::kUnlockReg, 1, &key), dyncal::port::PortStatus::ok) << drive_->error();
  std::vector<std::uint16_t> bytes(100), bb(100);
  for (int k = 0; k < 100; ++k) bytes[k] = static_cast<std::uint16_t>(0xA500 + k);
  ASSERT_EQ(drive_->write_holding(mm::kStagingTableReg, 100, bytes.data()), dyncal::port::PortStatus::ok);
  ASSERT_EQ(drive_->read_holding(mm::kStagingTableReg, 100, bb.data()), dyncal::port::PortStatus::ok);
  EXPECT_EQ(bytes, bb);
  // every input field is readable
  for (const auto& field : mm::kRegisterMap) {
    if (field.bank != mm::Bank::input) continue;
    std::vector<std::uint16_t> r(field.words);
    for (int done = 0; done < field.words; done += 120) {
      const int n = std::min(120, field.words - done);
      EXPECT_EQ(drive_->read_input(field.address + done, n, r.data() + done), dyncal::port::PortStatus::ok)
          << field.name << ": " << drive_->error();
    }
  }
}

TEST_F(DriveModbus, IllegalAddressesAndValuesGetModbusExceptions) {
  modbus_t* ctx = raw();
  std::uint16_t r[4];
  EXPECT_EQ(modbus_read_registers(ctx, 250, 1, r), -1);  // hole between coefficients and staging
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_input_registers(ctx, mm::kPayloadStateReg - 1, 2, r), -1);  // hole before the payload
  EXPECT_EQ(errno, EMBXILADD);
  r[0] = r[1] = 0;
  EXPECT_EQ(modbus_write_registers(ctx, mm::kRingReg, 2, r), -1);  // the ring window is read-only
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_and_read_registers(ctx, mm::kRingReg + 4, 2, r, mm::kRingReg, 8, r), -1);
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_registers(ctx, mm::kHoldingWords, 1, r), -1);  // beyond the map
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_register(ctx, mm::kSampleRateReg + 1, 0), -1);  // half of a float
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_write_register(ctx, mm::kCommandReg, 77), -1);  // unknown command
  EXPECT_EQ(errno, EMBXILVAL);
  EXPECT_EQ(modbus_write_register(ctx, mm::kHarmonicsReg, 0), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  EXPECT_EQ(modbus_write_register(ctx, mm::kHarmonicsReg, 9), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  // Through the port: an exception response is `rejected` (the drive answered and refused), named.
  const std::uint16_t nine = 9;
  EXPECT_EQ(drive_->write_holding(mm::kHarmonicsReg, 1, &nine), dyncal::port::PortStatus::rejected);
  EXPECT_NE(drive_->error().find("Illegal data value"), std::string::npos) << drive_->error();
  std::uint16_t f[2];
  mm::set_f32(f, 5000.0f);  // sample rate above 1 kHz
  EXPECT_EQ(modbus_write_registers(ctx, mm::kSampleRateReg, 2, f), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  mm::set_f32(f, 300.0f);  // does not divide the 1 kHz control rate
  EXPECT_EQ(modbus_write_registers(ctx, mm::kSampleRateReg, 2, f), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  mm::set_f32(f, std::nanf(""));
  EXPECT_EQ(modbus_write_registers(ctx, mm::kCoefficientsReg, 2, f), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  std::uint16_t a[2];
  mm::set_u32(a, 0xFFFFFFF0u);  // acknowledging samples never produced
  EXPECT_EQ(modbus_write_registers(ctx, mm::kAckReg, 2, a), -1);
  EXPECT_EQ(errno, EMBXILVAL);
  std::uint8_t coils[1];
  EXPECT_EQ(modbus_read_bits(ctx, 0, 1, coils), -1);  // the drive has no coils
  EXPECT_EQ(errno, EMBXILADD);
  // An unsupported function code (0x2B, encapsulated interface) gets ILLEGAL FUNCTION.
  const std::uint8_t req[] = {0xFF, 0x2B};  // no data: libmodbus frames unknown functions by code
  ASSERT_GT(modbus_send_raw_request(ctx, req, sizeof req), 0);
  std::uint8_t rsp[MODBUS_TCP_MAX_ADU_LENGTH];
  // The raw API returns the frame as is: MBAP header (7 bytes), function | 0x80, exception code.
  ASSERT_EQ(modbus_receive_confirmation(ctx, rsp), 9);
  EXPECT_EQ(rsp[7], 0x2B | 0x80);
  EXPECT_EQ(rsp[8], MODBUS_EXCEPTION_ILLEGAL_FUNCTION);
  // The legal values are still accepted afterwards.
  EXPECT_EQ(modbus_write_register(ctx, mm::kHarmonicsReg, 5), 1);
  modbus_close(ctx);
  modbus_free(ctx);
}

// Stages raw bytes and commits through registers; returns the drive's verdict.
dyncal::TableStatus commit_raw(ModbusDrive& d, const std::uint8_t* bytes, int size) {
  std::vector<std::uint16_t> regs(1 + (size + 1) / 2);
  regs[0] = static_cast<std::uint16_t>(size);
  mm::bytes_to_regs(bytes, size, regs.data() + 1);
  std::uint16_t before = 0;
  EXPECT_EQ(d.read_input(mm::kCommitCounterReg, 1, &before), dyncal::port::PortStatus::ok);
  const std::uint16_t key = mm::kUnlockKey;
  EXPECT_EQ(d.write_holding(mm::kUnlockReg, 1, &key), dyncal::port::PortStatus::ok) << d.error();
  EXPECT_EQ(d.write_holding(mm::kStagingSizeReg, static_cast<int>(regs.size()), regs.data()),
            dyncal::port::PortStatus::ok)
      << d.error();
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::commit_table);
  EXPECT_EQ(d.write_holding(mm::kCommandReg, 1, &cmd), dyncal::port::PortStatus::ok) << d.error();
  std::uint16_t r[2] = {0, before};
  for (int k = 0; k < 10000 && r[1] == before; ++k) {
    EXPECT_EQ(d.read_input(mm::kCommitResultReg, 2, r), dyncal::port::PortStatus::ok);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_NE(r[1], before) << "the commit never completed";
  return static_cast<dyncal::TableStatus>(r[0]);
}

TEST_F(DriveModbus, FlashRejectsBadTablesAndKeepsTheActiveOne) {
  using Model = dyncal::IdentificationModel<Er20, dyncal::kFrictionEq7 | dyncal::term::rotor_inertia>;
  std::uint8_t before[dyncal::kTableMaxBytes], after[dyncal::kTableMaxBytes];
  int before_size = 0, after_size = 0;
  ASSERT_EQ(drive_->read_active_bytes(before, sizeof before, &before_size), dyncal::port::PortStatus::ok)
      << drive_->error();

  Model::ParamVector<double> phi = Model::ParamVector<double>::Constant(0.5);
  dyncal::ParameterTable good;
  dyncal::make_table<Model>(phi, good);
  std::uint8_t bytes[dyncal::kTableMaxBytes];
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(good, bytes, sizeof bytes, &size), dyncal::TableStatus::ok);

  std::uint8_t bad[dyncal::kTableMaxBytes];
  std::memcpy(bad, bytes, size);
  bad[size - 1] ^= 0x5A;
  EXPECT_EQ(commit_raw(*drive_, bad, size), dyncal::TableStatus::bad_crc);

  auto other = good;
  other.robot_id = dyncal::generated::tx40::kRobotId;
  dyncal::TableStatus reason;
  EXPECT_EQ(drive_->write(other, &reason), dyncal::port::PortStatus::rejected);
  EXPECT_EQ(reason, dyncal::TableStatus::wrong_robot);

  auto range = good;
  range.values[Model::column(dyncal::term::coulomb, 0)] = -3.0f;
  EXPECT_EQ(drive_->write(range, &reason), dyncal::port::PortStatus::rejected);
  EXPECT_EQ(reason, dyncal::TableStatus::out_of_range);
  range = good;
  range.values[2] = 1e9f;
  EXPECT_EQ(drive_->write(range, &reason), dyncal::port::PortStatus::rejected);
  EXPECT_EQ(reason, dyncal::TableStatus::out_of_range);

  auto model = good;
  model.model_id = dyncal::term::power;  // a model the drive does not run
  EXPECT_EQ(drive_->write(model, &reason), dyncal::port::PortStatus::rejected);
  EXPECT_EQ(reason, dyncal::TableStatus::wrong_model);

  ASSERT_EQ(drive_->read_active_bytes(after, sizeof after, &after_size), dyncal::port::PortStatus::ok);
  ASSERT_EQ(after_size, before_size);
  EXPECT_EQ(std::memcmp(before, after, before_size), 0) << "a rejected table changed the active one";

  // A good table is accepted, read back identical (write() compares) and reported active.
  ASSERT_EQ(drive_->write(good, &reason), dyncal::port::PortStatus::ok) << drive_->error() << " " << to_string(reason);
  dyncal::ParameterTable active;
  ASSERT_EQ(drive_->read(active, &reason), dyncal::port::PortStatus::ok);
  EXPECT_EQ(active.model_id, good.model_id);
  EXPECT_EQ(active.values[5], good.values[5]);
}

// Access (docs/modbus.md "Access and states"): staging and commit only in a session the writing
// connection opened with the documented key; a wrong key is refused; the session belongs to its
// connection and ends with the commit; start while playing is refused (it would jump the arm).
TEST_F(DriveModbus, StagingNeedsASessionOfItsOwnConnectionAndStartWhilePlayingIsRefused) {
  modbus_t* a = raw();
  modbus_t* b = raw();
  EXPECT_EQ(modbus_write_register(a, mm::kStagingSizeReg, 10), -1);  // locked
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_write_register(a, mm::kCommandReg, static_cast<int>(mm::Command::commit_table)), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  EXPECT_EQ(modbus_write_register(a, mm::kUnlockReg, 0x1234), -1);  // wrong key
  EXPECT_EQ(errno, EMBXILVAL);
  ASSERT_EQ(modbus_write_register(a, mm::kUnlockReg, mm::kUnlockKey), 1) << modbus_strerror(errno);
  std::uint16_t r = 99;
  ASSERT_EQ(modbus_read_registers(a, mm::kUnlockReg, 1, &r), 1);
  EXPECT_EQ(r, 0);  // the key is not readable back
  EXPECT_EQ(modbus_write_register(a, mm::kStagingSizeReg, 10), 1) << modbus_strerror(errno);
  EXPECT_EQ(modbus_write_register(b, mm::kStagingSizeReg, 10), -1);  // another connection: still locked
  EXPECT_EQ(errno, EMBXILFUN);
  // A commit (of a bad staging: 10 bytes) ends the session.
  ASSERT_EQ(modbus_write_register(a, mm::kCommandReg, static_cast<int>(mm::Command::commit_table)), 1);
  dyncal::linux_port::DriveInfo info;
  for (int k = 0; k < 100; ++k) {  // the commit completes after its answer
    ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
    std::uint16_t res[2];
    ASSERT_EQ(drive_->read_input(mm::kCommitResultReg, 2, res), dyncal::port::PortStatus::ok);
    if (res[0] != 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(modbus_write_register(a, mm::kStagingSizeReg, 10), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  // Start while playing: busy.
  dyncal::linux_port::Trajectory t;
  t.f_f = 0.1;
  t.harmonics = 1;
  ASSERT_EQ(drive_->write_trajectory(t, 100, 1000), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->start(), dyncal::port::PortStatus::ok) << drive_->error();
  EXPECT_EQ(drive_->start(), dyncal::port::PortStatus::rejected);
  EXPECT_NE(drive_->error().find("busy"), std::string::npos) << drive_->error();
  ASSERT_EQ(modbus_write_register(a, mm::kUnlockReg, mm::kUnlockKey), 1);
  EXPECT_EQ(modbus_write_register(a, mm::kStagingSizeReg, 10), -1);  // staging while playing: busy
  EXPECT_EQ(errno, EMBXSBUSY);
  ASSERT_EQ(drive_->stop(), dyncal::port::PortStatus::ok);
  modbus_close(a);
  modbus_free(a);
  modbus_close(b);
  modbus_free(b);
}

// Issue 47: a second connection could take over a session (writing the key again) and commit the
// table the first one had staged. One session at a time (06 busy while another is open), and a new
// session starts with nothing staged: a commit writes only what its own connection staged.
TEST_F(DriveModbus, ACommitWritesOnlyWhatItsOwnSessionStaged) {
  using Model = dyncal::IdentificationModel<Er20, dyncal::kFrictionEq7 | dyncal::term::rotor_inertia>;
  std::uint8_t before[dyncal::kTableMaxBytes], after[dyncal::kTableMaxBytes];
  int before_size = 0, after_size = 0;
  ASSERT_EQ(drive_->read_active_bytes(before, sizeof before, &before_size), dyncal::port::PortStatus::ok);
  dyncal::ParameterTable staged;
  dyncal::make_table<Model>(Model::ParamVector<double>::Constant(0.25), staged);
  std::uint8_t bytes[dyncal::kTableMaxBytes];
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(staged, bytes, sizeof bytes, &size), dyncal::TableStatus::ok);
  ASSERT_TRUE(before_size != size || std::memcmp(before, bytes, static_cast<size_t>(size)) != 0);
  std::vector<std::uint16_t> regs(1 + static_cast<size_t>(size + 1) / 2);
  regs[0] = static_cast<std::uint16_t>(size);
  mm::bytes_to_regs(bytes, size, regs.data() + 1);

  modbus_t* a = raw();
  modbus_t* b = raw();
  ASSERT_EQ(modbus_write_register(a, mm::kUnlockReg, mm::kUnlockKey), 1) << modbus_strerror(errno);
  for (size_t done = 0; done < regs.size();) {  // a stages a valid table, and does not commit it
    const int n = static_cast<int>(std::min<size_t>(regs.size() - done, MODBUS_MAX_WRITE_REGISTERS));
    ASSERT_EQ(modbus_write_registers(a, mm::kStagingSizeReg + static_cast<int>(done), n, regs.data() + done), n)
        << modbus_strerror(errno);
    done += static_cast<size_t>(n);
  }
  EXPECT_EQ(modbus_write_register(b, mm::kUnlockReg, mm::kUnlockKey), -1);  // a's session is open: busy
  EXPECT_EQ(errno, EMBXSBUSY);
  // The host's flash says whose the session is, not just "busy" (issue 67).
  dyncal::TableStatus why = dyncal::TableStatus::ok;
  EXPECT_NE(drive_->write(staged, &why), dyncal::port::PortStatus::ok);
  EXPECT_NE(drive_->error().find("another connection holds the drive's staging session"), std::string::npos)
      << drive_->error();
  EXPECT_EQ(modbus_write_register(b, mm::kCommandReg, static_cast<int>(mm::Command::commit_table)), -1);
  EXPECT_EQ(errno, EMBXILFUN);
  // a leaves without committing; b's own session starts empty, so its commit has nothing to write.
  modbus_close(a);
  modbus_free(a);
  bool unlocked = false;
  for (int k = 0; k < 200 && !unlocked; ++k) {  // the drive sees a's close at its next poll
    unlocked = modbus_write_register(b, mm::kUnlockReg, mm::kUnlockKey) == 1;
    if (!unlocked) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_TRUE(unlocked) << modbus_strerror(errno);
  std::uint16_t staged_size = 99;
  ASSERT_EQ(modbus_read_registers(b, mm::kStagingSizeReg, 1, &staged_size), 1);
  EXPECT_EQ(staged_size, 0);
  std::uint16_t counter[2] = {0, 0};
  ASSERT_EQ(drive_->read_input(mm::kCommitResultReg, 2, counter), dyncal::port::PortStatus::ok);
  const std::uint16_t commits_before = counter[1];
  ASSERT_EQ(modbus_write_register(b, mm::kCommandReg, static_cast<int>(mm::Command::commit_table)), 1);
  for (int k = 0; k < 1000 && counter[1] == commits_before; ++k) {
    ASSERT_EQ(drive_->read_input(mm::kCommitResultReg, 2, counter), dyncal::port::PortStatus::ok);
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  ASSERT_NE(counter[1], commits_before) << "the commit never completed";
  EXPECT_NE(static_cast<dyncal::TableStatus>(counter[0]), dyncal::TableStatus::ok);
  ASSERT_EQ(drive_->read_active_bytes(after, sizeof after, &after_size), dyncal::port::PortStatus::ok);
  ASSERT_EQ(after_size, before_size);
  EXPECT_EQ(std::memcmp(before, after, static_cast<size_t>(before_size)), 0)
      << "another connection's staged table became active";
  modbus_close(b);
  modbus_free(b);
}

TEST_F(DriveModbus, CollisionMonitorIsSetInASessionAndAResidualBeyondItStopsTheRunWithFault5) {
  modbus_t* a = raw();
  std::uint16_t regs[2];
  mm::set_f32(regs, 200.0f);
  EXPECT_EQ(modbus_write_registers(a, mm::kMonitorGainReg, 2, regs), -1);  // no session: locked
  EXPECT_EQ(errno, EMBXILFUN);
  modbus_close(a);
  modbus_free(a);
  dyncal::linux_port::DriveMonitor m;
  m.gain = 2000;  // K dt = 2 at the 1 kHz control rate
  EXPECT_EQ(drive_->write_monitor(m), dyncal::port::PortStatus::rejected);
  m.gain = 5;  // a velocity window of 401 periods
  EXPECT_EQ(drive_->write_monitor(m), dyncal::port::PortStatus::rejected);
  m.gain = 200;
  m.threshold[1] = -1;
  EXPECT_EQ(drive_->write_monitor(m), dyncal::port::PortStatus::rejected);
  m.threshold[1] = 0;
  m.mean[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(drive_->write_monitor(m), dyncal::port::PortStatus::rejected);
  // Thresholds far below the torque noise: the first observed period trips.
  m.mean[2] = 0.5;
  for (int j = 0; j < 6; ++j) m.threshold[static_cast<size_t>(j)] = 1e-6;
  m.band.fill(1e-3);
  ASSERT_EQ(drive_->write_monitor(m), dyncal::port::PortStatus::ok) << drive_->error();
  std::uint16_t back[2 + 6 * mm::kMaxJoints];
  ASSERT_EQ(drive_->read_holding(mm::kMonitorGainReg, 2 + 6 * mm::kMaxJoints, back), dyncal::port::PortStatus::ok);
  EXPECT_EQ(mm::get_f32(back), 200.0f);
  EXPECT_EQ(mm::get_f32(back + (mm::kMonitorMeanReg - mm::kMonitorGainReg) + 4), 0.5f);
  dyncal::linux_port::Trajectory t;  // zero coefficients: the arm holds q0 = 0
  t.f_f = 0.1;
  t.harmonics = 1;
  ASSERT_EQ(drive_->write_trajectory(t, 1, 1000), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->start(), dyncal::port::PortStatus::ok) << drive_->error();
  dyncal::linux_port::DriveInfo info;
  for (int k = 0; k < 200; ++k) {
    ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
    if (info.state != mm::DriveState::playing) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(info.state, mm::DriveState::fault);
  EXPECT_EQ(info.fault, mm::DriveFault::collision);
  EXPECT_GE(info.fault_joint, 1);
  EXPECT_LE(info.fault_joint, 6);
  EXPECT_GT(std::abs(info.fault_value), 1e-6);
  EXPECT_LT(info.sim_time, 0.1);  // the window's 11 periods, then the first residual
  EXPECT_NE(dyncal::linux_port::describe_fault(info).find("collision: residual r - mean = "), std::string::npos)
      << dyncal::linux_port::describe_fault(info);
  mm::MonitorState state = mm::MonitorState::off;
  ASSERT_EQ(drive_->read_monitor_state(state), dyncal::port::PortStatus::ok);
  EXPECT_EQ(state, mm::MonitorState::watching);
  // In fault the settings are refused like a staging; after the reset the monitor is turned off.
  EXPECT_EQ(drive_->write_monitor({}), dyncal::port::PortStatus::rejected);
  ASSERT_EQ(drive_->reset(), dyncal::port::PortStatus::ok);
  ASSERT_EQ(drive_->write_monitor({}), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->start(), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->read_monitor_state(state), dyncal::port::PortStatus::ok);
  EXPECT_EQ(state, mm::MonitorState::off);
  ASSERT_EQ(drive_->stop(), dyncal::port::PortStatus::ok);
}

// Issue 67: the ring's samples are the run owner's. Another connection's ack (a monitoring tool
// reading the ring) is refused with 06 busy, and the owner's stream goes on undisturbed; it used to
// free the owner's unread samples and end its stream with "Illegal data value".
TEST_F(DriveModbus, AnotherConnectionsAckDoesNotDisturbTheRunOwner) {
  dyncal::linux_port::Trajectory t;  // zero coefficients: the arm holds q0 = 0
  t.f_f = 1;
  t.harmonics = 1;
  ASSERT_EQ(drive_->write_trajectory(t, 1, 1000), dyncal::port::PortStatus::ok) << drive_->error();
  ASSERT_EQ(drive_->start(), dyncal::port::PortStatus::ok) << drive_->error();
  dyncal::port::DriveSample block[mm::kMaxSamplesPerBlock];
  long received = 0;
  bool acked_by_other = false;
  modbus_t* other = raw();
  for (int k = 0; k < 100000; ++k) {
    int n = 0;
    const dyncal::port::PortStatus st = drive_->read(block, mm::kMaxSamplesPerBlock, &n);
    if (st == dyncal::port::PortStatus::end_of_stream) break;
    ASSERT_TRUE(st == dyncal::port::PortStatus::ok || st == dyncal::port::PortStatus::no_data) << drive_->error();
    received += n;
    if (received > 0 && !acked_by_other) {
      std::uint16_t ack[2];
      mm::set_u32(ack, static_cast<std::uint32_t>(received + 50));
      EXPECT_EQ(modbus_write_registers(other, mm::kAckReg, 2, ack), -1);
      EXPECT_EQ(errno, EMBXSBUSY);
      acked_by_other = true;
    }
  }
  modbus_close(other);
  modbus_free(other);
  EXPECT_TRUE(acked_by_other);
  EXPECT_EQ(received, 1000);
  EXPECT_EQ(drive_->lost(), 0U);
}

// Every monitor setting the drive acknowledges is the one it runs with (issue 67, symptom 1: a
// negative gain with every threshold 0 was answered OK and read back, while the next start tripped
// with the previous settings). Each hostile value goes into one field over settings that trip at
// once; then: acknowledged => read back as written and the run behaves by it (thresholds 0 where it
// was written: no trip); refused (exception 03) => the registers and the behaviour are the previous
// settings' (the run trips at once).
TEST_F(DriveModbus, EveryMonitorSettingTheDriveAcknowledgesIsTheOneItRuns) {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  const double hostile[] = {nan, inf, -inf, -1.0, -1e-30, 0.0, 1e-40, 3e38, 1e308, 200.0};
  dyncal::linux_port::DriveMonitor tripping;  // thresholds far below the torque noise
  tripping.gain = 200;
  for (int j = 0; j < 6; ++j) tripping.threshold[static_cast<size_t>(j)] = 1e-6;
  tripping.band.fill(1e-3);
  dyncal::linux_port::Trajectory t;  // zero coefficients: the arm holds q0 = 0
  t.f_f = 0.1;
  t.harmonics = 1;
  ASSERT_EQ(drive_->write_trajectory(t, 1, 1000), dyncal::port::PortStatus::ok) << drive_->error();
  constexpr int kWords = mm::kMonitorBandReg + 2 * mm::kMaxJoints - mm::kMonitorGainReg;
  int acknowledged = 0, refused = 0;
  for (int field = 0; field < 4; ++field) {
    for (const double v : hostile) {
      ASSERT_EQ(drive_->write_monitor(tripping), dyncal::port::PortStatus::ok) << drive_->error();
      dyncal::linux_port::DriveMonitor m = tripping;
      if (field == 0) {  // the gain, with every threshold 0: the symptom's case
        m.gain = v;
        m.threshold.fill(0);
      } else if (field == 1) {
        m.threshold[1] = v;
      } else if (field == 2) {
        m.mean[2] = v;
      } else {
        m.band[3] = v;
      }
      const dyncal::port::PortStatus st = drive_->write_monitor(m);
      ASSERT_NE(st, dyncal::port::PortStatus::transport_error) << drive_->error();
      std::uint16_t back[kWords];
      ASSERT_EQ(drive_->read_holding(mm::kMonitorGainReg, kWords, back), dyncal::port::PortStatus::ok);
      const dyncal::linux_port::DriveMonitor& expect = st == dyncal::port::PortStatus::ok ? m : tripping;
      const auto same = [](float a, double b) {  // bit for bit, as the float register holds it
        const float fb = static_cast<float>(b);
        return std::memcmp(&a, &fb, sizeof a) == 0;
      };
      EXPECT_TRUE(same(mm::get_f32(back), expect.gain)) << "field " << field << " value " << v;
      EXPECT_TRUE(same(mm::get_f32(back + (mm::kMonitorThresholdReg - mm::kMonitorGainReg) + 2), expect.threshold[1]));
      EXPECT_TRUE(same(mm::get_f32(back + (mm::kMonitorMeanReg - mm::kMonitorGainReg) + 4), expect.mean[2]));
      EXPECT_TRUE(same(mm::get_f32(back + (mm::kMonitorBandReg - mm::kMonitorGainReg) + 6), expect.band[3]));
      // The run: the settings read back trip at once unless they watch nothing.
      bool watches = expect.gain > 0;
      bool any_threshold = false;
      for (int j = 0; j < 6; ++j) any_threshold = any_threshold || expect.threshold[static_cast<size_t>(j)] > 0;
      watches = watches && any_threshold;
      ASSERT_EQ(drive_->start(), dyncal::port::PortStatus::ok)
          << drive_->error() << " field " << field << " value " << v;
      dyncal::linux_port::DriveInfo info;
      for (int k = 0; k < 30; ++k) {
        ASSERT_EQ(drive_->read_info(info), dyncal::port::PortStatus::ok);
        if (info.state != mm::DriveState::playing) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
      }
      if (watches) {
        EXPECT_EQ(info.state, mm::DriveState::fault) << "field " << field << " value " << v;
        EXPECT_EQ(info.fault, mm::DriveFault::collision);
        ASSERT_EQ(drive_->reset(), dyncal::port::PortStatus::ok);
      } else {  // the fixture's lockstep drive plays the 10 s run to its end, or holds at a full ring
        EXPECT_NE(info.state, mm::DriveState::fault)
            << "field " << field << " value " << v << ": the drive ran other settings than it acknowledged";
        ASSERT_EQ(drive_->stop(), dyncal::port::PortStatus::ok);
        if (info.state == mm::DriveState::fault) ASSERT_EQ(drive_->reset(), dyncal::port::PortStatus::ok);
      }
      (st == dyncal::port::PortStatus::ok ? acknowledged : refused) += 1;
    }
  }
  EXPECT_GT(acknowledged, 0);
  EXPECT_GT(refused, 0);
  ASSERT_EQ(drive_->write_monitor({}), dyncal::port::PortStatus::ok) << drive_->error();
}

}  // namespace

// A bare libmodbus server on loopback with a register map the test fills in: stands in for a drive
// that misbehaves in one precise way (another map version, a commit that never completes).
class BareModbusServer {
 public:
  BareModbusServer() {
    server_ = modbus_new_tcp("127.0.0.1", 0);
    listener_ = modbus_tcp_listen(server_, 1);
    sockaddr_in addr{};
    socklen_t len = sizeof addr;
    getsockname(listener_, reinterpret_cast<sockaddr*>(&addr), &len);
    port_ = ntohs(addr.sin_port);
    map_ = modbus_mapping_new(0, 0, mm::kHoldingWords, mm::kInputWords);
    map_->tab_input_registers[mm::kMapVersionReg] = mm::kMapVersion;
    map_->tab_input_registers[mm::kNumJointsReg] = 6;
  }
  ~BareModbusServer() {
    if (serve_.joinable()) serve_.join();
    close(listener_);
    modbus_mapping_free(map_);
    modbus_free(server_);
  }
  bool listening() const { return listener_ >= 0; }
  std::string uri() const { return "tcp://127.0.0.1:" + std::to_string(port_); }
  modbus_mapping_t* map() { return map_; }
  // Serves one client until it closes the connection.
  void serve_one() {
    serve_ = std::thread([this] {
      modbus_tcp_accept(server_, &listener_);
      std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
      for (;;) {
        const int n = modbus_receive(server_, query);
        if (n < 0) break;
        if (n > 0) modbus_reply(server_, query, n, map_);
      }
    });
  }

 private:
  modbus_t* server_ = nullptr;
  int listener_ = -1;
  int port_ = 0;
  modbus_mapping_t* map_ = nullptr;
  std::thread serve_;
};

// A drive of another register map version (map_version 3, the six-axis map) is refused by the host
// with a message naming both versions.
TEST(DriveModbusVersion, AnOlderMapIsRefusedWithBothVersions) {
  BareModbusServer bare;
  ASSERT_TRUE(bare.listening()) << modbus_strerror(errno);
  constexpr int kOlder = mm::kMapVersion - 1;  // a host or drive one version behind
  bare.map()->tab_input_registers[mm::kMapVersionReg] = kOlder;
  bare.serve_one();
  std::string error;
  auto drive = ModbusDrive::connect(bare.uri(), &error);
  ASSERT_NE(drive, nullptr) << error;
  dyncal::linux_port::DriveInfo info;
  EXPECT_EQ(drive->read_info(info), dyncal::port::PortStatus::rejected);
  const std::string expected =
      "register map version " + std::to_string(kOlder) + ", this host version " + std::to_string(mm::kMapVersion);
  EXPECT_NE(drive->error().find(expected), std::string::npos) << drive->error();
  drive.reset();  // the server's receive fails when the client closes
}

// A drive that accepts the commit command but never advances its commit counter: the host gives up
// at its deadline with transport_error and says what is unknown, instead of polling forever
// (issue 23, fault 6).
TEST(DriveModbusDeadline, ACommitThatNeverCompletesEndsAtTheDeadline) {
  BareModbusServer bare;
  ASSERT_TRUE(bare.listening()) << modbus_strerror(errno);
  bare.serve_one();
  std::string error;
  auto drive = ModbusDrive::connect(bare.uri(), &error);
  ASSERT_NE(drive, nullptr) << error;
  drive->set_commit_timeout(0.2);
  drive->set_commit_timeout(-1);  // ignored
  EXPECT_EQ(drive->commit_timeout(), 0.2);
  dyncal::ParameterTable table;
  table.robot_id = 1;
  table.model_id = 2;
  table.count = 3;
  for (int i = 0; i < table.count; ++i) table.values[i] = 1.0F + static_cast<float>(i);
  dyncal::TableStatus reason = dyncal::TableStatus::ok;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(drive->write(table, &reason), dyncal::port::PortStatus::transport_error);
  const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_GE(waited, 0.2);
  EXPECT_NE(drive->error().find("did not finish the commit within 0.2 s"), std::string::npos) << drive->error();
  // The staged bytes did reach the server: the request path worked, only the counter never moved.
  EXPECT_GT(bare.map()->tab_registers[mm::kStagingSizeReg], 0);
  drive.reset();
}
