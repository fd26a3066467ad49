#pragma once
// The set of metric families a process exposes.

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "primlabel/metrics/family.hpp"
#include "primlabel/metrics/family_snapshot.hpp"

namespace primlabel::metrics {

// Thread-safe. Families and their metrics keep their addresses for the registry's life.
class Registry {
 public:
  // The family of this name, created on first use. Registering an existing name again returns
  // the same family when type and constant labels agree, and throws std::invalid_argument
  // otherwise, or when the name collides with a histogram's _bucket/_sum/_count series.
  // Usually called through the builders (BuildCounter() ... .Register(registry)).
  template <typename T>
  Family<T>& Add(const std::string& name, const std::string& help, const Labels& constant_labels);

  // Families in registration order.
  std::vector<FamilySnapshot> Collect() const;

  // Prometheus text exposition format 0.0.4.
  std::string Serialize() const;

 private:
  mutable std::mutex mutex_;
  std::vector<std::unique_ptr<FamilyBase>> families_;
};

extern template Family<Counter>& Registry::Add<Counter>(const std::string&, const std::string&,
                                                        const Labels&);
extern template Family<Gauge>& Registry::Add<Gauge>(const std::string&, const std::string&,
                                                    const Labels&);
extern template Family<Histogram>& Registry::Add<Histogram>(const std::string&, const std::string&,
                                                            const Labels&);

}  // namespace primlabel::metrics
