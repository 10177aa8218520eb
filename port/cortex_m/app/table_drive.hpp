#pragma once
// The drive of the firmware images that serve Modbus without an arm: the er20's Eq. 7 model, its
// table in the flash A/B store (dyncal_cortex_m/flash_parameter_store.hpp), as lib/'s register
// server sees a drive (dyncal/drive/register_server.hpp's Drive). Idle, an empty ring; a start is
// refused. Used by the modbus_server image (instruction counts) and the drive image over UART0.
#include <cstdint>

#include "dyncal/drive/register_server.hpp"
#include "dyncal/drive/ring_window.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal/table_check.hpp"
#include "dyncal_cortex_m/flash_parameter_store.hpp"
#include "replay.hpp"

namespace dyncal::cortex_m {

/// The drive as the register server sees it: the flash store's active table (or the factory table
/// given to activate() when the flash holds none), no arm.
struct TableDrive {
  using Model = dyncal::replay::LinearModel;
  FlashParameterStore<Model>& store;
  dyncal::ParameterTable active{};
  dyncal::ParameterTable staged{};  ///< the table being committed (not on the stack)
  std::uint8_t active_bytes[dyncal::kTableMaxBytes] = {};
  int active_size = 0;
  std::uint32_t generation = 0;                  ///< +1 per table made active
  mutable std::uint32_t published = 0xFFFFFFFF;  ///< the generation the input registers show
  /// Called after the store took a table, before it becomes active (the drive image saves its flash
  /// region to a file); false: the table does not become active, the commit says store_failed.
  bool (*persist)() = nullptr;

  modbus_map::DriveState state() const { return modbus_map::DriveState::idle; }
  std::uint32_t acked() const { return 0; }
  std::uint32_t produced() const { return 0; }
  long ring_capacity_samples() const { return 0; }
  long run_samples(double periods, double period_s, double fs) const {
    return static_cast<long>(periods * period_s * fs);
  }
  double control_rate_hz() const { return 1000.0; }
  void ack(std::uint32_t) {}
  bool start(modbus_map::Command, const dyncal::drive::RunSettings&, const dyncal::drive::MonitorSettings&) {
    return false;
  }
  void stop() {}
  void reset() {}
  /// Decode, check against the model and the ratings, write to the slot not active, verify, then
  /// read the store's active table back: the registers show what the flash holds.
  TableStatus commit(const std::uint8_t* bytes, int size) {
    TableStatus st = dyncal::decode_table(bytes, size, staged);
    if (st != TableStatus::ok) return st;
    if (store.write(staged, &st) != dyncal::port::PortStatus::ok)
      return st != TableStatus::ok ? st : TableStatus::store_failed;
    if (persist && !persist()) return TableStatus::store_failed;
    return load();
  }
  /// Makes `t` active without storing it (the factory table of a drive whose flash holds none).
  TableStatus activate(const ParameterTable& t) {
    active = t;
    const TableStatus st = dyncal::encode_table(active, active_bytes, dyncal::kTableMaxBytes, &active_size);
    ++generation;
    return st;
  }
  TableStatus load() {
    TableStatus st;
    if (store.read(active, &st) != dyncal::port::PortStatus::ok) return st;
    st = dyncal::encode_table(active, active_bytes, dyncal::kTableMaxBytes, &active_size);
    ++generation;
    return st;
  }
  void publish_inputs(std::uint16_t* in) const {
    in[modbus_map::kMapVersionReg] = modbus_map::kMapVersion;
    in[modbus_map::kNumJointsReg] = Model::kNumJoints;
    modbus_map::set_u32(in + modbus_map::kRobotIdReg, Model::RobotType::kRobotId);
    in[modbus_map::kStateReg] = static_cast<std::uint16_t>(state());
    if (published == generation) return;  // the table registers change with the table only
    modbus_map::set_u32(in + modbus_map::kActiveModelIdReg, active.model_id);
    in[modbus_map::kActiveCountReg] = active.count;
    modbus_map::set_u32(in + modbus_map::kActiveCrcReg,
                        active_size >= 4 ? dyncal::detail::get_u32(active_bytes + active_size - 4) : 0);
    in[modbus_map::kActiveTableSizeReg] = static_cast<std::uint16_t>(active_size);
    for (int k = 0; k < modbus_map::kTableWords; ++k) in[modbus_map::kActiveTableReg + k] = 0;
    modbus_map::bytes_to_regs(active_bytes, active_size, in + modbus_map::kActiveTableReg);
    published = generation;
  }
  void publish_window(std::uint16_t* w) const {
    const dyncal::port::DriveSample* none = nullptr;
    dyncal::drive::RingWindowHeader header;
    dyncal::drive::encode_ring_window(none, 0, header, Model::kNumJoints, modbus_map::RingFormat::float32,
                                      dyncal::drive::RingResolution{}, w);
  }
};

}  // namespace dyncal::cortex_m
