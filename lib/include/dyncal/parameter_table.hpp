// The parameter table: one binary layout for the identified model, shared by firmware, the
// simulated drive and the host (flashed over Modbus, persisted in flash).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstring>

#include "dyncal/crc32.hpp"
#include "dyncal/effect_terms.hpp"

namespace dyncal {

/// Layout (all fields little-endian, no padding), `encoded_table_size(count)` bytes:
///
/// | offset | size | field |
/// |---|---|---|
/// | 0 | 4 | magic 0x54504344 ("DCPT" in memory order) |
/// | 4 | 2 | format version (kTableFormatVersion) |
/// | 6 | 2 | parameter count n (1..kTableMaxParams) |
/// | 8 | 4 | robot id (generated `kRobotId`: what each base parameter means) |
/// | 12 | 4 | model id (`dyncal::term` bits of the identification model: the columns after Y_b) |
/// | 16 | 4 n | values, IEEE-754 float32, in the model's column order (SI units) |
/// | 16 + 4 n | 2 | effect count e (0..kTableMaxEffects) |
/// | 18 + 4 n | 20 e | effect terms: kind u8, joint u8, joint2 u8, sign i8, shape f32, c0..c2 f32 |
/// | 18 + 4 n + 20 e | 4 | CRC-32 of all bytes before it |
inline constexpr std::uint32_t kTableMagic = 0x54504344u;
inline constexpr std::uint16_t kTableFormatVersion = 2;
inline constexpr int kTableHeaderBytes = 16;
inline constexpr int kTableMaxParams = 128;
inline constexpr int kTableMaxEffects = 16;
inline constexpr int kTableMaxBytes =
    kTableHeaderBytes + 4 * kTableMaxParams + 2 + kEffectTermBytes * kTableMaxEffects + 4;

constexpr int encoded_table_size(int count, int effects = 0) noexcept {
  return kTableHeaderBytes + 4 * count + 2 + kEffectTermBytes * effects + 4;
}

/// Outcome of decoding or checking a table; every rejection names its reason.
enum class TableStatus : std::uint8_t {
  ok = 0,
  bad_size,      ///< byte count does not match the parameter count (or exceeds the capacity)
  bad_magic,     ///< not a parameter table
  bad_version,   ///< format version this code does not read
  bad_count,     ///< parameter count 0 or above kTableMaxParams
  bad_crc,       ///< CRC-32 mismatch: corrupted or truncated
  wrong_robot,   ///< robot id differs from the drive's robot
  wrong_model,   ///< model id the drive does not run, or count not matching it
  non_finite,    ///< a value is NaN or infinite
  out_of_range,  ///< a value is outside the drive's accepted range
  bad_effect,    ///< an effect term is malformed (kind, joints, sign, shape) or too many
  store_failed,  ///< the table is valid, but the drive could not write it to its flash store
};

constexpr const char* to_string(TableStatus s) noexcept {
  switch (s) {
    case TableStatus::ok:
      return "ok";
    case TableStatus::bad_size:
      return "size does not match the parameter count";
    case TableStatus::bad_magic:
      return "bad magic: not a parameter table";
    case TableStatus::bad_version:
      return "unsupported table format version";
    case TableStatus::bad_count:
      return "parameter count out of range";
    case TableStatus::bad_crc:
      return "CRC-32 mismatch";
    case TableStatus::wrong_robot:
      return "robot id does not match this drive's robot";
    case TableStatus::wrong_model:
      return "model id not supported by this drive (or count does not match it)";
    case TableStatus::non_finite:
      return "a value is NaN or infinite";
    case TableStatus::out_of_range:
      return "a value is outside the accepted range";
    case TableStatus::bad_effect:
      return "an effect term is malformed";
    case TableStatus::store_failed:
      return "the drive could not write it to its flash store";
  }
  return "unknown";
}

/// A decoded table. Fixed capacity, no heap.
struct ParameterTable {
  std::uint32_t robot_id = 0;
  std::uint32_t model_id = 0;
  std::uint16_t count = 0;
  float values[kTableMaxParams] = {};
  std::uint16_t effect_count = 0;
  EffectTerm effects[kTableMaxEffects] = {};
};

namespace detail {

inline void put_u16(std::uint8_t* p, std::uint16_t v) noexcept {
  p[0] = static_cast<std::uint8_t>(v);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
inline void put_u32(std::uint8_t* p, std::uint32_t v) noexcept {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
}
inline std::uint16_t get_u16(const std::uint8_t* p) noexcept {
  return static_cast<std::uint16_t>(p[0] | (p[1] << 8));
}
inline std::uint32_t get_u32(const std::uint8_t* p) noexcept {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
inline std::uint32_t float_bits(float f) noexcept {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
inline float bits_float(std::uint32_t u) noexcept {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

}  // namespace detail

/// Encodes `table` into `out` (capacity bytes). Returns bad_count or bad_size (capacity too small)
/// without writing; on ok, *written = encoded_table_size(table.count).
inline TableStatus encode_table(const ParameterTable& table, std::uint8_t* out, int capacity, int* written) noexcept {
  if (table.count == 0 || table.count > kTableMaxParams) return TableStatus::bad_count;
  if (table.effect_count > kTableMaxEffects) return TableStatus::bad_effect;
  const int size = encoded_table_size(table.count, table.effect_count);
  if (capacity < size) return TableStatus::bad_size;
  detail::put_u32(out, kTableMagic);
  detail::put_u16(out + 4, kTableFormatVersion);
  detail::put_u16(out + 6, table.count);
  detail::put_u32(out + 8, table.robot_id);
  detail::put_u32(out + 12, table.model_id);
  for (int i = 0; i < table.count; ++i)
    detail::put_u32(out + kTableHeaderBytes + 4 * i, detail::float_bits(table.values[i]));
  std::uint8_t* e = out + kTableHeaderBytes + 4 * table.count;
  detail::put_u16(e, table.effect_count);
  e += 2;
  for (int i = 0; i < table.effect_count; ++i, e += kEffectTermBytes) {
    const EffectTerm& t = table.effects[i];
    e[0] = static_cast<std::uint8_t>(t.kind);
    e[1] = t.joint;
    e[2] = t.joint2;
    e[3] = static_cast<std::uint8_t>(t.sign);
    detail::put_u32(e + 4, detail::float_bits(t.shape));
    for (int k = 0; k < 3; ++k) detail::put_u32(e + 8 + 4 * k, detail::float_bits(t.c[k]));
  }
  detail::put_u32(out + size - 4, crc32(out, static_cast<std::size_t>(size - 4)));
  *written = size;
  return TableStatus::ok;
}

/// Parameter count stored in an encoded header (0 if fewer than kTableHeaderBytes bytes).
inline int table_count_of(const std::uint8_t* in, int size) noexcept {
  return size < kTableHeaderBytes ? 0 : detail::get_u16(in + 6);
}

/// Decodes and checks the format: magic, version, count, size, CRC-32, finite values. `size` is the
/// number of bytes available; the table must fill exactly encoded_table_size(count) of them.
/// `out` is written only on ok.
inline TableStatus decode_table(const std::uint8_t* in, int size, ParameterTable& out) noexcept {
  if (size < kTableHeaderBytes + 4) return TableStatus::bad_size;
  if (detail::get_u32(in) != kTableMagic) return TableStatus::bad_magic;
  if (detail::get_u16(in + 4) != kTableFormatVersion) return TableStatus::bad_version;
  const int count = detail::get_u16(in + 6);
  if (count == 0 || count > kTableMaxParams) return TableStatus::bad_count;
  if (size < encoded_table_size(count)) return TableStatus::bad_size;
  const int effects = detail::get_u16(in + kTableHeaderBytes + 4 * count);
  if (effects > kTableMaxEffects) return TableStatus::bad_effect;
  if (size != encoded_table_size(count, effects)) return TableStatus::bad_size;
  if (crc32(in, static_cast<std::size_t>(size - 4)) != detail::get_u32(in + size - 4)) return TableStatus::bad_crc;
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(detail::bits_float(detail::get_u32(in + kTableHeaderBytes + 4 * i)))) {
      return TableStatus::non_finite;
    }
  }
  out.robot_id = detail::get_u32(in + 8);
  out.model_id = detail::get_u32(in + 12);
  out.count = static_cast<std::uint16_t>(count);
  for (int i = 0; i < count; ++i) out.values[i] = detail::bits_float(detail::get_u32(in + kTableHeaderBytes + 4 * i));
  out.effect_count = static_cast<std::uint16_t>(effects);
  const std::uint8_t* e = in + kTableHeaderBytes + 4 * count + 2;
  for (int i = 0; i < effects; ++i, e += kEffectTermBytes) {
    EffectTerm& t = out.effects[i];
    t.kind = static_cast<EffectKind>(e[0]);
    t.joint = e[1];
    t.joint2 = e[2];
    t.sign = static_cast<std::int8_t>(e[3]);
    t.shape = detail::bits_float(detail::get_u32(e + 4));
    for (int k = 0; k < 3; ++k) t.c[k] = detail::bits_float(detail::get_u32(e + 8 + 4 * k));
  }
  return TableStatus::ok;
}

}  // namespace dyncal
