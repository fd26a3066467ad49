#include "primlabel/metrics/registry.hpp"

#include <array>
#include <stdexcept>
#include <string_view>

#include "primlabel/metrics/text_format.hpp"

namespace primlabel::metrics {
namespace {

constexpr std::array<std::string_view, 3> kHistogramSuffixes = {"_bucket", "_sum", "_count"};

// True when a histogram named `histogram` writes a series named `name`.
bool is_histogram_series(std::string_view histogram, std::string_view name) {
  for (auto suffix : kHistogramSuffixes)
    if (name.size() == histogram.size() + suffix.size() && name.starts_with(histogram) &&
        name.ends_with(suffix))
      return true;
  return false;
}

}  // namespace

template <typename T>
Family<T>& Registry::Add(const std::string& name, const std::string& help,
                         const Labels& constant_labels) {
  std::lock_guard lock(mutex_);
  constexpr MetricType type = MetricTypeOf<T>::value;
  for (const auto& family : families_) {
    if (family->name() == name) {
      auto* same = dynamic_cast<Family<T>*>(family.get());
      if (same && family->constant_labels() == constant_labels) return *same;
      throw std::invalid_argument("metric " + name +
                                  " is already registered with another type or constant labels");
    }
    const bool collides =
        (family->type() == MetricType::kHistogram && is_histogram_series(family->name(), name)) ||
        (type == MetricType::kHistogram && is_histogram_series(name, family->name()));
    if (collides)
      throw std::invalid_argument("metric " + name + " collides with the series of " +
                                  family->name());
  }
  auto family = std::make_unique<Family<T>>(name, help, constant_labels);
  auto& added = *family;
  families_.push_back(std::move(family));
  return added;
}

template Family<Counter>& Registry::Add<Counter>(const std::string&, const std::string&,
                                                 const Labels&);
template Family<Gauge>& Registry::Add<Gauge>(const std::string&, const std::string&, const Labels&);
template Family<Histogram>& Registry::Add<Histogram>(const std::string&, const std::string&,
                                                     const Labels&);

std::vector<FamilySnapshot> Registry::Collect() const {
  std::lock_guard lock(mutex_);
  std::vector<FamilySnapshot> snapshots;
  snapshots.reserve(families_.size());
  for (const auto& family : families_) snapshots.push_back(family->Collect());
  return snapshots;
}

std::string Registry::Serialize() const { return serialize(Collect()); }

}  // namespace primlabel::metrics
