#include "primlabel/metrics/family.hpp"

#include <stdexcept>

namespace primlabel::metrics {

FamilyBase::FamilyBase(std::string name, std::string help, Labels constant_labels)
    : name_(std::move(name)), help_(std::move(help)), constant_labels_(std::move(constant_labels)) {
  validate_metric_name(name_);
  validate_label_names(constant_labels_);
}

Labels FamilyBase::merged_labels(const Labels& labels) const {
  validate_label_names(labels);
  Labels merged = constant_labels_;
  for (const auto& [label, value] : labels) {
    // "le" is how histogram buckets are told apart, so no histogram series may carry it.
    if (label == "le" && type() == MetricType::kHistogram)
      throw std::invalid_argument("label 'le' is reserved in histogram " + name_);
    if (!merged.emplace(label, value).second)
      throw std::invalid_argument("label '" + label + "' repeats a constant label of " + name_);
  }
  return merged;
}

template <typename T>
T& Family<T>::Add(const Labels& labels) requires(!std::is_same_v<T, Histogram>) {
  std::lock_guard lock(mutex_);
  if (auto it = metrics_.find(labels); it != metrics_.end()) return *it->second;
  merged_labels(labels);  // validates
  return *metrics_.emplace(labels, std::make_unique<T>()).first->second;
}

template <typename T>
T& Family<T>::Add(const Labels& labels, const Histogram::BucketBoundaries& buckets) requires
    std::is_same_v<T, Histogram> {
  auto created = std::make_unique<Histogram>(buckets);  // validates the bounds
  std::lock_guard lock(mutex_);
  if (auto it = metrics_.find(labels); it != metrics_.end()) {
    if (it->second->bounds() != created->bounds())
      throw std::invalid_argument("histogram " + name() + " already has other buckets");
    return *it->second;
  }
  merged_labels(labels);
  return *metrics_.emplace(labels, std::move(created)).first->second;
}

template <typename T>
void Family<T>::Remove(T* metric) {
  std::lock_guard lock(mutex_);
  for (auto it = metrics_.begin(); it != metrics_.end(); ++it) {
    if (it->second.get() == metric) {
      metrics_.erase(it);
      return;
    }
  }
}

template <typename T>
FamilySnapshot Family<T>::Collect() const {
  FamilySnapshot snapshot{name(), help(), type(), {}};
  std::lock_guard lock(mutex_);
  snapshot.metrics.reserve(metrics_.size());
  for (const auto& [labels, metric] : metrics_) {
    MetricSnapshot sample;
    sample.labels = merged_labels(labels);
    if constexpr (std::is_same_v<T, Histogram>) {
      sample.histogram = metric->Collect();
    } else {
      sample.value = metric->Value();
    }
    snapshot.metrics.push_back(std::move(sample));
  }
  return snapshot;
}

template class Family<Counter>;
template class Family<Gauge>;
template class Family<Histogram>;

}  // namespace primlabel::metrics
