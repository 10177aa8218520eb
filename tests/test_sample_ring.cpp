// lib/'s sample ring (dyncal/drive/sample_ring.hpp) against a std::deque fed the same operations:
// the drive's ring keeps the same samples in the same order across wrap-arounds, refuses a push
// when full, and frees from the front.
#include <gtest/gtest.h>

#include <cstdint>
#include <deque>
#include <random>

#include "dyncal/drive/sample_ring.hpp"

// The suite in a namespace of its own: the program's suites compile as one unit (tests/CMakeLists.txt).
namespace {
namespace sample_ring_suite {

TEST(SampleRing, KeepsWhatADequeKeepsAcrossWrapArounds) {
  dyncal::drive::SampleRing<7> ring;
  std::deque<std::uint32_t> reference;
  std::mt19937 rng(3);
  std::uint32_t seq = 0;
  int refused = 0;
  for (int step = 0; step < 5000; ++step) {
    if (rng() % 3 != 0) {
      dyncal::port::DriveSample s{};
      s.seq = seq;
      s.q[0] = static_cast<float>(seq);
      const bool stored = ring.push_back(s);
      EXPECT_EQ(stored, reference.size() < 7);
      if (stored) reference.push_back(seq);
      refused += stored ? 0 : 1;
      ++seq;
    } else {
      ring.pop_front();
      if (!reference.empty()) reference.pop_front();
    }
    ASSERT_EQ(ring.size(), reference.size());
    std::size_t k = 0;
    for (const auto& s : ring) {
      ASSERT_EQ(s.seq, reference[k]);
      ASSERT_EQ(ring[k].q[0], static_cast<float>(reference[k]));
      ++k;
    }
  }
  EXPECT_GT(refused, 0);  // the sequence filled the ring at times
  ring.clear();
  EXPECT_TRUE(ring.empty());
}

}  // namespace sample_ring_suite
}  // namespace
