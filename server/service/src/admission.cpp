#include "primlabel/service/admission.hpp"

#include <algorithm>
#include <utility>

namespace primlabel::service {

Admission::Admission(int workers, int queue_capacity, Observer observer)
    : capacity_(std::max(1, workers) + std::max(0, queue_capacity)),
      observer_(std::move(observer)) {
  for (int i = 0; i < std::max(1, workers); ++i) threads_.emplace_back([this] { worker_loop(); });
}

Admission::~Admission() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (std::thread& thread : threads_) thread.join();
  while (!queue_.empty()) {
    const std::shared_ptr<Job> job = queue_.front();
    abandon(job);
  }
}

void Admission::Ticket::release() {
  if (!admission_) return;
  {
    std::lock_guard lock(admission_->mutex_);
    --admission_->admitted_;
  }
  std::exchange(admission_, nullptr)->notify();
}

std::optional<Admission::Ticket> Admission::try_admit() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_ || admitted_ >= capacity_) return std::nullopt;
    ++admitted_;
  }
  notify();
  return Ticket(this);
}

std::shared_ptr<Admission::Job> Admission::submit(const Ticket&, std::function<void()> work) {
  auto job = std::make_shared<Job>();
  job->work_ = std::move(work);
  {
    std::lock_guard lock(mutex_);
    queue_.push_back(job);
    ++waiting_;
  }
  work_ready_.notify_one();
  notify();
  return job;
}

bool Admission::Job::wait_for(std::chrono::milliseconds timeout) {
  std::unique_lock lock(mutex_);
  return done_.wait_for(lock, timeout,
                        [this] { return state_ == State::kDone || state_ == State::kAbandoned; });
}

bool Admission::abandon(const std::shared_ptr<Job>& job) {
  {
    std::lock_guard lock(mutex_);
    auto queued = std::find(queue_.begin(), queue_.end(), job);
    if (queued == queue_.end()) return false;  // a worker has it
    queue_.erase(queued);
    --waiting_;
    std::lock_guard job_lock(job->mutex_);
    job->state_ = Job::State::kAbandoned;
    job->work_ = nullptr;
  }
  job->done_.notify_all();
  notify();
  return true;
}

void Admission::worker_loop() {
  for (;;) {
    std::shared_ptr<Job> job;
    {
      std::unique_lock lock(mutex_);
      work_ready_.wait(lock, [this] { return stopping_ || !queue_.empty(); });
      if (stopping_) return;
      job = std::move(queue_.front());
      queue_.pop_front();
      --waiting_;
      std::lock_guard job_lock(job->mutex_);
      job->state_ = Job::State::kRunning;  // under the queue lock: abandon() sees it gone
    }
    notify();
    job->work_();
    {
      std::lock_guard lock(job->mutex_);
      job->state_ = Job::State::kDone;
      job->work_ = nullptr;
    }
    job->done_.notify_all();
  }
}

int Admission::admitted() const {
  std::lock_guard lock(mutex_);
  return admitted_;
}

int Admission::queued() const {
  std::lock_guard lock(mutex_);
  return waiting_;
}

void Admission::notify() {
  if (!observer_) return;
  int admitted, queued;
  {
    std::lock_guard lock(mutex_);
    admitted = admitted_;
    queued = waiting_;
  }
  observer_(admitted, queued);
}

}  // namespace primlabel::service
