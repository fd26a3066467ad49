#include "primlabel/metrics/text_format.hpp"

#include <charconv>
#include <cmath>

namespace primlabel::metrics {
namespace {

void append_labels(const Labels& labels, const std::string* le, std::string& out) {
  if (labels.empty() && !le) return;
  out += '{';
  bool first = true;
  for (const auto& [name, value] : labels) {
    if (!first) out += ',';
    first = false;
    out += name;
    out += "=\"";
    out += escape_label_value(value);
    out += '"';
  }
  if (le) {
    if (!first) out += ',';
    out += "le=\"";
    out += *le;
    out += '"';
  }
  out += '}';
}

void append_sample(std::string_view name, const Labels& labels, const std::string* le,
                   const std::string& value, std::string& out) {
  out += name;
  append_labels(labels, le, out);
  out += ' ';
  out += value;
  out += '\n';
}

}  // namespace

std::string escape_help(std::string_view help) {
  std::string out;
  out.reserve(help.size());
  for (char c : help) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

std::string escape_label_value(std::string_view value) {
  std::string out;
  out.reserve(value.size());
  for (char c : value) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '"') {
      out += "\\\"";
    } else if (c == '\n') {
      out += "\\n";
    } else {
      out += c;
    }
  }
  return out;
}

std::string format_value(double value) {
  if (std::isnan(value)) return "NaN";
  if (std::isinf(value)) return value > 0 ? "+Inf" : "-Inf";
  char buffer[32];
  // Shortest round-trip form and locale-independent, unlike printf.
  const auto [end, error] = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, end);
}

void serialize_family(const FamilySnapshot& family, std::string& out) {
  if (family.metrics.empty()) return;
  if (!family.help.empty()) {
    out += "# HELP " + family.name + ' ' + escape_help(family.help) + '\n';
  }
  out += "# TYPE " + family.name + ' ' + type_name(family.type) + '\n';
  for (const auto& metric : family.metrics) {
    if (family.type != MetricType::kHistogram) {
      append_sample(family.name, metric.labels, nullptr, format_value(metric.value), out);
      continue;
    }
    const auto& histogram = metric.histogram;
    const std::string bucket_name = family.name + "_bucket";
    for (std::size_t i = 0; i < histogram.bounds.size(); ++i) {
      const std::string le = format_value(histogram.bounds[i]);
      append_sample(bucket_name, metric.labels, &le, std::to_string(histogram.cumulative_counts[i]),
                    out);
    }
    append_sample(family.name + "_sum", metric.labels, nullptr, format_value(histogram.sum), out);
    append_sample(family.name + "_count", metric.labels, nullptr, std::to_string(histogram.count),
                  out);
  }
}

std::string serialize(const std::vector<FamilySnapshot>& families) {
  std::string out;
  for (const auto& family : families) serialize_family(family, out);
  return out;
}

}  // namespace primlabel::metrics
