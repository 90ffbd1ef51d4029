#pragma once
// A small random generator whose numbers are the same on every platform and standard library
// (std::normal_distribution is not), so a seed gives the same scene and frames everywhere.

#include <cmath>
#include <cstdint>

namespace objmap::sim {

class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  /// A stream for one purpose (a frame, a pixel row) derived from a seed and labels.
  Random(std::uint64_t seed, std::uint64_t a, std::uint64_t b = 0)
      : state_(Mix(seed ^ Mix(a + 0x9E3779B97F4A7C15ull) ^ Mix(b + 0xBF58476D1CE4E5B9ull))) {}

  /// SplitMix64.
  std::uint64_t Next() {
    state_ += 0x9E3779B97F4A7C15ull;
    return Mix(state_);
  }
  /// Uniform in [0, 1).
  double Uniform() { return static_cast<double>(Next() >> 11) * (1.0 / 9007199254740992.0); }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  /// Standard normal (Box-Muller).
  double Normal() {
    const double u1 = 1.0 - Uniform();  // (0, 1]
    const double u2 = Uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }

 private:
  static std::uint64_t Mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::uint64_t state_;
};

}  // namespace objmap::sim
