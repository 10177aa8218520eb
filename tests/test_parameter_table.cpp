// Parameter table layout, CRC-32 and the drive-side checks (lib/).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "dyncal/crc32.hpp"
#include "dyncal/generated/er20/robot.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/table_check.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace parameter_table_suite {

using Er20 = dyncal::generated::er20::Robot;
using Model = dyncal::IdentificationModel<Er20, dyncal::kFrictionEq7 | dyncal::term::rotor_inertia>;

dyncal::ParameterTable valid_table() {
  Model::ParamVector<double> phi;
  for (int i = 0; i < Model::kNumParams; ++i) phi[i] = 0.5 + 0.01 * i;
  dyncal::ParameterTable t;
  dyncal::make_table<Model>(phi, t);
  return t;
}

TEST(Crc32, MatchesTheStandardCheckValue) {
  const char* text = "123456789";
  EXPECT_EQ(dyncal::crc32(reinterpret_cast<const std::uint8_t*>(text), 9), 0xCBF43926u);
  // Chaining two halves gives the same result as one pass.
  const auto* p = reinterpret_cast<const std::uint8_t*>(text);
  EXPECT_EQ(dyncal::crc32(p + 4, 5, dyncal::crc32(p, 4)), 0xCBF43926u);
}

TEST(ParameterTable, RoundTripsAndHasTheDocumentedLayout) {
  const auto t = valid_table();
  std::uint8_t bytes[dyncal::kTableMaxBytes];
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(t, bytes, sizeof bytes, &size), dyncal::TableStatus::ok);
  EXPECT_EQ(size, 16 + 4 * Model::kNumParams + 2 + 4);
  EXPECT_EQ(bytes[0], 0x44);  // magic, little-endian
  EXPECT_EQ(bytes[6] | (bytes[7] << 8), Model::kNumParams);
  float v0;
  std::memcpy(&v0, bytes + 16, 4);
  EXPECT_EQ(v0, t.values[0]);
  dyncal::ParameterTable back;
  ASSERT_EQ(dyncal::decode_table(bytes, size, back), dyncal::TableStatus::ok);
  EXPECT_EQ(back.robot_id, Er20::kRobotId);
  EXPECT_EQ(back.model_id, Model::kTerms);
  ASSERT_EQ(back.count, Model::kNumParams);
  for (int i = 0; i < back.count; ++i) EXPECT_EQ(back.values[i], t.values[i]);
  EXPECT_EQ(dyncal::check_table<Model>(back), dyncal::TableStatus::ok);
}

TEST(ParameterTable, EveryCorruptionIsNamed) {
  const auto t = valid_table();
  std::uint8_t good[dyncal::kTableMaxBytes];
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(t, good, sizeof good, &size), dyncal::TableStatus::ok);
  dyncal::ParameterTable out;
  out.count = 7;  // must stay untouched on failure
  std::uint8_t b[dyncal::kTableMaxBytes];
  // Any single flipped bit is caught: in the values or the CRC by the CRC, in the effect count by
  // the size it implies.
  const int effect_count_at = 16 + 4 * Model::kNumParams;
  for (int byte = 16; byte < size; byte += 3) {
    std::memcpy(b, good, size);
    b[byte] ^= 0x10;
    const auto st = dyncal::decode_table(b, size, out);
    if (byte == effect_count_at || byte == effect_count_at + 1) {
      EXPECT_NE(st, dyncal::TableStatus::ok) << "byte " << byte;
    } else {
      EXPECT_EQ(st, dyncal::TableStatus::bad_crc) << "byte " << byte;
    }
  }
  std::memcpy(b, good, size);
  b[0] ^= 1;
  EXPECT_EQ(dyncal::decode_table(b, size, out), dyncal::TableStatus::bad_magic);
  std::memcpy(b, good, size);
  b[4] = 9;
  EXPECT_EQ(dyncal::decode_table(b, size, out), dyncal::TableStatus::bad_version);
  EXPECT_EQ(dyncal::decode_table(good, size - 1, out), dyncal::TableStatus::bad_size);
  EXPECT_EQ(dyncal::decode_table(good, 10, out), dyncal::TableStatus::bad_size);
  std::memcpy(b, good, size);
  b[6] = 0;
  b[7] = 0;
  EXPECT_EQ(dyncal::decode_table(b, size, out), dyncal::TableStatus::bad_count);
  EXPECT_EQ(out.count, 7);
  // A NaN with a correct CRC is still refused.
  auto nan_table = t;
  nan_table.values[3] = std::numeric_limits<float>::quiet_NaN();
  ASSERT_EQ(dyncal::encode_table(nan_table, b, sizeof b, &size), dyncal::TableStatus::ok);
  EXPECT_EQ(dyncal::decode_table(b, size, out), dyncal::TableStatus::non_finite);
}

