// The simulated drive over Modbus TCP on loopback (a real libmodbus server started by a CTest
// fixture): register round trips, Modbus exceptions, table flash checks.
#include <arpa/inet.h>
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
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
  // bytes (staging bank)
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
  EXPECT_EQ(modbus_read_registers(ctx, 1, 1, r), -1);  // hole between command and ack
  EXPECT_EQ(errno, EMBXILADD);
  EXPECT_EQ(modbus_read_input_registers(ctx, mm::kRingReg - 1, 2, r), -1);
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
  EXPECT_EQ(d.write_holding(mm::kStagingSizeReg, static_cast<int>(regs.size()), regs.data()),
            dyncal::port::PortStatus::ok)
      << d.error();
  const std::uint16_t cmd = static_cast<std::uint16_t>(mm::Command::commit_table);
  EXPECT_EQ(d.write_holding(mm::kCommandReg, 1, &cmd), dyncal::port::PortStatus::ok) << d.error();
  std::uint16_t r[2] = {0, before};
  while (r[1] == before) EXPECT_EQ(d.read_input(mm::kCommitResultReg, 2, r), dyncal::port::PortStatus::ok);
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

}  // namespace

// A drive of another register map version (a real libmodbus server on loopback whose map_version
// is 3, the six-axis map) is refused by the host with a message naming both versions.
TEST(DriveModbusVersion, AnOlderMapIsRefusedWithBothVersions) {
  modbus_t* server = modbus_new_tcp("127.0.0.1", 0);
  ASSERT_NE(server, nullptr);
  const int listener = modbus_tcp_listen(server, 1);
  ASSERT_GE(listener, 0) << modbus_strerror(errno);
  sockaddr_in addr{};
  socklen_t len = sizeof addr;
  ASSERT_EQ(getsockname(listener, reinterpret_cast<sockaddr*>(&addr), &len), 0);
  const int port = ntohs(addr.sin_port);
  modbus_mapping_t* map = modbus_mapping_new(0, 0, 0, mm::kInputWords);
  map->tab_input_registers[mm::kMapVersionReg] = 3;
  map->tab_input_registers[mm::kNumJointsReg] = 6;
  std::thread serve([&] {
    modbus_tcp_accept(server, const_cast<int*>(&listener));
    std::uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
    for (;;) {
      const int n = modbus_receive(server, query);
      if (n < 0) break;
      if (n > 0) modbus_reply(server, query, n, map);
    }
  });
  std::string error;
  auto drive = ModbusDrive::connect("tcp://127.0.0.1:" + std::to_string(port), &error);
  ASSERT_NE(drive, nullptr) << error;
  dyncal::linux_port::DriveInfo info;
  EXPECT_EQ(drive->read_info(info), dyncal::port::PortStatus::rejected);
  EXPECT_NE(drive->error().find("register map version 3, this host version 4"), std::string::npos) << drive->error();
  drive.reset();  // the server's receive fails when the client closes
  serve.join();
  close(listener);
  modbus_mapping_free(map);
  modbus_free(server);
}
