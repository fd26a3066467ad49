#include "primlabel/service/free_memory.hpp"

#include <malloc.h>

#include <atomic>
#include <mutex>
#include <utility>

namespace primlabel::service {

struct IdleMemoryTrimmer::State {
  std::mutex mutex;
  TimerService::Id pending = 0;  // 0: no trim scheduled
  std::uint64_t generation = 0;  // of the latest schedule: an older timer that ran anyway yields
  std::atomic<std::uint64_t> trims{0};
};

IdleMemoryTrimmer::IdleMemoryTrimmer(TimerService& timers, std::chrono::milliseconds quiet)
    : timers_(timers), quiet_(quiet), state_(std::make_shared<State>()) {}

IdleMemoryTrimmer::~IdleMemoryTrimmer() {
  std::lock_guard lock(state_->mutex);
  if (state_->pending) timers_.cancel(std::exchange(state_->pending, 0));
}

void IdleMemoryTrimmer::released(std::uint64_t points) {
  if (points < kTrimAfterPoints) return;
  std::lock_guard lock(state_->mutex);
  if (state_->pending) timers_.cancel(state_->pending);
  const std::uint64_t generation = ++state_->generation;
  // The callback holds only the shared state: nothing it touches can be gone when it runs.
  state_->pending = timers_.schedule(TimerService::Clock::now() + quiet_,
                                     [weak = std::weak_ptr<State>(state_), generation] {
                                       const std::shared_ptr<State> state = weak.lock();
                                       if (!state) return;
                                       {
                                         std::lock_guard lock(state->mutex);
                                         if (state->generation != generation)
                                           return;  // a later request moved the trim
                                         state->pending = 0;
                                       }
                                       malloc_trim(0);
                                       ++state->trims;
                                     });
}

std::uint64_t IdleMemoryTrimmer::trims() const { return state_->trims.load(); }

}  // namespace primlabel::service
