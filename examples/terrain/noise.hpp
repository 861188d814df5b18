// Deterministic 2D noise for the example's terrain: gradient noise, fBm and a
// ridged multifractal.
//
// Everything is computed in double from integer hashes of the lattice
// coordinates and a seed: the same seed gives the same terrain on every
// machine and compiler (no std::rand, no unordered containers, no platform
// math beyond + - * and floor), so the test images are reproducible.
#pragma once

#include <cstdint>

namespace engine {

class Noise {
 public:
  explicit Noise(std::uint32_t seed) : seed_(seed) {}

  // Gradient ("Perlin") noise at p, in about [-1, 1], zero at the lattice
  // points, smooth (C2) everywhere; the lattice spacing is 1.
  double gradient(double x, double y) const;

  // Fractional Brownian motion: `octaves` layers of gradient noise, each at
  // twice the frequency and `gain` times the amplitude of the previous one,
  // normalised to about [-1, 1]. Rolling hills.
  double fbm(double x, double y, int octaves, double gain = 0.5) const;

  // Ridged multifractal (after Musgrave): 1 - |noise| squared makes sharp
  // crests along the zero lines of the noise; each octave is weighted by the
  // previous one, so valleys stay smooth and ridges get the fine detail.
  // Result in about [0, 1]. Mountain ranges.
  double ridged(double x, double y, int octaves) const;

 private:
  std::uint32_t seed_;
};

}  // namespace engine
