// atmos — the optics of seas and lakes for renderers: the water's inputs in
// SI units and its optical properties at the three channels of an
// atmosphere's tables (docs/water.md). The shading functions themselves are
// GLSL (the sea on the globe: atmos/ocean.hpp).
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <glm/mat3x3.hpp>

#include <array>
#include <vector>

#include "atmos/atmosphere.hpp"

namespace atmos {

// The water, in SI units (chlorophyll in the oceanographers' mg m^-3).
struct Water {
  double wind_speed_m_s = 7.0;            // 12.5 m above the water (Cox & Munk 1954's height), [0, 50]
  // Chlorophyll a, [0, 25]: the range of Bricaud et al. 1998's fits (0.02-25;
  // below 0.02 their power laws go to 0 with the chlorophyll).
  double chlorophyll_mg_m3 = 0.1;
  double cdom_absorption_440_per_m = 0.0; // coloured dissolved organic matter at 440 nm, [0, 10]
  double salinity_psu = 35.0;             // [0, 40]: 35 the open ocean, 0 fresh water
  double temperature_c = 20.0;            // [0, 30] (Quan & Fry 1995's fit)
};

// The water's optical properties at three wavelengths, one per channel.
struct WaterOptics {
  std::array<double, 3> wavelengths_nm{};
  glm::dvec3 refractive_index{1.0};      // relative to air (Quan & Fry 1995)
  glm::dvec3 absorption_per_m{0.0};      // pure water + phytoplankton + dissolved organic matter
  glm::dvec3 backscattering_per_m{0.0};  // pure water + particles
  glm::dvec3 diffuse_reflectance{0.0};   // the flat surface's under a uniform sky
  glm::dvec2 slope_variance{0.0};        // upwind and crosswind (Cox & Munk 1954)
};

// The optics of `water` at the channels of `atmosphere`'s tables: its three
// working wavelengths in the three-wavelength mode; in the spectral mode
// (channels linear sRGB) 680, 550 and 440 nm, the representative
// wavelengths of the sRGB primaries that the renderer's phase functions
// use too. Throws atmos::Error with one line naming the first input
// outside its range (or not finite).
WaterOptics water_optics(const Water& water, const Atmosphere& atmosphere);

// The water at every working wavelength of `atmosphere`, in its triples of
// wavelengths as its tables are computed (docs/water.md, "Wavelengths and
// channels"): per triple, the optics (wavelengths outside 300-830 nm take
// the pure-water table's end values), the solar irradiance the tables take
// there, the matrix from the triple's radiance to the tables' channels (the
// atmosphere's own; the identity with three wavelengths) and the weights
// that spread channel values over the triple's wavelengths (linear
// interpolation in ln λ between water_optics's wavelengths; the identity
// with three). Throws atmos::Error as water_optics does.
struct WaterTriples {
  std::vector<WaterOptics> optics;
  std::vector<glm::dvec3> solar_irradiance;  // the tables' units
  std::vector<glm::dmat3> to_channels;
  std::vector<glm::dmat3> from_channels;
};
WaterTriples water_triples(const Water& water, const Atmosphere& atmosphere);

}  // namespace atmos
