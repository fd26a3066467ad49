#include "server_wait_progress.hpp"

#include <unistd.h>

#include <cstdio>

namespace primlabel::client::tools {

namespace {
using Clock = std::chrono::steady_clock;
constexpr auto kTtyAfter = std::chrono::seconds(1);
constexpr auto kTtyEvery = std::chrono::milliseconds(250);
constexpr auto kLogAfter = std::chrono::seconds(2);
constexpr auto kLogEvery = std::chrono::seconds(5);
}  // namespace

ServerWaitProgress::ServerWaitProgress(bool quiet, std::string what)
    : quiet_(quiet), tty_(isatty(STDERR_FILENO) == 1), what_(std::move(what)) {}

ServerWaitProgress::~ServerWaitProgress() { stop(); }

void ServerWaitProgress::start() {
  if (quiet_) return;
  std::lock_guard lock(mutex_);
  since_ = Clock::now();
  if (!thread_.joinable() && !stopping_) thread_ = std::thread([this] { run(); });
}

void ServerWaitProgress::stop() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (printed_ && tty_) std::fputc('\n', stderr);
  printed_ = false;
}

void ServerWaitProgress::run() {
  std::unique_lock lock(mutex_);
  Clock::duration next = tty_ ? Clock::duration(kTtyAfter) : Clock::duration(kLogAfter);
  auto started = since_;
  while (!stopping_) {
    if (since_ != started) {  // a retry sent the scan again: the wait starts over
      started = since_;
      next = tty_ ? Clock::duration(kTtyAfter) : Clock::duration(kLogAfter);
    }
    const auto waited = Clock::now() - since_;
    if (waited >= next) {
      if (tty_) {
        std::fprintf(stderr, "\r%s: waiting for the server: %.1f s", what_.c_str(),
                     std::chrono::duration<double>(waited).count());
        next = waited + kTtyEvery;
      } else {  // the mark passed, not the moment seen: logs read 2 s, 7 s, 12 s, ...
        std::fprintf(
            stderr, "%s: waiting for the server: %lld s\n", what_.c_str(),
            static_cast<long long>(std::chrono::duration_cast<std::chrono::seconds>(next).count()));
        next += kLogEvery;
      }
      std::fflush(stderr);
      printed_ = true;
    }
    wake_.wait_for(lock, std::chrono::milliseconds(50));
  }
}

}  // namespace primlabel::client::tools
