#pragma once
// Bounded concurrency: a fixed pool of worker threads runs labeling jobs, and at most
// workers + queue requests hold a compute slot at once (from their complete scan until their
// result is computed; streams still receiving points count in their own budget, SlotBudget).
// Admission beyond that fails at once, for the caller to answer RESOURCE_EXHAUSTED.

#include <chrono>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>
#include <vector>

namespace primlabel::service {

class Admission {
 public:
  // Called (under no lock of the caller) whenever the counts change.
  using Observer = std::function<void(int admitted, int queued)>;

  Admission(int workers, int queue_capacity, Observer observer = {});
  ~Admission();  // finishes the running jobs, drops queued ones
  Admission(const Admission&) = delete;
  Admission& operator=(const Admission&) = delete;

  // A place among the admitted requests, held until destroyed.
  class Ticket {
   public:
    Ticket(Ticket&& other) noexcept : admission_(std::exchange(other.admission_, nullptr)) {}
    Ticket& operator=(Ticket&& other) noexcept {
      if (this != &other) {
        release();
        admission_ = std::exchange(other.admission_, nullptr);
      }
      return *this;
    }
    ~Ticket() { release(); }

   private:
    friend class Admission;
    explicit Ticket(Admission* admission) : admission_(admission) {}
    void release();
    Admission* admission_;
  };

  // A submitted job: wait for it, or abandon it (Admission::abandon) while it still waits.
  class Job {
   public:
    // True when the job has finished (ran to its end, or was abandoned before starting).
    bool wait_for(std::chrono::milliseconds timeout);

   private:
    friend class Admission;
    enum class State { kQueued, kRunning, kDone, kAbandoned };
    std::function<void()> work_;
    std::mutex mutex_;
    std::condition_variable done_;
    State state_ = State::kQueued;
  };

  std::optional<Ticket> try_admit();

  // Queues `work` for a worker; the ticket proves admission. `work` must not throw.
  std::shared_ptr<Job> submit(const Ticket& ticket, std::function<void()> work);
  // Takes the job out of the queue if no worker started it yet; true if so (its work never runs).
  bool abandon(const std::shared_ptr<Job>& job);

  int admitted() const;
  int queued() const;
  int workers() const { return int(threads_.size()); }
  int capacity() const { return capacity_; }

 private:
  void worker_loop();
  void notify();

  const int capacity_;
  Observer observer_;
  mutable std::mutex mutex_;
  std::condition_variable work_ready_;
  std::deque<std::shared_ptr<Job>> queue_;
  int admitted_ = 0;
  int waiting_ = 0;  // submitted jobs no worker started yet
  bool stopping_ = false;
  std::vector<std::thread> threads_;
};

}  // namespace primlabel::service
