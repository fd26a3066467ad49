#pragma once
// The JSON form of primitive instances (primlabel-eval --primitives, primlabel label
// --primitives, primlabel-render --primitives): {"primitives": [ {...}, ... ]}, one object per
// instance with its id, kind, class, point count, inliers, rms, confidence, centroid, bounds and
// the model's parameters (metres, unit vectors).

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "primlabel/geometry/json_text.hpp"
#include "primlabel/primitives/primitive.hpp"

namespace primlabel::primitives {

json::Json to_json(const Primitive& primitive, std::size_t id);
std::string primitives_json(std::span<const Primitive> primitives);

// Reads primitives_json's output back; throws std::invalid_argument naming what is wrong.
std::vector<Primitive> parse_primitives_json(std::string_view text);

}  // namespace primlabel::primitives
