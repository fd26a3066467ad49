#pragma once
// A point-in-time copy of a metric family's values, the input of the text serialiser.

#include <string>
#include <vector>

#include "primlabel/metrics/histogram.hpp"
#include "primlabel/metrics/labels.hpp"

namespace primlabel::metrics {

enum class MetricType { kCounter, kGauge, kHistogram };

// "counter", "gauge", "histogram": the words of the TYPE line.
const char* type_name(MetricType type);

struct MetricSnapshot {
  Labels labels;                  // constant labels merged with the metric's own
  double value = 0.0;             // counter and gauge
  Histogram::Snapshot histogram;  // histogram only
};

struct FamilySnapshot {
  std::string name;
  std::string help;
  MetricType type = MetricType::kCounter;
  std::vector<MetricSnapshot> metrics;  // in label order
};

}  // namespace primlabel::metrics
