// The idle memory trim: after a large request only, once the server has been quiet.

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "primlabel/service/free_memory.hpp"

namespace primlabel::service {
namespace {

using std::chrono::milliseconds;

// Polls (bounded, 5 s) until `trimmer` has trimmed `count` times.
bool wait_for_trims(const IdleMemoryTrimmer& trimmer, std::uint64_t count) {
  for (int i = 0; i < 500 && trimmer.trims() < count; ++i)
    std::this_thread::sleep_for(milliseconds(10));
  return trimmer.trims() >= count;
}

TEST(IdleMemoryTrimmer, TrimsOnceAfterTheLastLargeRequestOfABurst) {
  TimerService timers;
  IdleMemoryTrimmer trimmer(timers, milliseconds(50));
  for (int i = 0; i < 5; ++i) trimmer.released(kTrimAfterPoints);  // one burst: one trim
  EXPECT_TRUE(wait_for_trims(trimmer, 1));
  std::this_thread::sleep_for(milliseconds(150));
  EXPECT_EQ(trimmer.trims(), 1u);
  EXPECT_EQ(timers.pending(), 0u);
  trimmer.released(2 * kTrimAfterPoints);  // a later request trims again
  EXPECT_TRUE(wait_for_trims(trimmer, 2));
}

TEST(IdleMemoryTrimmer, SmallRequestsNeverTrim) {
  TimerService timers;
  IdleMemoryTrimmer trimmer(timers, milliseconds(1));
  trimmer.released(kTrimAfterPoints - 1);
  trimmer.released(0);
  EXPECT_EQ(timers.pending(), 0u);
  std::this_thread::sleep_for(milliseconds(30));
  EXPECT_EQ(trimmer.trims(), 0u);
}

TEST(IdleMemoryTrimmer, WaitsForTheQuietPeriod) {
  TimerService timers;
  IdleMemoryTrimmer trimmer(timers, std::chrono::hours(1));
  trimmer.released(kTrimAfterPoints);
  EXPECT_EQ(timers.pending(), 1u);
  std::this_thread::sleep_for(milliseconds(30));
  EXPECT_EQ(trimmer.trims(), 0u);
}

TEST(IdleMemoryTrimmer, APendingTrimGoesWithTheTrimmer) {
  TimerService timers;
  {
    IdleMemoryTrimmer trimmer(timers, std::chrono::hours(1));
    trimmer.released(kTrimAfterPoints);
  }
  EXPECT_EQ(timers.pending(), 0u);
}

}  // namespace
}  // namespace primlabel::service
