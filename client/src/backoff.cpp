#include "primlabel/client/backoff.hpp"

#include <algorithm>
#include <cmath>

namespace primlabel::client {

Backoff::Backoff(BackoffPolicy policy, std::uint64_t seed) : policy_(policy), rng_(seed) {}

std::chrono::milliseconds Backoff::nominal(int n) const {
  const double initial = static_cast<double>(policy_.initial.count());
  const double cap = static_cast<double>(policy_.max.count());
  // pow overflows to inf for large n; min() keeps it at the cap.
  const double delay = std::min(cap, initial * std::pow(std::max(1.0, policy_.multiplier), n));
  return std::chrono::milliseconds(static_cast<std::int64_t>(delay));
}

std::chrono::milliseconds Backoff::next() {
  const double centre = static_cast<double>(nominal(retries_++).count());
  const double jitter = std::clamp(policy_.jitter, 0.0, 1.0);
  std::uniform_real_distribution<double> factor(1.0 - jitter, 1.0 + jitter);
  const double delay = std::min(static_cast<double>(policy_.max.count()), centre * factor(rng_));
  return std::chrono::milliseconds(static_cast<std::int64_t>(delay));
}

void Backoff::reset() { retries_ = 0; }

}  // namespace primlabel::client
