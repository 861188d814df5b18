// The sweep's random numbers: SplitMix64 (Steele, Lea & Flood 2014,
// "Fast splittable pseudorandom number generators", OOPSLA) and its own
// mappings to doubles, so that a seed gives the same configurations with any
// standard library (the distributions of <random> are implementation-defined).
#pragma once

#include <glm/vec3.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace atmos::sweep {

// SplitMix64's output function: the state advanced by the golden-ratio
// increment 0x9E3779B97F4A7C15 (2^64 / φ), then two xor-shift-multiply rounds
// (the finaliser of MurmurHash3 with Stafford's "Mix13" constants).
inline std::uint64_t splitmix64_mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// An independent stream for (seed, stream, index): the mix of the three
// words, each first spread by the output function so that neighbouring
// indices give unrelated states.
inline std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return splitmix64_mix(splitmix64_mix(seed + 0x9E3779B97F4A7C15ULL) ^
                        splitmix64_mix(stream * 0xD1B54A32D192ED03ULL + index));
}

class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}

  std::uint64_t next() {
    state_ += 0x9E3779B97F4A7C15ULL;
    return splitmix64_mix(state_);
  }
  // The top 53 bits as a double in [0, 1): every value a multiple of 2^-53.
  double uniform() { return double(next() >> 11) * 0x1.0p-53; }
  double uniform(double a, double b) { return a + (b - a) * uniform(); }
  // exp of a uniform log: each decade between a and b (both > 0) equally likely.
  double log_uniform(double a, double b) { return std::exp(uniform(std::log(a), std::log(b))); }
  // An integer in [lo, hi] (inclusive), by multiplying the top 32 bits by the
  // range (Lemire 2019's multiply-shift, without the rejection step: the bias
  // is below range / 2^32, irrelevant for ranges of a few thousand).
  int integer(int lo, int hi) {
    const std::uint64_t range = std::uint64_t(std::int64_t(hi) - std::int64_t(lo) + 1);
    return int(std::int64_t(lo) + std::int64_t(((next() >> 32) * range) >> 32));
  }
  bool chance(double p) { return uniform() < p; }
  // A standard normal deviate by the Box-Muller transform (Box & Muller
  // 1958): sqrt(-2 ln u1) cos(2π u2), with u1 in (0, 1].
  double normal() {
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
  }
  // Uniform on the unit sphere (Archimedes' hat-box theorem: z uniform in
  // [-1, 1], the azimuth uniform).
  glm::dvec3 unit_vector() {
    const double z = uniform(-1.0, 1.0);
    const double phi = uniform(0.0, 2.0 * M_PI);
    const double s = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {s * std::cos(phi), s * std::sin(phi), z};
  }

 private:
  std::uint64_t state_;
};

}  // namespace atmos::sweep
