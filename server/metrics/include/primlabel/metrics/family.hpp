#pragma once
// All metrics of one name (a "family"), one per label set, as in prometheus-cpp.

#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <type_traits>

#include "primlabel/metrics/counter.hpp"
#include "primlabel/metrics/family_snapshot.hpp"
#include "primlabel/metrics/gauge.hpp"
#include "primlabel/metrics/histogram.hpp"
#include "primlabel/metrics/labels.hpp"

namespace primlabel::metrics {

template <typename T>
struct MetricTypeOf;
template <>
struct MetricTypeOf<Counter> {
  static constexpr MetricType value = MetricType::kCounter;
};
template <>
struct MetricTypeOf<Gauge> {
  static constexpr MetricType value = MetricType::kGauge;
};
template <>
struct MetricTypeOf<Histogram> {
  static constexpr MetricType value = MetricType::kHistogram;
};

// What the registry needs of a family, whatever its metric type.
class FamilyBase {
 public:
  FamilyBase(std::string name, std::string help, Labels constant_labels);
  virtual ~FamilyBase() = default;
  FamilyBase(const FamilyBase&) = delete;
  FamilyBase& operator=(const FamilyBase&) = delete;

  const std::string& name() const { return name_; }
  const std::string& help() const { return help_; }
  const Labels& constant_labels() const { return constant_labels_; }
  virtual MetricType type() const = 0;
  virtual FamilySnapshot Collect() const = 0;

 protected:
  // Validates a metric's own labels and merges the constant ones in. Throws std::invalid_argument
  // on a bad or reserved name, or one that repeats a constant label.
  Labels merged_labels(const Labels& labels) const;

 private:
  std::string name_;
  std::string help_;
  Labels constant_labels_;
};

// Thread-safe. A metric lives (at a fixed address) until Remove() or the family's end.
template <typename T>
class Family final : public FamilyBase {
 public:
  using FamilyBase::FamilyBase;

  // The metric with these labels, created on first use: same labels -> same object.
  T& Add(const Labels& labels) requires(!std::is_same_v<T, Histogram>);
  // Same, for histograms. Asking again for existing labels with other buckets throws
  // std::invalid_argument (one series cannot have two bucket layouts).
  T& Add(const Labels& labels,
         const Histogram::BucketBoundaries& buckets) requires std::is_same_v<T, Histogram>;

  // Drops the metric; its address is invalid afterwards. Unknown pointers are ignored.
  void Remove(T* metric);

  MetricType type() const override { return MetricTypeOf<T>::value; }
  FamilySnapshot Collect() const override;

 private:
  mutable std::mutex mutex_;
  std::map<Labels, std::unique_ptr<T>> metrics_;  // key: the metric's own labels
};

extern template class Family<Counter>;
extern template class Family<Gauge>;
extern template class Family<Histogram>;

}  // namespace primlabel::metrics
