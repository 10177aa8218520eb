// The same calibration over Modbus RTU: on a pseudo-terminal pair (socat), and on a serial line at
// 115 200 baud (tests/support/serial_line_relay.cpp) where a six-joint 1 kHz stream does not fit
// live and calibrate traces its runs. And the choice between live and trace itself (stream_plan.hpp).
#include <gtest/gtest.h>
#include <modbus/modbus.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <random>
#include <sstream>
#include <vector>

#include "dyncal/drive/modbus_frames.hpp"
#include "dyncal/modbus_map.hpp"
#include "dyncal_host/calibration/calibrate.hpp"
#include "dyncal_host/calibration/stream_plan.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace {

using namespace dyncal::host;

TEST(CalibrateRtu, CalibratesAndFlashesOverAPtyPair) {
  const char* device = std::getenv("DYNCAL_RTU_DEVICE");
  ASSERT_TRUE(device) << "run through ctest";
  const auto robot = load_robot(default_robots_dir(), "er20");
  CalibrateOptions o;
  o.uri = std::string("rtu:") + device;
  o.terms = parse_model("eq7,rotor_inertia,offset");
  o.sample_rate_hz = 100;  // the survey's rate; RTU frames are slower than TCP
  o.periods = 2;
  o.verify_periods = 1;
  o.progress = false;
  std::ostringstream progress;
  const CalibrateResult r = calibrate(robot, o, progress);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_EQ(r.samples, 2000);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  for (int j = 0; j < 6; ++j) EXPECT_LT(r.drive_error_after[j], 0.5 * r.drive_error_before[j]) << "joint " << j + 1;
  print_calibrate_report(std::cout, r);
}

// Noise on the line (issue 69: the drive application frames RTU requests by their length and CRC,
// dyncal/drive/modbus_frames.hpp): 4 000 random bytes, a request with a wrong CRC and one cut short
// reach the drive; none is answered, and after the line's silence the next request is answered with
// the active table unchanged.
TEST(CalibrateRtu, NoiseOnTheLineIsDroppedAndTheNextRequestIsAnswered) {
  const char* device = std::getenv("DYNCAL_RTU_DEVICE");
  ASSERT_TRUE(device) << "run through ctest";
  namespace mm = dyncal::modbus_map;
  modbus_t* ctx = modbus_new_rtu(device, 115200, 'N', 8, 1);
  ASSERT_TRUE(ctx && modbus_set_slave(ctx, 1) == 0 && modbus_connect(ctx) == 0);
  modbus_set_response_timeout(ctx, 1, 0);
  std::uint16_t before[2] = {}, after[2] = {};
  ASSERT_EQ(modbus_read_input_registers(ctx, mm::kActiveCrcReg, 2, before), 2) << modbus_strerror(errno);
  std::vector<std::uint8_t> noise(4000);
  std::mt19937 rng(69);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  // A read with its CRC's last byte flipped, and a 16 write that stops after its byte count.
  std::uint8_t bad[8] = {1, 0x04, 0, 0, 0, 2, 0, 0};
  const std::uint16_t crc = dyncal::drive::crc16(bad, 6);
  bad[6] = static_cast<std::uint8_t>(crc & 0xFF), bad[7] = static_cast<std::uint8_t>((crc >> 8) ^ 0x01);
  const std::uint8_t cut[7] = {1, 0x10, 0, 0, 0, 4, 8};
  const int fd = modbus_get_socket(ctx);
  for (const auto& [bytes, n] : {std::pair<const std::uint8_t*, std::size_t>{noise.data(), noise.size()},
                                 {bad, sizeof bad},
                                 {cut, sizeof cut}}) {
    ASSERT_EQ(::write(fd, bytes, n), static_cast<ssize_t>(n));
    ::usleep(100000);  // a silence: the drive resynchronises after 50 ms
  }
  std::uint8_t stray[64];
  EXPECT_LE(::read(fd, stray, sizeof stray), 0) << "the drive answered noise";
  ASSERT_EQ(modbus_read_input_registers(ctx, mm::kActiveCrcReg, 2, after), 2) << modbus_strerror(errno);
  EXPECT_EQ(before[0], after[0]);
  EXPECT_EQ(before[1], after[1]);
  modbus_close(ctx);
  modbus_free(ctx);
}

