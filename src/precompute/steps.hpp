// The steps of the CPU precomputation, one wavelength triple at a time.
//
// Each step evaluates the shared functions of physics/functions.glsl. The
// integrals along rays hoist everything that does not depend on the sun out of
// the per-texel loop (all texels of one (r, mu) row share a view ray), the
// sky irradiance shares the (mu, r) part of its lookups along rings of
// directions, and the scattering density uses the spherical-harmonic
// structure of the phase functions instead of a full sphere of directions per
// texel; tests check all of them against the straightforward forms in
// functions.glsl. What the orders of a wavelength triple share (their view
// rays' nodes, the density's quadrature) is computed once (OrderGeometry), and
// the inner loops run on vectors of 4 floats (a texel's three channels) or
// 8 (eight texels, view directions, harmonics or points of two solar discs
// at a time; precompute/simd.hpp), compiled for x86-64-v3 and the baseline.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include "physics/quadrature.hpp"
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
  const vec3& at(int x, int y) const { return texels[std::size_t(y) * std::size_t(width) + std::size_t(x)]; }
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

// With `scaled` (the delta-M scaled medium of `atmosphere`,
// delta_scaled_params), also that medium's single scattering through
// `transmittance` into `scaled_rayleigh`, `scaled_aerosol`, in the same pass:
// on the same view-ray nodes, weighted by the ratio of the two media's
// transmittances along the ray (smooth), and sharing the lookups of the
// sunlight, which dominate the cost.
void compute_single_scattering_tables(const AtmosphereParams& atmosphere, const Table2D& transmittance,
                                      Table3D& rayleigh, Table3D& aerosol, const StepProgress& progress,
                                      const AtmosphereParams& scaled, Table3D& scaled_rayleigh,
                                      Table3D& scaled_aerosol);
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

// What the steps of the scattering orders need that depends on the atmosphere
// of one wavelength triple only — the quadrature nodes of the multiple
// scattering's view rays, the spherical-harmonic quadrature of the density —
// computed once per triple and shared by its orders. The forms with an
// OrderGeometry write into `out`, reusing its memory.
struct OrderGeometry;
std::shared_ptr<const OrderGeometry> make_order_geometry(const AtmosphereParams& atmosphere);
void compute_scattering_density_table(const AtmosphereParams& atmosphere, const OrderGeometry& geometry,
                                      const Table2D& transmittance, const Table3D& single_rayleigh,
                                      const Table3D& single_aerosol, const Table3D& multiple_scattering,
                                      const Table2D& irradiance, int order, const StepProgress& progress,
                                      Table3D& out, bool clamp_ringing = true);
// `clamp_undershoot`: the source read between radius rows of a thick
// atmosphere is kept above the smaller of the two rows around each node
// (source_function_lookup in functions.glsl); false for the signed fields of
// the tail solver, whose operator must stay linear.
void compute_multiple_scattering_table(const AtmosphereParams& atmosphere, const OrderGeometry& geometry,
                                       const Table3D& scattering_density, const StepProgress& progress, Table3D& out,
                                       bool clamp_undershoot = true);

// The light scattered more than K times, T = Σ_{n > K} v_n, where v_n is
// order n (its radiance M_n and the sky irradiance E_{n-1} whose ground
// reflection order n + 1 includes), from v_{K+1} = (next_radiance,
// next_irradiance): GMRES on (I - A) T = v_{K+1}, A one scattering order
// (tail.cpp). Stops when the residual of every channel is below `tolerance`
// relative to |v_{K+1}|, or after `max_iterations` applications of A, each
// costing about one order; keeps at most `restart` + 1 fields (tables of the
// size of a scattering table) at a time, and carries `deflation` of them
// (approximate eigenvectors of the slowest modes) over each restart.
struct ScatteringTail {
  Table3D radiance;    // Σ_{n > K} M_n, radiance like an order's multiple scattering table
  Table2D irradiance;  // Σ_{n >= K} E_n, sky irradiance like compute_indirect_irradiance_table
  int iterations = 0;  // applications of A
  glm::dvec3 relative_residual{0.0};  // |v_{K+1} - (I - A) T| / |v_{K+1}| per channel
};
ScatteringTail solve_scattering_tail(const AtmosphereParams& atmosphere, const OrderGeometry& geometry,
                                     const Table2D& transmittance, const Table3D& next_radiance,
                                     const Table2D& next_irradiance, double tolerance, int max_iterations, int restart,
                                     int deflation, const StepProgress& progress);

// Legendre moments p_l = 2π ∫ P(x) P_l(x) dx, l = 0..max_degree, of a phase
// function P (so that P(x) = Σ (2l + 1) / (4π) p_l P_l(x); p_0 = 1 when P is
// normalised).
std::vector<double> legendre_moments(const std::function<double(double)>& phase, int max_degree);

// The n-point Gauss-Legendre rule on [a, b] (physics/quadrature.hpp).
using physics::gauss_legendre;

// Degree of the spherical-harmonic expansion of the scattering density.
inline constexpr int kDensityMaxDegree = 28;

}  // namespace atmos::precompute
