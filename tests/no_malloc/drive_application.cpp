// test_no_malloc: lib/'s drive application (dyncal/drive/drive_application.hpp) allocates nothing
// over a whole run on the drive image's simulated er20 — start (the PD gains' LDLT), every control
// period (table dispatch, the control law, the collision monitor, recording, the payload estimator),
// the payload's verdict and loaded table, the registers and the ring window, a commit —
// in double and in float, as the Cortex-M drive images run it.
#define EIGEN_RUNTIME_NO_MALLOC
#include <gtest/gtest.h>

#include <memory>

#include "no_malloc/allocation_counter.hpp"
#include "support/er20_drive_in_memory.hpp"

namespace {

using namespace dyncal::test::er20_drive;
using dyncal::test::allocations_during;

template <typename Scalar>
struct DriveWorkspace {
  MemoryStore store;
  dyncal::replay::SimulatedArm<Robot, Scalar> joints = arm<Scalar>();
  Application<Scalar> drive{store, joints, settings<Scalar>()};
  std::uint16_t inputs[dyncal::modbus_map::kInputWords] = {};
  std::uint16_t window[dyncal::modbus_map::kRingWords] = {};
  std::uint8_t bytes[dyncal::kTableMaxBytes] = {};
};

template <typename Scalar>
void run_and_commit(DriveWorkspace<Scalar>& w) {
  int size = 0;
  ASSERT_EQ(dyncal::encode_table(true_table(), w.bytes, dyncal::kTableMaxBytes, &size), dyncal::TableStatus::ok);
  ASSERT_EQ(w.drive.commit(w.bytes, size), dyncal::TableStatus::ok);
  // A payload run watched by the collision monitor (thresholds 0: watched, never tripped).
  dyncal::drive::MonitorSettings monitor;
  monitor.gain = 50;
  ASSERT_TRUE(w.drive.start(dyncal::modbus_map::Command::identify_payload, run(2.0, 1, 100), monitor));
  while (w.drive.state() == dyncal::modbus_map::DriveState::playing) {
    if (!w.drive.wants_period()) w.drive.ack(w.drive.produced());
    w.drive.period();
    w.drive.publish_inputs(w.inputs);
    w.drive.publish_window(w.window);
  }
  EXPECT_EQ(w.drive.produced(), 50u);  // 0.5 s at 100 Hz
  EXPECT_NE(w.drive.payload_state(), dyncal::modbus_map::PayloadState::running);
}

TEST(NoMalloc, DriveApplicationAllocatesNothing) {
  auto wd = std::make_unique<DriveWorkspace<double>>();
  auto wf = std::make_unique<DriveWorkspace<float>>();
  EXPECT_EQ(allocations_during([&] {
              run_and_commit(*wd);
              run_and_commit(*wf);
            }),
            0);
}

}  // namespace
