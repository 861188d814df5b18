// The reference's building blocks, exposed for its own tests: optical depth
// quadrature, phase functions, their sampling, and the random number stream.
#pragma once

#include <glm/vec3.hpp>

#include <cstdint>

#include "atmos/atmosphere.hpp"

namespace atmos {

// Building blocks of the reference, exposed for its unit tests.
namespace reference_detail {

// Optical depth τ = ∫ Σ_i (β_s,i(λ) + β_a,i(λ)) ρ_i(h(x)) ds along the straight
// segment from `from` to `to` (m), counting only the part inside the
// atmosphere (Rb <= |x| <= Rt). Throws Error if the segment passes below the
// ground by more than 1 mm.
double optical_depth(const Atmosphere& atmosphere, double wavelength_nm, const glm::dvec3& from,
                     const glm::dvec3& to);

// Phase function value p(cos θ) in sr^-1 at one wavelength, normalised so
// that ∫ p dω = 1; θ is the angle between the incident and the scattered
// propagation directions.
double phase_function(const PhaseFunction& phase, double wavelength_nm, double cos_theta);

// SplitMix64 (Steele, Lea & Flood 2014): a 64-bit counter advanced by the
// golden-ratio increment and passed through a bijective mixer.
class Random {
 public:
  explicit Random(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next_u64() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1), 53 random bits.
  double uniform() { return double(next_u64() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

// Draws cos θ with density p(cos θ)·2π (the phase function as a density over
// directions, azimuth uniform), exactly: Rayleigh by inverting its cubic CDF,
// Henyey–Greenstein by its analytic inverse CDF, Cornette–Shanks by rejection
// from Henyey–Greenstein, double Henyey–Greenstein by picking a lobe by its
// weight and sampling it; the parameters at `wavelength_nm`.
double sample_phase_cosine(const PhaseFunction& phase, double wavelength_nm, Random& random);

}  // namespace reference_detail

}  // namespace atmos
