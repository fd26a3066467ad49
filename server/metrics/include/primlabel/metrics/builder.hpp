#pragma once
// Fluent family builders, as in prometheus-cpp:
//   auto& requests =
//   BuildCounter().Name("primlabel_requests_total").Help("...").Register(registry);

#include <string>

#include "primlabel/metrics/family.hpp"
#include "primlabel/metrics/registry.hpp"

namespace primlabel::metrics {

template <typename T>
class Builder {
 public:
  Builder& Name(const std::string& name) {
    name_ = name;
    return *this;
  }
  Builder& Help(const std::string& help) {
    help_ = help;
    return *this;
  }
  // Constant labels, added to every metric of the family.
  Builder& Labels(const metrics::Labels& labels) {
    labels_ = labels;
    return *this;
  }
  Family<T>& Register(Registry& registry) const { return registry.Add<T>(name_, help_, labels_); }

 private:
  std::string name_;
  std::string help_;
  metrics::Labels labels_;
};

inline Builder<Counter> BuildCounter() { return {}; }
inline Builder<Gauge> BuildGauge() { return {}; }
inline Builder<Histogram> BuildHistogram() { return {}; }

}  // namespace primlabel::metrics
