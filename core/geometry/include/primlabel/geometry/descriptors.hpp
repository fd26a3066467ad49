#pragma once
// Per-point descriptors of a cloud (FPFH, PFH): `dim` values per point, row-major, so row i
// belongs to point i. A point without a descriptor has an all-NaN row (see features.hpp).

#include <cstddef>
#include <span>
#include <stdexcept>
#include <vector>

namespace primlabel {

struct Descriptors {
  int dim = 0;
  std::vector<float> values;  // size() x dim, row-major

  Descriptors() = default;
  // Throws std::invalid_argument unless dim > 0 and values hold whole rows.
  Descriptors(int dim_, std::vector<float> values_) : dim(dim_), values(std::move(values_)) {
    if (dim <= 0) throw std::invalid_argument("descriptors: dimension <= 0");
    if (values.size() % static_cast<std::size_t>(dim) != 0)
      throw std::invalid_argument("descriptors: values are not whole rows of the dimension");
  }
  // `points` rows of `dim` copies of `value`.
  static Descriptors filled(std::size_t points, int dim, float value) {
    if (dim <= 0) throw std::invalid_argument("descriptors: dimension <= 0");
    return Descriptors(dim, std::vector<float>(points * static_cast<std::size_t>(dim), value));
  }

  std::size_t size() const { return dim > 0 ? values.size() / static_cast<std::size_t>(dim) : 0; }
  bool empty() const { return values.empty(); }
  std::span<const float> row(std::size_t i) const {
    return {values.data() + i * static_cast<std::size_t>(dim), static_cast<std::size_t>(dim)};
  }
  std::span<float> row(std::size_t i) {
    return {values.data() + i * static_cast<std::size_t>(dim), static_cast<std::size_t>(dim)};
  }
  bool operator==(const Descriptors&) const = default;
};

}  // namespace primlabel
