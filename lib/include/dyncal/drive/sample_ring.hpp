#pragma once
// The drive's sample ring: the samples recorded since the run started and not yet acknowledged by
// the host, oldest first, in fixed storage (`Capacity` samples; docs/modbus.md "Measurement
// stream"). The drive records into it at the sample rate and frees what an acknowledgement covers;
// the ring window (ring_window.hpp) shows its oldest samples. Heap-free, exception-free.

#include <cstddef>
#include <cstdint>
#include <iterator>

#include "dyncal/port.hpp"

namespace dyncal::drive {

template <std::size_t Capacity>
class SampleRing {
  static_assert(Capacity >= 1, "a ring holds at least one sample");

 public:
  using value_type = port::DriveSample;

  /// An empty ring. User-provided so that value-initialisation (make_unique, `{}`) does not zero
  /// the storage: only held samples are ever read.
  SampleRing() noexcept {}

  /// Samples held.
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }
  static constexpr std::size_t capacity() noexcept { return Capacity; }
  /// The k-th oldest sample (k < size()).
  const port::DriveSample& operator[](std::size_t k) const noexcept { return samples_[(head_ + k) % Capacity]; }
  const port::DriveSample& front() const noexcept { return (*this)[0]; }
  const port::DriveSample& back() const noexcept { return (*this)[size_ - 1]; }

  /// Appends `s`; false (nothing stored) when the ring is full.
  bool push_back(const port::DriveSample& s) noexcept {
    if (size_ == Capacity) return false;
    samples_[(head_ + size_) % Capacity] = s;
    ++size_;
    return true;
  }
  /// Frees the oldest sample (none when empty).
  void pop_front() noexcept {
    if (size_ == 0) return;
    head_ = (head_ + 1) % Capacity;
    --size_;
  }
  void clear() noexcept { head_ = size_ = 0; }

  /// Oldest-first iteration.
  class const_iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = port::DriveSample;
    using difference_type = std::ptrdiff_t;
    using pointer = const port::DriveSample*;
    using reference = const port::DriveSample&;
    const_iterator(const SampleRing& r, std::size_t k) noexcept : r_(&r), k_(k) {}
    const port::DriveSample& operator*() const noexcept { return (*r_)[k_]; }
    const port::DriveSample* operator->() const noexcept { return &(*r_)[k_]; }
    const_iterator& operator++() noexcept {
      ++k_;
      return *this;
    }
    bool operator==(const const_iterator& o) const noexcept { return k_ == o.k_; }
    bool operator!=(const const_iterator& o) const noexcept { return k_ != o.k_; }

   private:
    const SampleRing* r_;
    std::size_t k_;
  };
  const_iterator begin() const noexcept { return const_iterator(*this, 0); }
  const_iterator end() const noexcept { return const_iterator(*this, size_); }

 private:
  port::DriveSample samples_[Capacity];
  std::size_t head_ = 0, size_ = 0;
};

}  // namespace dyncal::drive