// Six joints at 1 kHz over 115 200 baud: the line carries about a quarter of the stream, so both
// runs are traced, and the calibration completes with every sample.
TEST(CalibrateRtuLine, SixJointsAtOneKilohertzAreTracedWithNoSampleLost) {
  const char* line = std::getenv("DYNCAL_RTU_LINE");  // BAUD:DEVICE
  ASSERT_TRUE(line && std::strchr(line, ':')) << "run through ctest";
  const double baud = std::atof(line);
  const std::string device = std::strchr(line, ':') + 1;
  const auto robot = load_robot(default_robots_dir(), "er20");
  CalibrateOptions o;
  o.uri = std::string("rtu:") + device;
  o.terms = parse_model("eq7,rotor_inertia,offset");
  o.sample_rate_hz = 1000;
  o.f_f = 0.5;  // 2 s periods: 4 000 excitation samples, about 16 s on this line
  o.periods = 2;
  o.verify_periods = 1;
  o.progress = false;
  std::ostringstream progress;
  const CalibrateResult r = calibrate(robot, o, progress);
  print_calibrate_report(std::cout, r);
  EXPECT_EQ(r.lost, 0u);
  EXPECT_EQ(r.samples, 4000);
  ASSERT_EQ(r.link.plans.size(), 2u);
  for (const auto& p : r.link.plans) EXPECT_NE(p.find(", traced:"), std::string::npos) << p;
  // The line's bound: a transaction's RTU bytes (ModbusDrive::LinkStats) at 10 bits a character.
  const int joints = 6,
            per_block = dyncal::modbus_map::samples_per_block(joints, dyncal::modbus_map::RingFormat::counts);
  const double transaction_bytes = (10 + 4) + (2 + 2 * dyncal::modbus_map::kRingWords) + 2 * 3;
  const double line_bound = baud / 10 / transaction_bytes * per_block;  // samples/s
  EXPECT_LE(r.link.capacity.samples_per_second, 1.01 * line_bound);
  EXPECT_LT(r.link.capacity.samples_per_second, o.sample_rate_hz);
  // The line really limited the upload, and full blocks kept the bytes near the payload (3 N
  // registers a sample).
  EXPECT_GE(r.stream_seconds, 0.99 * 4000 / line_bound);
  EXPECT_EQ(r.link.samples, 4000 + 2 * 2000);
  EXPECT_LE(static_cast<double>(r.link.bytes) / static_cast<double>(r.link.samples), 1.5 * 2 * 3 * joints);
  ASSERT_TRUE(r.flashed) << r.flash_message;
  for (int j = 0; j < joints; ++j)
    EXPECT_LT(r.drive_error_after[j], 0.5 * r.drive_error_before[j]) << "joint " << j + 1;
}

// The choice itself, on a link of 250 samples/s and a ring of 16 384 samples.
constexpr LinkCapacity kSlowLink{250.0, 0.024, 16384};

TEST(StreamPlan, ALinkThatCarriesTheRateStreamsLive) {
  const StreamPlan p = plan_stream(StreamMode::automatic, kSlowLink, "excitation", 20000, 200, 2);
  EXPECT_FALSE(p.trace);
  EXPECT_NE(p.line.find("live: the link carries about 250 samples/s"), std::string::npos) << p.line;
}

TEST(StreamPlan, ARunTheLinkCannotCarryIsTracedWhenTheRingHoldsIt) {
  const StreamPlan p = plan_stream(StreamMode::automatic, kSlowLink, "excitation", 16384, 1000, 2);
  EXPECT_TRUE(p.trace);
  // The upload ends when the line has carried 16 384 samples at 250 a second.
  EXPECT_NE(p.line.find("about 66 s after the start"), std::string::npos) << p.line;
}

TEST(StreamPlan, ALongerRunStreamsLiveWhenItsBacklogFitsTheRing) {
  // 20 s at 1 kHz against 250/s: the backlog reaches 15 000 samples, within 16 384.
  const StreamPlan p = plan_stream(StreamMode::automatic, kSlowLink, "excitation", 20000, 1000, 2);
  EXPECT_FALSE(p.trace);
  EXPECT_NE(p.line.find("about 15000 samples at the run's end"), std::string::npos) << p.line;
}

TEST(StreamPlan, ARunThatNeitherStreamsNorFitsIsRefusedWithWhatWould) {
  // 40 s at 1 kHz: a backlog of 30 000. At 500 Hz the run has 20 000 samples and a backlog of
  // 10 000, which fits; one period (20 000 samples at 1 kHz) does not fit a trace.
  try {
    plan_stream(StreamMode::automatic, kSlowLink, "excitation", 40000, 1000, 2);
    FAIL() << "no refusal";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("neither streams live nor fits a trace"), std::string::npos) << m;
    EXPECT_NE(m.find("--rate 500 would"), std::string::npos) << m;
    EXPECT_EQ(m.substr(m.size() - 5), "would") << m;  // no period count suggested: one period does not fit
  }
  // With four periods of 10 000 samples, one traces.
  try {
    plan_stream(StreamMode::automatic, LinkCapacity{50.0, 0.1, 16384}, "excitation", 40000, 1000, 4);
    FAIL() << "no refusal";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("or 1 period at this rate"), std::string::npos) << e.what();
  }
}

TEST(StreamPlan, ForcedTraceIsRefusedForARunTheRingCannotHold) {
  EXPECT_THROW(plan_stream(StreamMode::trace, kSlowLink, "excitation", 16385, 1000, 1), InputError);
  EXPECT_TRUE(plan_stream(StreamMode::trace, LinkCapacity{1e6, 1e-5, 16384}, "excitation", 16384, 1000, 1).trace);
  EXPECT_FALSE(plan_stream(StreamMode::live, kSlowLink, "excitation", 40000, 1000, 1).trace);
  EXPECT_THROW(parse_stream_mode("fast"), InputError);
}

}  // namespace
