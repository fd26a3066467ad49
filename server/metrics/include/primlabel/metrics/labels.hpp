#pragma once
// Label sets and the naming rules of the Prometheus data model.

#include <map>
#include <string>
#include <string_view>

namespace primlabel::metrics {

// Label name -> value. A std::map, so a label set has one canonical (sorted) order.
using Labels = std::map<std::string, std::string>;

// [a-zA-Z_:][a-zA-Z0-9_:]*
bool is_valid_metric_name(std::string_view name);
// [a-zA-Z_][a-zA-Z0-9_]*, and not starting with "__" (reserved for Prometheus itself).
bool is_valid_label_name(std::string_view name);

// Throw std::invalid_argument naming the offending name.
void validate_metric_name(std::string_view name);
void validate_label_names(const Labels& labels);

}  // namespace primlabel::metrics
