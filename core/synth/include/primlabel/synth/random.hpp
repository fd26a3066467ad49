#pragma once
// Random numbers for the generator that come out the same on every platform and for any thread
// count: SplitMix64 with our own uniform and Gaussian transforms (std::*_distribution differ
// between standard libraries), seeded per scene and per ray from a counter.

#include <cmath>
#include <cstdint>

namespace primlabel::synth {

// A well-mixed 64-bit value for (seed, stream, index): independent streams for scene layout,
// each sensor ray, ... without sharing generator state.
constexpr std::uint64_t mix_seed(std::uint64_t seed, std::uint64_t stream,
                                 std::uint64_t index = 0) {
  std::uint64_t z = seed * 0x9E3779B97F4A7C15ull ^
                    (stream + 0x632BE59BD9B4E019ull) * 0xBF58476D1CE4E5B9ull ^
                    (index + 1) * 0x94D049BB133111EBull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1) with 53 random bits.
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Uniform integer in [0, n).
  int below(int n) { return static_cast<int>(uniform() * n); }
  bool chance(double p) { return uniform() < p; }
  // Standard normal (Box-Muller; one value per call keeps the draw count per ray fixed).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  double normal(double mean, double sigma) { return mean + sigma * normal(); }

 private:
  std::uint64_t state_;
};

}  // namespace primlabel::synth
