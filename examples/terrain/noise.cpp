#include "noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace engine {

namespace {

// A 32-bit integer hash with good avalanche (every input bit flips about half
// of the output bits), so neighbouring lattice points get unrelated
// gradients. Integer arithmetic only: identical on every platform.
std::uint32_t hash(std::int32_t x, std::int32_t y, std::uint32_t seed) {
  std::uint32_t h = seed * 0x9E3779B9u;
  h ^= static_cast<std::uint32_t>(x) * 0x85EBCA6Bu;
  h = (h << 13) | (h >> 19);
  h ^= static_cast<std::uint32_t>(y) * 0xC2B2AE35u;
  h ^= h >> 16;
  h *= 0x7FEB352Du;
  h ^= h >> 15;
  h *= 0x846CA68Bu;
  h ^= h >> 16;
  return h;
}

// Sixteen unit gradients evenly spread over the circle (cos, sin of k·22.5°,
// written out so that no libm rounding can differ between machines).
constexpr std::array<std::array<double, 2>, 16> kGradients = {{
    {1.0, 0.0},
    {0.9238795325112867, 0.3826834323650898},
    {0.7071067811865476, 0.7071067811865476},
    {0.3826834323650898, 0.9238795325112867},
    {0.0, 1.0},
    {-0.3826834323650898, 0.9238795325112867},
    {-0.7071067811865476, 0.7071067811865476},
    {-0.9238795325112867, 0.3826834323650898},
    {-1.0, 0.0},
    {-0.9238795325112867, -0.3826834323650898},
    {-0.7071067811865476, -0.7071067811865476},
    {-0.3826834323650898, -0.9238795325112867},
    {0.0, -1.0},
    {0.3826834323650898, -0.9238795325112867},
    {0.7071067811865476, -0.7071067811865476},
    {0.9238795325112867, -0.3826834323650898},
}};

// Quintic fade 6t^5 - 15t^4 + 10t^3: zero first and second derivatives at
// the lattice points, so the terrain's normals (and their derivative) are
// continuous across cells — no grid pattern in the shading.
double fade(double t) { return t * t * t * (t * (t * 6.0 - 15.0) + 10.0); }

// Each octave is rotated by this angle (about 36.87°: cos = 0.8, sin = 0.6,
// exact in binary) and shifted, so the lattices of the octaves never line
// up and no axis-aligned streaks appear.
constexpr double kRotateCos = 0.8;
constexpr double kRotateSin = 0.6;
constexpr double kOctaveShift = 17.31;

}  // namespace

double Noise::gradient(double x, double y) const {
  const double fx = std::floor(x), fy = std::floor(y);
  const auto ix = static_cast<std::int32_t>(fx), iy = static_cast<std::int32_t>(fy);
  const double tx = x - fx, ty = y - fy;
  // Dot product of the corner's gradient with the offset from that corner.
  auto corner = [&](std::int32_t dx, std::int32_t dy) {
    const auto& g = kGradients[hash(ix + dx, iy + dy, seed_) & 15u];
    return g[0] * (tx - dx) + g[1] * (ty - dy);
  };
  const double u = fade(tx), v = fade(ty);
  const double bottom = corner(0, 0) + u * (corner(1, 0) - corner(0, 0));
  const double top = corner(0, 1) + u * (corner(1, 1) - corner(0, 1));
  // 2D gradient noise with unit gradients stays within ±sqrt(2)/2: scale to ±1.
  return 1.4142135623730951 * (bottom + v * (top - bottom));
}

double Noise::fbm(double x, double y, int octaves, double gain) const {
  double sum = 0.0, amplitude = 1.0, total = 0.0;
  for (int i = 0; i < octaves; ++i) {
    sum += amplitude * gradient(x, y);
    total += amplitude;
    amplitude *= gain;
    const double rx = kRotateCos * x - kRotateSin * y, ry = kRotateSin * x + kRotateCos * y;
    x = 2.0 * rx + kOctaveShift;
    y = 2.0 * ry - kOctaveShift;
  }
  return sum / total;
}

double Noise::ridged(double x, double y, int octaves) const {
  double sum = 0.0, amplitude = 1.0, total = 0.0, weight = 1.0;
  for (int i = 0; i < octaves; ++i) {
    double crest = 1.0 - std::abs(gradient(x, y));
    crest *= crest;
    // Detail where the previous octave was high (on ridges), little in the
    // valleys: that is what makes eroded-looking ranges rather than noise.
    crest *= weight;
    weight = std::clamp(crest * 2.0, 0.0, 1.0);
    sum += amplitude * crest;
    total += amplitude;
    amplitude *= 0.5;
    const double rx = kRotateCos * x - kRotateSin * y, ry = kRotateSin * x + kRotateCos * y;
    x = 2.0 * rx - kOctaveShift;
    y = 2.0 * ry + kOctaveShift;
  }
  return sum / total;
}

}  // namespace engine
