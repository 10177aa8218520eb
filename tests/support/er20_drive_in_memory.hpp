#pragma once
// The er20 drive of the Cortex-M drive image (port/replay/er20_drive.hpp) on the host, for the tests
// of lib/'s drive application: its flash store replaced by memory, a 2 048-sample ring, a run
// inside the er20's ranges, and a host that reads every sample.
#include "er20_drive.hpp"

namespace dyncal::test::er20_drive {

using namespace dyncal::replay;
using Robot = Er20;
using Models = DriveModels;
namespace data = dyncal::replay::data;

/// A parameter store in memory (what the flash A/B store is to the image).
struct MemoryStore final : port::ParameterStore {
  ParameterTable table{};
  bool holds = false;
  int writes = 0;
  port::PortStatus write(const ParameterTable& t, TableStatus* reason) noexcept override {
    table = t;
    holds = true;
    ++writes;
    if (reason) *reason = TableStatus::ok;
    return port::PortStatus::ok;
  }
  port::PortStatus read(ParameterTable& t, TableStatus* reason) noexcept override {
    if (reason) *reason = holds ? TableStatus::ok : TableStatus::bad_magic;
    if (!holds) return port::PortStatus::rejected;
    t = table;
    return port::PortStatus::ok;
  }
};

template <typename Scalar>
using Application = Er20Drive<Scalar, 2048>;

template <typename Scalar>
typename Application<Scalar>::Settings settings() {
  return drive_settings<Application<Scalar>>();
}

template <typename Scalar>
replay::SimulatedArm<Robot, Scalar> arm(std::uint64_t seed = 2026) {
  return replay::SimulatedArm<Robot, Scalar>{arm_physics(seed)};
}

/// A run inside the er20's ranges (er20_drive.hpp).
inline drive::RunSettings run(double f_f, int periods, double fs, double amplitude = 0.3) {
  return excitation_run(f_f, periods, fs, amplitude);
}

/// Plays the run the drive started to its end as a host reading every sample would (acknowledging
/// what the ring holds whenever it fills); the periods run.
template <class Drive>
long play(Drive& d) {
  long periods = 0;
  while (d.state() == modbus_map::DriveState::playing) {
    if (!d.wants_period()) d.ack(d.produced());
    d.period();
    ++periods;
  }
  return periods;
}

}  // namespace dyncal::test::er20_drive