TEST(ParameterTable, EffectTermsRoundTripAndAreChecked) {
  auto t = valid_table();
  t.effect_count = 2;
  t.effects[0] = {dyncal::EffectKind::position_periodic, 1, 0, 1, 36.0f, {1.5f, -0.5f, 0.0f}};
  t.effects[1] = {dyncal::EffectKind::coupling, 4, 5, -1, 0.0f, {0.8f, 0.3f, 0.01f}};
  std::uint8_t bytes[dyncal::kTableMaxBytes];
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(t, bytes, sizeof bytes, &size), dyncal::TableStatus::ok);
  EXPECT_EQ(size, dyncal::encoded_table_size(Model::kNumParams, 2));
  dyncal::ParameterTable back;
  ASSERT_EQ(dyncal::decode_table(bytes, size, back), dyncal::TableStatus::ok);
  ASSERT_EQ(back.effect_count, 2);
  EXPECT_EQ(back.effects[0].kind, dyncal::EffectKind::position_periodic);
  EXPECT_EQ(back.effects[0].shape, 36.0f);
  EXPECT_EQ(back.effects[1].joint2, 5);
  EXPECT_EQ(back.effects[1].sign, -1);
  EXPECT_EQ(back.effects[1].c[2], 0.01f);
  EXPECT_EQ(dyncal::check_table<Model>(back), dyncal::TableStatus::ok);
  // The feed-forward of the two terms at one state, by hand.
  Eigen::Matrix<double, 6, 1> q = Eigen::Matrix<double, 6, 1>::Constant(0.1), qd = Eigen::Matrix<double, 6, 1>::Zero(),
                              qdd = Eigen::Matrix<double, 6, 1>::Zero(), rb = qd, tau = qd;
  qd[4] = 1.0;
  qd[5] = 0.25;
  dyncal::add_effect_torques(back.effects, back.effect_count, q, qd, qdd, rb, tau);
  EXPECT_NEAR(tau[1], 1.5 * std::sin(3.6) - 0.5 * std::cos(3.6), 1e-6);
  EXPECT_NEAR(tau[4], 0.8 + 0.3 * 0.75, 1e-6);  // v = qd5 - qd6 = 0.75
  EXPECT_NEAR(tau[5], -(0.8 + 0.3 * 0.75), 1e-6);
  // A coupling with ratio 0.5 (shape): v = qd5 - 0.5 qd6 = 0.875, joint 6 takes -0.5 f.
  auto ratio = back;
  ratio.effect_count = 1;
  ratio.effects[0] = back.effects[1];
  ratio.effects[0].shape = 0.5f;
  EXPECT_EQ(dyncal::check_table<Model>(ratio), dyncal::TableStatus::ok);
  tau.setZero();
  dyncal::add_effect_torques(ratio.effects, ratio.effect_count, q, qd, qdd, rb, tau);
  EXPECT_NEAR(tau[4], 0.8 + 0.3 * 0.875, 1e-6);
  EXPECT_NEAR(tau[5], -0.5 * (0.8 + 0.3 * 0.875), 1e-6);
  // Malformed terms are refused by the drive.
  auto bad = back;
  bad.effects[1].joint2 = 4;  // coupled with itself
  EXPECT_EQ(dyncal::check_table<Model>(bad), dyncal::TableStatus::bad_effect);
  bad = back;
  bad.effects[0].shape = 0.0f;  // no period
  EXPECT_EQ(dyncal::check_table<Model>(bad), dyncal::TableStatus::bad_effect);
  bad = back;
  bad.effects[1].shape = -1.0f;  // a negative ratio (its sign is `sign`)
  EXPECT_EQ(dyncal::check_table<Model>(bad), dyncal::TableStatus::bad_effect);
  bad = back;
  bad.effects[0].kind = static_cast<dyncal::EffectKind>(42);
  EXPECT_EQ(dyncal::check_table<Model>(bad), dyncal::TableStatus::bad_effect);
  bad = back;
  bad.effect_count = dyncal::kTableMaxEffects + 1;
  EXPECT_EQ(dyncal::encode_table(bad, bytes, sizeof bytes, &size), dyncal::TableStatus::bad_effect);
}

TEST(ParameterTable, DriveChecksRobotModelAndRanges) {
  auto t = valid_table();
  t.robot_id ^= 1;
  EXPECT_EQ(dyncal::check_table<Model>(t), dyncal::TableStatus::wrong_robot);
  t = valid_table();
  t.model_id = dyncal::kFrictionEq8;
  EXPECT_EQ(dyncal::check_table<Model>(t), dyncal::TableStatus::wrong_model);
  t = valid_table();
  t.count = static_cast<std::uint16_t>(t.count - 1);
  EXPECT_EQ(dyncal::check_table<Model>(t), dyncal::TableStatus::wrong_model);
  t = valid_table();
  t.values[0] = 2 * dyncal::kTableMaxAbsValue;
  EXPECT_EQ(dyncal::check_table<Model>(t), dyncal::TableStatus::out_of_range);
  t = valid_table();
  t.values[Model::column(dyncal::term::viscous, 2)] = -1.0f;  // friction must oppose motion
  EXPECT_EQ(dyncal::check_table<Model>(t), dyncal::TableStatus::out_of_range);
  t = valid_table();
  t.values[0] = -1.0f;  // a base parameter may be negative
  EXPECT_EQ(dyncal::check_table<Model>(t), dyncal::TableStatus::ok);
}

TEST(ModbusMap, FieldsDoNotOverlapAndBytesRoundTrip) {
  namespace mm = dyncal::modbus_map;
  for (const auto& a : mm::kRegisterMap) {
    for (const auto& b : mm::kRegisterMap) {
      if (&a == &b || a.bank != b.bank) continue;
      EXPECT_FALSE(a.address < b.address + b.words && b.address < a.address + a.words) << a.name << " / " << b.name;
    }
  }
  const std::uint8_t bytes[5] = {1, 2, 3, 4, 5};
  std::uint16_t regs[3];
  mm::bytes_to_regs(bytes, 5, regs);
  EXPECT_EQ(regs[0], 0x0102);
  EXPECT_EQ(regs[2], 0x0500);
  std::uint8_t back[5];
  mm::regs_to_bytes(regs, 5, back);
  EXPECT_EQ(std::memcmp(back, bytes, 5), 0);
  std::uint16_t f[2];
  mm::set_f32(f, 1.5f);
  EXPECT_EQ(f[0], 0x3FC0);  // most significant word first
  EXPECT_EQ(mm::get_f32(f), 1.5f);
}

}  // namespace parameter_table_suite
}  // namespace
