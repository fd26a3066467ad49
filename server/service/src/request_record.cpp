#include "primlabel/service/request_record.hpp"

#include <atomic>
#include <cstdio>
#include <random>

#include "primlabel/ops/logging.hpp"
#include "primlabel/service/user_text.hpp"

namespace primlabel::service {

std::string next_request_id() {
  static const unsigned prefix = std::random_device{}();
  static std::atomic<std::uint64_t> counter{0};
  char id[32];
  std::snprintf(id, sizeof id, "%08x-%06llu", prefix,
                static_cast<unsigned long long>(counter.fetch_add(1) + 1));
  return id;
}

RequestRecord::RequestRecord(std::string method, ops::ServerMetrics& metrics)
    : method_(std::move(method)),
      metrics_(metrics),
      id_(next_request_id()),
      start_(std::chrono::steady_clock::now()) {}

double RequestRecord::elapsed_seconds() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void RequestRecord::finish(std::string_view code_name, std::string_view message) {
  if (finished_) return;
  finished_ = true;
  const double seconds = elapsed_seconds();
  const std::string code(code_name);
  const bool ok = code == "OK";
  const std::string metric_model = model_resolved ? user_text(model) : std::string();
  metrics_.request_finished(method_, metric_model, code, seconds);
  if (ok && points > 0) metrics_.points_labeled(metric_model, double(points));
  if (ok && !model_choice.empty()) metrics_.model_chosen(metric_model, model_choice);
  if (dropped_non_finite > 0) metrics_.points_dropped("non_finite", double(dropped_non_finite));
  ops::LogLine line(ok ? ops::LogLevel::kInfo : ops::LogLevel::kWarn, "request");
  line.kv("method", method_)
      .kv("request_id", id_)
      .kv("scan_id", user_text(scan_id))
      .kv("model", user_text(model))
      .kv("version", user_text(version))
      .kv("points", points)
      .kv("dropped_non_finite", dropped_non_finite)
      .kv("duration_ms", seconds * 1e3)
      .kv("status", code);
  if (!model_choice.empty()) line.kv("model_choice", model_choice);
  if (ok) line.kv("cascaded", cascaded);
  for (const auto& [name, field] : ops::kStages) {
    const double value = stages.*field;
    if (value < 0) continue;
    metrics_.stage(name, value);
    line.kv(std::string(name) + "_ms", value * 1e3);
  }
  if (!ok) line.kv("message", user_text(std::string(message), 2000));
}

}  // namespace primlabel::service
