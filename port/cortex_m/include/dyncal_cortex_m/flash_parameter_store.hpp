#pragma once
// Parameter store in a flash region (port::ParameterStore for the firmware). Two slots (A/B): a
// write goes to the slot not holding the active table — erase, program, verify — and carries a
// generation one above the active one; reading picks the valid slot (magic + table CRC-32) with
// the highest generation. Power lost during a write leaves the previous table active.
//
// The flash itself is behind FlashDevice (erase a sector to 0xFF, program bytes that may only
// clear bits); on qemu's MPS2 boards the region `.param_store` of the linker script (the end of the
// 4 MiB SSRAM that stands in for flash) is emulated with those semantics. A drive port implements
// FlashDevice with its MCU's flash controller.
#include <cstdint>

#include "dyncal/drive/term_sets.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal/port.hpp"
#include "dyncal/table_check.hpp"

namespace dyncal::cortex_m {

/// A flash region of `size()` bytes: erase(offset) sets one sector to 0xFF, program() may only
/// clear bits (returns false if the result differs from the data), data() maps the region.
class FlashDevice {
 public:
  virtual int size() const noexcept = 0;
  virtual int sector_size() const noexcept = 0;
  virtual bool erase(int offset) noexcept = 0;
  virtual bool program(int offset, const std::uint8_t* bytes, int count) noexcept = 0;
  virtual const std::uint8_t* data() const noexcept = 0;

 protected:
  ~FlashDevice() = default;
};

/// Slot layout: magic u32 'DPS1', generation u32, table length u32, then the encoded table (its own
/// CRC-32, dyncal/parameter_table.hpp). Models: the term sets the drive runs
/// (dyncal/drive/term_sets.hpp); write() refuses a table Models::check rejects (its robot, one of
/// the models, check_table of that model), and with set_ratings also one that is implausible
/// against the robot's ratings (check_table with JointRatings: no per-joint term and not the rigid
/// body beyond 10 x tau_max at rated motion; Yb's N x kNumBase floats on the stack while it runs).
template <class Models>
class FlashParameterStore final : public port::ParameterStore {
 public:
  static constexpr std::uint32_t kSlotMagic = 0x31535044u;  // "DPS1"
  static constexpr int kSlotHeader = 12;

  explicit FlashParameterStore(FlashDevice& flash) noexcept : flash_(flash) {}

  /// The robot's ratings (robot.json limits, joint side) that write() checks tables against.
  void set_ratings(const JointRatings<Models::kNumJoints>& ratings) noexcept {
    ratings_ = ratings;
    has_ratings_ = true;
  }

  port::PortStatus write(const ParameterTable& table, TableStatus* reason) noexcept override {
    TableStatus s = has_ratings_ ? Models::check(table, ratings_) : Models::check(table);
    if (s == TableStatus::ok) s = encode_table(table, buffer_ + kSlotHeader, kTableMaxBytes, &length_);
    if (reason != nullptr) *reason = s;
    if (s != TableStatus::ok) return port::PortStatus::rejected;
    const int slot_bytes = slot_size();
    if (kSlotHeader + length_ > slot_bytes) return port::PortStatus::transport_error;
    std::uint32_t generation = 0;
    const int active = newest(&generation);
    const int target = active == 0 ? 1 : 0;
    put_u32(buffer_, kSlotMagic);
    put_u32(buffer_ + 4, generation + 1);
    put_u32(buffer_ + 8, static_cast<std::uint32_t>(length_));
    const int offset = target * slot_bytes;
    for (int o = 0; o < slot_bytes; o += flash_.sector_size()) {
      if (!flash_.erase(offset + o)) return port::PortStatus::transport_error;
    }
    if (!flash_.program(offset, buffer_, kSlotHeader + length_)) return port::PortStatus::transport_error;
    if (slot_table(target, nullptr) != TableStatus::ok) return port::PortStatus::transport_error;  // verify
    return port::PortStatus::ok;
  }

  port::PortStatus read(ParameterTable& table, TableStatus* reason) noexcept override {
    const int slot = newest(nullptr);
    if (slot < 0) {
      if (reason != nullptr) *reason = slot_table(0, nullptr);
      return port::PortStatus::rejected;
    }
    const TableStatus s = slot_table(slot, &table);
    if (reason != nullptr) *reason = s;
    return s == TableStatus::ok ? port::PortStatus::ok : port::PortStatus::rejected;
  }

  /// Generation of the active table (0: none).
  std::uint32_t generation() const noexcept {
    std::uint32_t g = 0;
    newest(&g);
    return g;
  }

 private:
  int slot_size() const noexcept { return flash_.size() / 2; }

  static void put_u32(std::uint8_t* p, std::uint32_t v) noexcept {
    for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>(v >> (8 * i));
  }
  static std::uint32_t get_u32(const std::uint8_t* p) noexcept {
    return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
           static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
  }

  /// Decodes slot `slot` (into `out` when given; a scratch table otherwise).
  TableStatus slot_table(int slot, ParameterTable* out) const noexcept {
    const std::uint8_t* p = flash_.data() + slot * slot_size();
    if (get_u32(p) != kSlotMagic) return TableStatus::bad_magic;
    const std::uint32_t length = get_u32(p + 8);
    if (length > static_cast<std::uint32_t>(slot_size() - kSlotHeader)) return TableStatus::bad_size;
    return decode_table(p + kSlotHeader, static_cast<int>(length), out != nullptr ? *out : scratch_);
  }

  /// The valid slot with the highest generation (-1: none), its generation in *generation.
  int newest(std::uint32_t* generation) const noexcept {
    int best = -1;
    std::uint32_t g_best = 0;
    for (int slot = 0; slot < 2; ++slot) {
      if (slot_table(slot, nullptr) != TableStatus::ok) continue;
      const std::uint32_t g = get_u32(flash_.data() + slot * slot_size() + 4);
      if (best < 0 || g > g_best) {
        best = slot;
        g_best = g;
      }
    }
    if (generation != nullptr) *generation = best < 0 ? 0 : g_best;
    return best;
  }

  FlashDevice& flash_;
  std::uint8_t buffer_[kSlotHeader + kTableMaxBytes] = {};
  JointRatings<Models::kNumJoints> ratings_ = {};
  bool has_ratings_ = false;
  int length_ = 0;
  mutable ParameterTable scratch_;
};

/// The `.param_store` region of the MPS2 linker script as a FlashDevice (RAM-backed on qemu, with
/// flash semantics: erase to 0xFF, programming only clears bits).
FlashDevice& mps2_param_flash() noexcept;

/// One store per image, over mps2_param_flash().
template <class Models>
FlashParameterStore<Models>& flash_parameter_store() noexcept {
  static FlashParameterStore<Models> store(mps2_param_flash());
  return store;
}

}  // namespace dyncal::cortex_m
