#include <stdexcept>
#include <string>

#include "primlabel/metrics/family_snapshot.hpp"
#include "primlabel/metrics/labels.hpp"

namespace primlabel::metrics {
namespace {

bool is_letter_or_underscore(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}
bool is_digit(char c) { return c >= '0' && c <= '9'; }

}  // namespace

bool is_valid_metric_name(std::string_view name) {
  if (name.empty()) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    const bool ok = is_letter_or_underscore(c) || c == ':' || (i > 0 && is_digit(c));
    if (!ok) return false;
  }
  return true;
}

bool is_valid_label_name(std::string_view name) {
  if (name.empty() || name.starts_with("__")) return false;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (!(is_letter_or_underscore(c) || (i > 0 && is_digit(c)))) return false;
  }
  return true;
}

void validate_metric_name(std::string_view name) {
  if (!is_valid_metric_name(name))
    throw std::invalid_argument("invalid metric name '" + std::string(name) + "'");
}

void validate_label_names(const Labels& labels) {
  for (const auto& [name, value] : labels)
    if (!is_valid_label_name(name))
      throw std::invalid_argument("invalid label name '" + name + "'");
}

const char* type_name(MetricType type) {
  switch (type) {
    case MetricType::kCounter:
      return "counter";
    case MetricType::kGauge:
      return "gauge";
    case MetricType::kHistogram:
      return "histogram";
  }
  return "untyped";
}

}  // namespace primlabel::metrics
