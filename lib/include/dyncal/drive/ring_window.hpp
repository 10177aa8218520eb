#pragma once
// The ring window's codec: how a drive packs its oldest unacknowledged samples into the holding
// registers `ring` (docs/modbus.md "Measurement stream") and how a host unpacks them. The one codec
// both ends use: the drive application (register_server.hpp's drives) encodes, port/linux's Modbus
// client decodes. Heap-free, exception-free.
//
// Window layout (modbus_map::kRingWords registers): u32 first seq, u16 count n, u16 state
// (DriveState), u32 produced, u32 overruns, then n consecutive samples of N joints:
//   float32: f32 q[N] [rad], f32 qd[N] [rad/s], f32 tau[N] [Nm]          (6 N registers)
//   counts:  i32 q[N] [counts of q_resolution], i16 tau[N] [counts of tau_resolution]  (3 N)

#include <cmath>
#include <cstdint>

#include "dyncal/modbus_map.hpp"
#include "dyncal/port.hpp"

namespace dyncal::drive {

/// The window's header: the drive's state and counters at the same instant as its samples.
struct RingWindowHeader {
  std::uint32_t first = 0;  ///< seq of the window's first sample (produced when the window is empty)
  std::uint16_t count = 0;  ///< samples in the window
  modbus_map::DriveState state = modbus_map::DriveState::idle;
  std::uint32_t produced = 0;  ///< samples recorded since the start (the next seq)
  std::uint32_t overruns = 0;  ///< samples dropped because the ring was full
};

inline void encode_ring_header(const RingWindowHeader& h, std::uint16_t* w) noexcept {
  modbus_map::set_u32(w, h.first);
  w[2] = h.count;
  w[3] = static_cast<std::uint16_t>(h.state);
  modbus_map::set_u32(w + 4, h.produced);
  modbus_map::set_u32(w + 6, h.overruns);
}

inline RingWindowHeader decode_ring_header(const std::uint16_t* w) noexcept {
  RingWindowHeader h;
  h.first = modbus_map::get_u32(w);
  h.count = w[2];
  h.state = static_cast<modbus_map::DriveState>(w[3]);
  h.produced = modbus_map::get_u32(w + 4);
  h.overruns = modbus_map::get_u32(w + 6);
  return h;
}

/// Resolutions of format counts per joint (input registers q_resolution [rad], tau_resolution [Nm]).
struct RingResolution {
  float q[modbus_map::kMaxJoints] = {};
  float tau[modbus_map::kMaxJoints] = {};
};

/// Packs sample `s` of `joints` joints at p[0, sample_words(joints, format)). Counts: q rounded to
/// its counts (kQInvalid when not finite or beyond an i32), tau rounded and saturated at
/// +-kTauFullScale as an ADC saturates (a NaN torque reads full scale); qd is not sent.
inline void encode_ring_sample(const port::DriveSample& s, int joints, modbus_map::RingFormat format,
                               const RingResolution& res, std::uint16_t* p) noexcept {
  namespace mm = modbus_map;
  for (int j = 0; j < joints; ++j) {
    if (format == mm::RingFormat::float32) {
      mm::set_f32(p + 2 * j, s.q[j]);
      mm::set_f32(p + 2 * (joints + j), s.qd[j]);
      mm::set_f32(p + 2 * (2 * joints + j), s.tau[j]);
      continue;
    }
    const double q = std::round(static_cast<double>(s.q[j]) / static_cast<double>(res.q[j]));
    const double tau = std::round(static_cast<double>(s.tau[j]) / static_cast<double>(res.tau[j]));
    const bool q_fits = std::fabs(q) <= 2147483647.0;  // false for NaN too
    mm::set_u32(p + 2 * j, static_cast<std::uint32_t>(q_fits ? static_cast<std::int32_t>(q) : mm::kQInvalid));
    const double full = mm::kTauFullScale;
    const double saturated = std::isnan(tau) ? full : tau < -full ? -full : tau > full ? full : tau;
    p[2 * joints + j] = static_cast<std::uint16_t>(static_cast<std::int16_t>(saturated));
  }
}

/// Unpacks the sample at p into `s` (seq left to the caller). Counts: qd is NaN (the host
/// differentiates), an invalid q decodes as NaN; returns a bit per joint whose torque reads full
/// scale (saturated), 0 in format float32.
inline std::uint32_t decode_ring_sample(const std::uint16_t* p, int joints, modbus_map::RingFormat format,
                                        const RingResolution& res, port::DriveSample& s) noexcept {
  namespace mm = modbus_map;
  std::uint32_t saturated = 0;
  for (int j = 0; j < joints; ++j) {
    if (format == mm::RingFormat::float32) {
      s.q[j] = mm::get_f32(p + 2 * j);
      s.qd[j] = mm::get_f32(p + 2 * (joints + j));
      s.tau[j] = mm::get_f32(p + 2 * (2 * joints + j));
      continue;
    }
    const auto q = static_cast<std::int32_t>(mm::get_u32(p + 2 * j));
    const auto tau = static_cast<std::int16_t>(p[2 * joints + j]);
    s.q[j] = q == mm::kQInvalid ? NAN : static_cast<float>(q * static_cast<double>(res.q[j]));
    s.qd[j] = NAN;
    s.tau[j] = static_cast<float>(tau * static_cast<double>(res.tau[j]));
    if (tau >= mm::kTauFullScale || tau <= -mm::kTauFullScale) saturated |= 1u << j;
  }
  return saturated;
}

/// Fills the window w[0, kRingWords) from a ring of samples (`ring[k]` the k-th oldest
/// unacknowledged, with .seq; `size` of them): the oldest consecutive samples up to the first gap
/// (samples dropped by a full ring) and at most a block's worth, behind the header of this instant
/// (`header.first`, `header.count` set here). Registers past the samples are 0.
template <typename Ring>
void encode_ring_window(const Ring& ring, std::size_t size, RingWindowHeader header, int joints,
                        modbus_map::RingFormat format, const RingResolution& res, std::uint16_t* w) noexcept {
  namespace mm = modbus_map;
  for (int k = 0; k < mm::kRingWords; ++k) w[k] = 0;
  header.first = size == 0 ? header.produced : ring[0].seq;
  int n = 0;
  const int per_block = mm::samples_per_block(joints, format);
  while (n < per_block && static_cast<std::size_t>(n) < size &&
         ring[static_cast<std::size_t>(n)].seq == header.first + static_cast<std::uint32_t>(n))
    ++n;
  header.count = static_cast<std::uint16_t>(n);
  encode_ring_header(header, w);
  std::uint16_t* p = w + mm::kRingHeaderWords;
  for (int k = 0; k < n; ++k, p += mm::sample_words(joints, format))
    encode_ring_sample(ring[static_cast<std::size_t>(k)], joints, format, res, p);
}

}  // namespace dyncal::drive
