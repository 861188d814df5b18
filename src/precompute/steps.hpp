// The steps of the CPU precomputation, one wavelength triple at a time.
//
// Each step evaluates the shared functions of physics/functions.glsl. The
// integrals along rays hoist everything that does not depend on the sun out of
// the per-texel loop (all texels of one (r, mu) row share a view ray), and the
// scattering density uses the spherical-harmonic structure of the phase
// functions instead of a full sphere of directions per texel; tests check
// both against the straightforward forms in functions.glsl.
#pragma once

#include <functional>
#include <vector>

#include "physics/shader_cpp.hpp"

namespace atmos::precompute {

using physics::AtmosphereParams;
using physics::vec3;

struct Table2D {
  int width = 0;
  int height = 0;
  std::vector<vec3> texels;

  Table2D() = default;
  Table2D(int w, int h) : width(w), height(h), texels(std::size_t(w) * std::size_t(h), vec3(0.0f)) {}
  vec3& at(int x, int y) { return texels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
  physics::sampler2D sampler() const { return {width, height, texels.data()}; }
};

struct Table3D {
  int width = 0;
  int height = 0;
  int depth = 0;
  std::vector<vec3> texels;

  Table3D() = default;
  Table3D(int w, int h, int d)
      : width(w), height(h), depth(d), texels(std::size_t(w) * std::size_t(h) * std::size_t(d), vec3(0.0f)) {}
  vec3& at(int x, int y, int z) {
    return texels[(std::size_t(z) * std::size_t(height) + std::size_t(y)) * std::size_t(width) + std::size_t(x)];
  }
  const vec3& at(int x, int y, int z) const {
    return texels[(std::size_t(z) * std::size_t(height) + std::size_t(y)) * std::size_t(width) + std::size_t(x)];
  }
  physics::sampler3D sampler() const { return {width, height, depth, texels.data()}; }
};

// Called after each slice of work with the fraction of the step done.
using StepProgress = std::function<void(double)>;

Table2D compute_transmittance_table(const AtmosphereParams& atmosphere);

Table2D compute_direct_irradiance_table(const AtmosphereParams& atmosphere, const Table2D& transmittance);

Table2D compute_indirect_irradiance_table(const AtmosphereParams& atmosphere, const Table2D& transmittance,
                                          const Table3D& single_rayleigh, const Table3D& single_aerosol,
                                          const Table3D& multiple_scattering, int order);

void compute_single_scattering_tables(const AtmosphereParams& atmosphere, const Table2D& transmittance,
                                      Table3D& rayleigh, Table3D& aerosol, const StepProgress& progress);

// Scattering density of order `order` + 1 from the radiance of order `order`
// (see incident_radiance() in functions.glsl for the meaning of the inputs).
Table3D compute_scattering_density_table(const AtmosphereParams& atmosphere, const Table2D& transmittance,
                                         const Table3D& single_rayleigh, const Table3D& single_aerosol,
                                         const Table3D& multiple_scattering, const Table2D& irradiance, int order,
                                         const StepProgress& progress);

Table3D compute_multiple_scattering_table(const AtmosphereParams& atmosphere, const Table3D& scattering_density,
                                          const StepProgress& progress);

// Legendre moments p_l = 2π ∫ P(x) P_l(x) dx, l = 0..max_degree, of a phase
// function P (so that P(x) = Σ (2l + 1) / (4π) p_l P_l(x); p_0 = 1 when P is
// normalised).
std::vector<double> legendre_moments(const std::function<double(double)>& phase, int max_degree);

// Nodes and weights of the n-point Gauss-Legendre rule on [a, b].
void gauss_legendre(int n, double a, double b, std::vector<double>& nodes, std::vector<double>& weights);

// Degree of the spherical-harmonic expansion of the scattering density.
inline constexpr int kDensityMaxDegree = 28;

}  // namespace atmos::precompute
