#pragma once
// Exponential backoff with jitter, as the client uses between attempts on UNAVAILABLE and the
// uploader between rounds while the server is away.

#include <chrono>
#include <cstdint>
#include <random>

namespace primlabel::client {

struct BackoffPolicy {
  std::chrono::milliseconds initial{200};
  double multiplier = 2.0;
  std::chrono::milliseconds max{5000};
  // Each delay is drawn uniformly from [d * (1 - jitter), d * (1 + jitter)], then capped at max,
  // so clients that lost the server together do not come back in lockstep.
  double jitter = 0.2;
};

// The delays of successive retries: the n-th (from 0) is initial * multiplier^n, capped at max,
// with jitter applied.
class Backoff {
 public:
  explicit Backoff(BackoffPolicy policy, std::uint64_t seed = std::random_device{}());

  std::chrono::milliseconds next();  // the delay before the next retry
  void reset();                      // after a success: start again from `initial`
  int retries() const { return retries_; }

  // The delay before retry n without jitter (the centre of the jitter window).
  std::chrono::milliseconds nominal(int n) const;

 private:
  BackoffPolicy policy_;
  std::mt19937_64 rng_;
  int retries_ = 0;
};

}  // namespace primlabel::client
