// Training-scene augmentation: the spec and the seeded draws.

#include "primlabel/synth/augment.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "primlabel/synth/random.hpp"

namespace primlabel::synth {
namespace {

constexpr std::uint64_t kAugmentStream = 401;

double parse_number(std::string_view text, std::string_view key) {
  const std::string s(text);
  char* end = nullptr;
  const double value = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size() || !std::isfinite(value))
    throw std::invalid_argument("--augment: " + std::string(key) + ": not a number: '" + s + "'");
  return value;
}

AugmentRange parse_range(std::string_view text, std::string_view key) {
  const auto colon = text.find(':');
  AugmentRange r;
  r.lo = parse_number(text.substr(0, colon), key);
  r.hi = colon == std::string_view::npos ? r.lo : parse_number(text.substr(colon + 1), key);
  if (r.hi < r.lo) throw std::invalid_argument("--augment: " + std::string(key) + ": lo > hi");
  return r;
}

}  // namespace

Augmentation parse_augmentation(std::string_view spec) {
  Augmentation a;
  a.copies = 1;
  while (!spec.empty()) {
    const auto comma = spec.find(',');
    const std::string_view item = spec.substr(0, comma);
    spec = comma == std::string_view::npos ? std::string_view{} : spec.substr(comma + 1);
    const auto eq = item.find('=');
    if (eq == std::string_view::npos)
      throw std::invalid_argument("--augment: expected key=lo:hi, got '" + std::string(item) + "'");
    const std::string_view key = item.substr(0, eq), value = item.substr(eq + 1);
    if (key == "noise") {
      a.noise = parse_range(value, key);
      if (!(a.noise.lo > 0)) throw std::invalid_argument("--augment: noise must be > 0");
    } else if (key == "density") {
      a.density = parse_range(value, key);
      if (!(a.density.lo > 0 && a.density.hi <= 1))
        throw std::invalid_argument("--augment: density must be in (0, 1]");
    } else if (key == "range") {
      a.range = parse_range(value, key);
      if (!(a.range.lo > 0)) throw std::invalid_argument("--augment: range must be > 0");
    } else if (key == "elevation") {
      a.elevation_deg = parse_range(value, key);
      if (!(a.elevation_deg.lo > -60 && a.elevation_deg.hi < 60))
        throw std::invalid_argument("--augment: elevation must be within +-60 degrees");
    } else if (key == "copies") {
      const double copies = parse_number(value, key);
      if (!(copies >= 1 && copies <= 16 && copies == std::floor(copies)))
        throw std::invalid_argument("--augment: copies must be an integer in 1..16");
      a.copies = static_cast<int>(copies);
    } else {
      throw std::invalid_argument("--augment: unknown key '" + std::string(key) +
                                  "' (noise, density, range, elevation, copies)");
    }
  }
  return a;
}

std::string to_string(const Augmentation& a) {
  char out[256];
  std::snprintf(out, sizeof out, "noise=%g:%g,density=%g:%g,range=%g:%g,elevation=%g:%g,copies=%d",
                a.noise.lo, a.noise.hi, a.density.lo, a.density.hi, a.range.lo, a.range.hi,
                a.elevation_deg.lo, a.elevation_deg.hi, a.copies);
  return out;
}

GenerateOptions augmented(const GenerateOptions& base, const Augmentation& a, int copy) {
  Rng rng(mix_seed(base.seed, kAugmentStream, static_cast<std::uint64_t>(copy)));
  GenerateOptions out = base;
  // Log-uniform noise: 0.5-4 spends as many draws on 0.5-1 as on 2-4.
  out.noise_scale =
      base.noise_scale * std::exp(rng.uniform(std::log(a.noise.lo), std::log(a.noise.hi)));
  out.keep = base.keep * rng.uniform(a.density.lo, a.density.hi);
  out.placement.range_scale = base.placement.range_scale * rng.uniform(a.range.lo, a.range.hi);
  out.placement.elevation_deg =
      base.placement.elevation_deg + rng.uniform(a.elevation_deg.lo, a.elevation_deg.hi);
  out.scan_seed = mix_seed(base.seed, kAugmentStream + 1, static_cast<std::uint64_t>(copy));
  return out;
}

}  // namespace primlabel::synth
