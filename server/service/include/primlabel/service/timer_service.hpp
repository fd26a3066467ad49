#pragma once
// One thread for the timers of every call (idle, receive rate, send and request deadlines):
// a call schedules a callback at a time and may cancel it. Callbacks run on the timer thread,
// one at a time, and must be short; they may schedule and cancel timers themselves.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <thread>
#include <utility>

namespace primlabel::service {

class TimerService {
 public:
  using Clock = std::chrono::steady_clock;
  using Id = std::uint64_t;

  TimerService();
  ~TimerService();  // pending callbacks are dropped without running
  TimerService(const TimerService&) = delete;
  TimerService& operator=(const TimerService&) = delete;

  Id schedule(Clock::time_point when, std::function<void()> callback);
  // Drops a pending timer; no effect once it ran or began to run.
  void cancel(Id id);
  std::size_t pending() const;

 private:
  void run(std::stop_token stop);

  mutable std::mutex mutex_;
  std::condition_variable_any wake_;
  std::map<std::pair<Clock::time_point, Id>, std::function<void()>> timers_;
  std::map<Id, Clock::time_point> when_;
  Id next_id_ = 1;
  std::jthread thread_;  // last: stops and joins before the maps go
};

}  // namespace primlabel::service
