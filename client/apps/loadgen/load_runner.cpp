#include "load_runner.hpp"

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

namespace primlabel::client::loadgen {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

// When a step must stop issuing calls: its duration, or the hard cap.
Clock::time_point end_of(const LoadSpec& spec, Clock::time_point start) {
  double limit = spec.max_duration_s;
  if (spec.duration_s > 0) limit = std::min(limit, spec.duration_s);
  return start + std::chrono::microseconds(static_cast<long long>(limit * 1e6));
}

StepResult run_closed(Client& client, const std::vector<PointCloud>& clouds, const LoadSpec& spec) {
  const auto start = Clock::now();
  const auto end = end_of(spec, start);
  std::atomic<std::uint64_t> tickets{0};
  std::vector<LoadStats> per_caller(std::max(1, spec.concurrency));
  std::vector<std::thread> callers;
  for (std::size_t c = 0; c < per_caller.size(); ++c) {
    callers.emplace_back([&, c] {
      // Seeded by the caller's index: the same run draws the same delays.
      Backoff backoff(spec.rejection_backoff, c + 1);
      while (Clock::now() < end) {
        const std::uint64_t ticket = tickets++;
        if (spec.requests > 0 && ticket >= spec.requests) break;
        const PointCloud& cloud = clouds[ticket % clouds.size()];
        const auto sent = Clock::now();
        try {
          const LabelResult result =
              spec.unary ? client.label_unary(cloud, spec.label) : client.label(cloud, spec.label);
          per_caller[c].record_ok(seconds_between(sent, Clock::now()), result.size());
          backoff.reset();
        } catch (const ClientError& e) {
          per_caller[c].record_error(status_code_name(e.code()));
          // A full server answers at once; resending at once would only measure rejections.
          if (e.code() == grpc::StatusCode::RESOURCE_EXHAUSTED)
            std::this_thread::sleep_until(std::min(end, Clock::now() + backoff.next()));
        }
      }
    });
  }
  for (auto& t : callers) t.join();
  StepResult result{spec, seconds_between(start, Clock::now()), {}};
  for (const auto& s : per_caller) result.stats.merge(s);
  return result;
}

StepResult run_open(Client& client, const std::vector<PointCloud>& clouds, const LoadSpec& spec) {
  std::mutex mutex;
  std::condition_variable drained;
  LoadStats stats;
  int outstanding = 0;
  std::vector<CallHandle> calls;
  const auto start = Clock::now();
  const auto end = end_of(spec, start);
  const auto interval = std::chrono::duration<double>(1.0 / std::max(spec.rate, 1e-3));
  for (std::uint64_t k = 0; spec.requests == 0 || k < spec.requests; ++k) {
    const auto scheduled = start + std::chrono::duration_cast<Clock::duration>(interval * k);
    if (scheduled >= end) break;
    std::this_thread::sleep_until(scheduled);
    {
      std::lock_guard lock(mutex);
      if (outstanding >= spec.max_outstanding) {
        stats.record_skipped();
        continue;
      }
      ++outstanding;
    }
    calls.push_back(client.label_async(
        clouds[k % clouds.size()], spec.label,
        [&, scheduled](CallStatus status, LabelResult result) {
          std::lock_guard lock(mutex);
          if (status.ok()) {
            stats.record_ok(seconds_between(scheduled, Clock::now()), result.size());
          } else {
            stats.record_error(status_code_name(status.code));
          }
          --outstanding;
          drained.notify_all();
        },
        spec.unary));
  }
  {
    // Calls in flight end by their deadline at the latest.
    std::unique_lock lock(mutex);
    drained.wait(lock, [&] { return outstanding == 0; });
  }
  for (auto& call : calls) call.wait();
  return {spec, seconds_between(start, Clock::now()), std::move(stats)};
}

}  // namespace

std::vector<int> parse_concurrency_range(const std::string& text) {
  std::vector<int> parts;
  std::size_t at = 0;
  while (at <= text.size()) {
    const std::size_t colon = std::min(text.find(':', at), text.size());
    parts.push_back(std::stoi(text.substr(at, colon - at)));
    at = colon + 1;
  }
  if (parts.empty() || parts.size() > 3) throw std::invalid_argument("START:END:STEP");
  const int start = parts[0], end = parts.size() > 1 ? parts[1] : start;
  const int step = parts.size() > 2 ? parts[2] : 1;
  if (start < 1 || end < start || step < 1 || end > 4096)
    throw std::invalid_argument("need 1 <= START <= END <= 4096 and STEP >= 1");
  std::vector<int> values;
  for (int v = start; v <= end; v += step) values.push_back(v);
  return values;
}

StepResult run_step(Client& client, const std::vector<PointCloud>& clouds, const LoadSpec& spec) {
  return spec.mode == LoadMode::kClosed ? run_closed(client, clouds, spec)
                                        : run_open(client, clouds, spec);
}

}  // namespace primlabel::client::loadgen
