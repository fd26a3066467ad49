#include "primlabel/service/timer_service.hpp"

#include "primlabel/ops/logging.hpp"

namespace primlabel::service {

TimerService::TimerService() : thread_([this](std::stop_token stop) { run(stop); }) {}

TimerService::~TimerService() {
  thread_.request_stop();
  wake_.notify_all();
}

TimerService::Id TimerService::schedule(Clock::time_point when, std::function<void()> callback) {
  Id id;
  bool earliest;
  {
    std::lock_guard lock(mutex_);
    id = next_id_++;
    auto placed = timers_.emplace(std::make_pair(when, id), std::move(callback)).first;
    when_.emplace(id, when);
    earliest = placed == timers_.begin();
  }
  if (earliest) wake_.notify_all();
  return id;
}

void TimerService::cancel(Id id) {
  std::lock_guard lock(mutex_);
  const auto found = when_.find(id);
  if (found == when_.end()) return;
  timers_.erase({found->second, id});
  when_.erase(found);
}

std::size_t TimerService::pending() const {
  std::lock_guard lock(mutex_);
  return timers_.size();
}

void TimerService::run(std::stop_token stop) {
  std::unique_lock lock(mutex_);
  while (!stop.stop_requested()) {
    if (timers_.empty()) {
      wake_.wait(lock, stop, [this] { return !timers_.empty(); });
      continue;
    }
    const auto first = timers_.begin();
    if (Clock::now() < first->first.first) {
      const Clock::time_point due = first->first.first;
      // Woken early by an earlier timer, a cancel or the stop; then look again.
      wake_.wait_until(lock, stop, due, [this, due] {
        return timers_.empty() || timers_.begin()->first.first < due;
      });
      continue;
    }
    std::function<void()> callback = std::move(first->second);
    when_.erase(first->first.second);
    timers_.erase(first);
    lock.unlock();
    try {
      callback();
    } catch (const std::exception& e) {  // a timer must never take the thread down
      ops::log_error("timer_failed").kv("error", e.what());
    } catch (...) {
      ops::log_error("timer_failed").kv("error", "unknown exception");
    }
    callback = nullptr;  // its captures go outside the lock, too
    lock.lock();
  }
}

}  // namespace primlabel::service
