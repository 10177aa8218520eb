#pragma once
// The drive's RTU line receiver: the bytes a serial line delivers in, the requests to answer out
// (MODBUS over Serial Line v1.02, sec. 2.5.1). Frames are delimited by their function's length and
// CRC (modbus_frames.hpp next_rtu_request), not by the t3.5 silence alone: under emulation and on
// USB adapters the gaps inside one frame exceed t3.5. The silence still ends what length cannot:
// a frame that cannot be taken (a wrong CRC, an impossible length, bytes that stop mid-frame) is
// dropped with everything after it until the line has been silent for `resync_us`; a function
// whose length its code does not give ends at that silence. Heap-free: `Capacity` bytes, at least
// one ADU (kMaxRtuAduBytes); time from the port's microsecond clock.

#include <cstddef>
#include <cstdint>

#include "dyncal/drive/modbus_frames.hpp"

namespace dyncal::drive {

template <std::size_t Capacity = 2 * kMaxRtuAduBytes>
class RtuReceiver {
  static_assert(Capacity >= kMaxRtuAduBytes, "the receiver holds at least one ADU");

 public:
  /// `address`: the drive's unit (slave) address, 1..247; `resync_us`: the silence [us] that ends
  /// a frame length cannot end (at least t3.5, rtu_silence_us; on real hardware t3.5 itself).
  RtuReceiver(std::uint8_t address, std::uint64_t resync_us) noexcept : address_(address), resync_us_(resync_us) {}

  /// Bytes that arrived at `now` [us].
  void push(const std::uint8_t* bytes, std::size_t n, std::uint64_t now) noexcept {
    if (n == 0) return;
    last_byte_ = now;
    if (resync_) return;  // still inside the bytes of a dropped frame
    for (std::size_t k = 0; k < n; ++k) {
      if (size_ == Capacity) {  // more than a frame without one: not a request, resynchronise
        size_ = 0;
        resync_ = true;
        return;
      }
      buf_[size_++] = bytes[k];
    }
  }

  /// Hands every request for this drive that the bytes so far complete to `answer(adu, length)`
  /// (address, PDU, CRC; the CRC checked); requests for other addresses are skipped. Call after
  /// push() and whenever time passes (a silence ends frames too). Returns the requests handed over.
  template <typename Answer>
  int poll(std::uint64_t now, Answer&& answer) noexcept {
    const bool silent = now > last_byte_ && now - last_byte_ > resync_us_;  // a clock that steps back is no silence
    if (resync_) {
      if (silent) resync_ = false;
      return 0;
    }
    int answered = 0;
    while (size_ > 0) {
      const RtuFrame f = next_rtu_request(buf_, size_);
      if (f.status == RtuFrame::Status::complete && f.crc_ok) {
        if (f.address == address_) {
          answer(static_cast<const std::uint8_t*>(buf_), f.bytes);
          ++answered;
        }
        consume(f.bytes);
        continue;
      }
      if (f.status == RtuFrame::Status::needs_silence && silent && size_ >= 4) {
        // A function whose length its code does not give ends at the silence: answered (illegal
        // function) when its CRC holds.
        if (crc16_holds(buf_, size_) && buf_[0] == address_) {
          answer(static_cast<const std::uint8_t*>(buf_), size_);
          ++answered;
        }
        size_ = 0;
        return answered;
      }
      if (f.status == RtuFrame::Status::incomplete ||
          (f.status == RtuFrame::Status::needs_silence && size_ <= kMaxRtuAduBytes)) {
        if (silent) size_ = 0;  // the rest of the frame never came
        return answered;
      }
      size_ = 0;  // a wrong CRC or an impossible length: resynchronise at the next silence
      resync_ = !silent;
      return answered;
    }
    return answered;
  }

  /// Bytes held (a partial frame).
  std::size_t pending() const noexcept { return size_; }

 private:
  void consume(std::size_t n) noexcept {
    for (std::size_t k = n; k < size_; ++k) buf_[k - n] = buf_[k];
    size_ -= n;
  }

  std::uint8_t address_;
  std::uint64_t resync_us_;
  std::uint8_t buf_[Capacity] = {};
  std::size_t size_ = 0;
  std::uint64_t last_byte_ = 0;
  bool resync_ = false;
};

}  // namespace dyncal::drive
