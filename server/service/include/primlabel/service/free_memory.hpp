#pragma once
// Gives the heap's free pages back to the system once the server has gone quiet after a large
// request. glibc keeps freed memory of big requests in its arenas (hundreds of MB after one
// multi-million-point scan), so a container's memory limit would see an idle server as full. The
// trim waits for a pause: trimming after every request made the next one fault all its pages in
// again, most of the service's overhead on a frame (docs/development.md, "Figures behind the
// code").

#include <chrono>
#include <cstdint>
#include <memory>

#include "primlabel/service/timer_service.hpp"

namespace primlabel::service {

// Requests below this many points free too little to be worth a trim (a few ms).
inline constexpr std::uint64_t kTrimAfterPoints = 100'000;
// How long no large request must have ended before the trim: longer than the gap between the
// frames of a sensor streamed at 1 Hz or more, short enough that an idle server shrinks at once.
inline constexpr std::chrono::milliseconds kTrimWhenQuietFor{1000};

class IdleMemoryTrimmer {
 public:
  explicit IdleMemoryTrimmer(TimerService& timers,
                             std::chrono::milliseconds quiet = kTrimWhenQuietFor);
  ~IdleMemoryTrimmer();  // a pending trim is dropped
  IdleMemoryTrimmer(const IdleMemoryTrimmer&) = delete;
  IdleMemoryTrimmer& operator=(const IdleMemoryTrimmer&) = delete;

  // A request of `points` points let its memory go: a large one (re)starts the quiet period,
  // at whose end the free heap pages go back to the system (on the timer thread).
  void released(std::uint64_t points);
  std::uint64_t trims() const;  // trims done so far

 private:
  struct State;
  TimerService& timers_;
  const std::chrono::milliseconds quiet_;
  std::shared_ptr<State> state_;  // shared with a pending timer, which may outlive this object
};

}  // namespace primlabel::service
