#pragma once
// Lets another thread cancel a call that may be between attempts (sleeping in its backoff) or in
// the middle of one (its ClientContext is cancelled).

#include <grpcpp/client_context.h>

#include <chrono>
#include <condition_variable>
#include <mutex>

namespace primlabel::client {

class CallControl {
 public:
  void cancel() {
    std::lock_guard lock(mutex_);
    cancelled_ = true;
    if (context_) context_->TryCancel();
    wake_.notify_all();
  }
  bool cancelled() const {
    std::lock_guard lock(mutex_);
    return cancelled_;
  }
  // Registers the attempt's context; false when the call was cancelled already.
  bool attach(grpc::ClientContext* context) {
    std::lock_guard lock(mutex_);
    if (cancelled_) return false;
    context_ = context;
    return true;
  }
  void detach() {
    std::lock_guard lock(mutex_);
    context_ = nullptr;
  }
  // Sleeps for `delay` unless cancelled first; false when cancelled.
  bool sleep_for(std::chrono::milliseconds delay) {
    std::unique_lock lock(mutex_);
    return !wake_.wait_for(lock, delay, [&] { return cancelled_; });
  }

 private:
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  grpc::ClientContext* context_ = nullptr;
  bool cancelled_ = false;
};

}  // namespace primlabel::client
