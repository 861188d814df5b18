// atmos — water: from physical inputs (wind, chlorophyll, salinity, ...) to
// the WaterParams of the shared functions (physics/water.glsl) at three
// working wavelengths, the spectra behind them, and the validation of the
// inputs.
#pragma once

#include <array>
#include <memory>

#include "atmos/water.hpp"
#include "physics/water_cpp.hpp"

namespace atmos::physics {

// The water's inputs (wind, chlorophyll, dissolved matter, salinity,
// temperature): the public atmos::Water (atmos/water.hpp) with its ranges.
using Water = atmos::Water;

// Throws atmos::Error with one line naming the first input outside its range
// (or not finite).
void validate_water(const Water& water);

// Throws atmos::Error for a seabed depth (m) that is negative or NaN (+inf
// is deep water) or an albedo outside [0, 1].
void validate_seabed(double depth_m, const vec3& albedo);

// Pure water's absorption (m^-1): Pope & Fry 1997 over 380-725 nm, Smith &
// Baker 1981 below, Kou et al. 1993 above (data/spectra/pure_water.csv),
// linear between the table's 5 nm rows. atmos::Error outside 300-830 nm.
double pure_water_absorption(double wavelength_nm);

// The scattering coefficient of water of the given salinity (m^-1): pure
// seawater's (Smith & Baker 1981's table, S = 35-38) scaled as Morel 1974
// measured, pure water scattering 1/1.30 of seawater, linearly in salinity
// between them (reference salinity 37). Half of it is backward (Rayleigh-like
// symmetry of molecular scattering).
double water_scattering(double wavelength_nm, double salinity_psu);

// Phytoplankton absorption (m^-1), Bricaud et al. 1998:
// A_ph(λ) Chl^E_ph(λ) (data/spectra/phytoplankton_absorption.csv), held at
// its 400 and 700 nm values beyond 400-700 nm (where pure water's absorption
// is 2-100 times larger at all concentrations).
double phytoplankton_absorption(double wavelength_nm, double chlorophyll_mg_m3);

// Absorption of coloured dissolved organic matter (m^-1),
// a_g(440) e^{-0.014 (λ - 440)} (Bricaud, Morel & Prieur 1981).
double cdom_absorption(double wavelength_nm, double absorption_440_per_m);

// Scattering and backscattering of the particles of Case 1 waters (m^-1):
// b_p(λ) = 0.416 Chl^0.766 (λ / 550)^ν (Loisel & Morel 1998, with the
// spectral exponent ν = 0.5 (log10 Chl - 0.3) for Chl < 2, 0 above, of
// Morel & Maritorena 2001), and the backscattering ratio
// 0.002 + 0.01 (0.5 - 0.25 log10 Chl) (λ / 550)^ν (Morel & Maritorena 2001).
// The exponent and ratio use max(Chl, 0.02), the fits' lowest concentration.
double particle_scattering(double wavelength_nm, double chlorophyll_mg_m3);
double particle_backscattering(double wavelength_nm, double chlorophyll_mg_m3);

// The reflectance of the flat surface under a uniform sky, r_e = 2 ∫ F(μ) μ dμ
// over μ in [0, 1], with the shared fresnel_reflectance (eta = n from the
// air's side, 1 / n from the water's: then it is the diffuse internal
// reflectance r_i). 4096 midpoint nodes in μ².
double diffuse_fresnel_reflectance(double eta);

// The WaterParams of `water` (validated) at three wavelengths (nm, each in
// [300, 830]): the refractive index (Quan & Fry 1995), absorption and
// backscattering (pure water + phytoplankton + CDOM; water + particles),
// r_e, and the Cox & Munk 1954 up/crosswind slope variances.
WaterParams make_water_params(const Water& water, const std::array<double, 3>& wavelengths_nm);

// The wavelengths (nm) whose optics the water takes in each of the tables'
// channels: the working wavelengths with three of them (the channels are
// those wavelengths); in the spectral mode (channels linear sRGB) 680, 550
// and 440 nm, the representative wavelengths of the sRGB primaries that
// the renderer's phase functions use too (kRenderPhaseWavelengths).
std::array<double, 3> water_channel_wavelengths(const Atmosphere& atmosphere);

// The water at every working wavelength of `atmosphere`, in its triples
// (water.glsl, WaterSpectrum): the water's optics at each (wavelengths
// outside the pure-water table's 300-830 nm take its ends' values; the
// colour matching functions are below 1e-4 of their peak there), the solar
// irradiance as the tables take it, set_to_channels, and the weights of
// linear interpolation in ln λ between water_channel_wavelengths (held at
// the ends beyond them). Large (~2 KB): allocate, don't copy.
std::unique_ptr<WaterSpectrum> make_water_spectrum(const Water& water, const Atmosphere& atmosphere);

}  // namespace atmos::physics
