// From an atmos::Atmosphere (spectra, SI units) to the AtmosphereParams of the
// shared functions: one per triple of working wavelengths for the
// precomputation, and the parameters of the render tables, whose channels
// are the three wavelengths or linear sRGB (see definitions.glsl, Channels).
#pragma once

#include <array>
#include <memory>

#include "atmos/atmosphere.hpp"
#include "atmos/table_sizes.hpp"
#include "physics/shader_cpp.hpp"

namespace atmos::physics {

// The wavelengths (nm) whose aerosol phase function the R, G, B channels of
// sRGB render tables use.
inline constexpr std::array<double, 3> kRenderPhaseWavelengths = {680.0, 550.0, 440.0};

// Lowest sun zenith cosine stored in the scattering tables: the sun is below
// the horizon of every point of the atmosphere (the horizon dip seen from the
// top, acos(R_bottom / R_top)) plus a margin of 2° for the light scattered by
// the last lit layers.
double mu_s_min(const Atmosphere& atmosphere);

// Number of wavelength triples: ceil(N / 3) for N working wavelengths.
int spectral_set_count(const std::vector<double>& wavelengths_nm);

// The wavelengths of triple `set`: 3 set .. 3 set + 2, the last triple padded
// by repeating its last wavelength (the padding's conversion weight is 0).
std::array<double, 3> set_wavelengths(const std::vector<double>& wavelengths_nm, int set);

// Whether tables of these wavelengths hold linear sRGB / 683 (several
// triples) rather than the radiance at the wavelengths themselves (three).
bool srgb_channels(const std::vector<double>& wavelengths_nm);

// The matrix that converts radiance at the wavelengths of triple `set` to the
// tables' channels: the identity for three wavelengths; otherwise that
// triple's share of the spectrum's linear sRGB (its columns are the weights
// of spectral_to_srgb_weights / 683; zero for padding).
glm::mat3 set_to_channels(const std::vector<double>& wavelengths_nm, int set);

// Linear sRGB on the cd/m² scale from the tables' channels.
glm::mat3 channels_to_srgb_matrix(const std::vector<double>& wavelengths_nm);

// Vertical optical depth (extinction, ground to top) at 550 nm, from the
// density profiles of `params` (any triple of `atmosphere`: only its
// geometry and profiles are read). One wavelength for every triple, so that
// what depends on it is the same in all the tables that are summed.
double vertical_optical_depth_550(const Atmosphere& atmosphere, const AtmosphereParams& params);

// The warp of the scattering tables' mu axis towards log-spaced distances
// (AtmosphereParams.scattering_mu_log_weight, see scattering_u_mu in
// functions.glsl), from the vertical optical depth at 550 nm: 0 (Bruneton's
// mapping, unchanged) up to kMuLogWarpOpticalDepth[0], 1 from
// kMuLogWarpOpticalDepth[1], smoothstep in log τ between. Why by optical
// depth: the warp gives the directions above and below a point inside an
// optically thick layer the texels that its horizon loses, and that is where
// the light comes from there: the Venus tables (τ 47, default sizes) go from
// 0.81 to 0.97 of the reference's light reflected to space and from 0.56 to
// 0.82 of its light on the ground (0.96 with the 32 intervals that
// multiple_scattering_intervals gives the warped atmospheres;
// tests/venus_accuracy.cpp). In thinner atmospheres the
// light that matters is that of long grazing rays, seen from the ground or
// along the limb from above, and the warp costs their horizon: Earth
// (τ 0.27) seen from 100 km, 4.8-6.8 % RMS against the reference instead of
// < 2 %; Titan (τ 9.3, an absorbing haze) gains nothing measurable in its
// fluxes (within 2 % of the unwarped tables at 0-599 km). Earth, both Mars
// and Titan keep 0; Venus and 100x Earth (τ 27, weight 0.97) are warped.
inline constexpr std::array<double, 2> kMuLogWarpOpticalDepth = {10.0, 30.0};
double scattering_mu_log_weight(double vertical_optical_depth);

// The weight of the optical depth in the scattering tables' r axis
// (AtmosphereParams.scattering_r_optical_depth_weight, see
// scattering_x_r_from_rho_fraction in functions.glsl): the same atmospheres
// as the mu warp, kScatteringROpticalDepthShare of its weight. Measured on
// Venus, default sizes (32 radius texels), against the reference (pooled
// over 3-4 seeds of 16000 paths; tests/venus_accuracy.cpp): the light on
// the ground at 680 and 550 nm with the sun 40° up and at 550 nm with it
// 70° up is 1.19, 1.20 and 1.14 of the reference with Bruneton's axis and
// 0.92, 1.00 and 0.99 with a share of 0.5; the light reflected to space
// (550 nm, sun 40°) 0.93 and 0.90. Shares 0.35 and 0.75 gave the ground
// 1.00-1.04 and 0.96-1.03 but reflected only 0.81 (what is above
// the cloud top gets too few texels); 0.9 made an order add more light than
// the one before. With 64 texels the axes agree better (ground 680 nm 1.10
// Bruneton's, 1.01 this one; reflected 0.96, 0.95), so this is resolution,
// and the share that spreads the error least.
inline constexpr double kScatteringROpticalDepthShare = 0.5;
double scattering_r_optical_depth_weight(double mu_log_weight);

// The optical depth over which the multiple scattering's nodes along a view
// ray are uniform in optical depth (AtmosphereParams.source_flat_optical_depth,
// see source_integration_nodes in functions.glsl), from the vertical optical
// depth at 550 nm: 0 (nodes following the transmittance back to the start of
// the ray) up to kSourceFlatOpticalDepthRange[0], kSourceFlatOpticalDepth from
// kSourceFlatOpticalDepthRange[1], smoothstep in log τ between. The error
// it removes needs several optical depths along the rays; measured against
// the reference, sky light on the ground at 680 nm with the sun 40° up:
// Titan (τ 9.3; 5.9 at 680 nm) 1.06 of it with the old nodes, 0.99 with
// these; 100x Earth's air alone (τ 9.7, black ground) 1.05 -> 0.97 (550 nm
// 0.81 -> 0.89, 440 nm 0.83 -> 0.79); 100x Earth 0.84 -> 1.16 (0.74 -> 1.04
// with 64 radius texels); Venus 0.92 -> 0.97. 10x Earth (τ 2.7, 1.4-2.0 %
// RMS against the reference) and thinner atmospheres keep the old nodes.
inline constexpr double kSourceFlatOpticalDepth = 4.0;
inline constexpr std::array<double, 2> kSourceFlatOpticalDepthRange = {3.0, 10.0};
double source_flat_optical_depth(double vertical_optical_depth);

// The parameters of wavelength triple `set`, reading tile `transmittance_tile`
// of a transmittance texture of `transmittance_tiles` tiles (and the same
// tile for the single scattering: make_spectral_sets points that at the
// scaled medium's tile).
AtmosphereParams make_atmosphere_params(const Atmosphere& atmosphere, const TableSizes& sizes, int set,
                                        int transmittance_tile = 0, int transmittance_tiles = 1);

// The parameters of the render tables (the run time): the geometry and table
// sizes, and the solar irradiance and ground albedo in the tables' channels
// (for sRGB channels: the sRGB of the solar spectrum / 683, and the albedo
// that reflects it, sRGB(albedo x sun) / sRGB(sun)). The medium's
// coefficients are zero for sRGB channels: everything spectral goes through
// the SpectralSets. The aerosol phase function of sRGB channel c is that of
// wavelength kRenderPhaseWavelengths[c] (see the .cpp).
AtmosphereParams make_render_params(const Atmosphere& atmosphere, const TableSizes& sizes);

// The delta-M scaled medium of the multiple scattering (Wiscombe 1977,
// J. Atmos. Sci. 34, 1408; the delta-Eddington form of Joseph, Wiscombe &
// Weinman 1976, J. Atmos. Sci. 33, 2452). An aerosol forward lobe sharper
// than kDeltaScaledMaxG (Henyey-Greenstein or Cornette-Shanks g, the forward
// lobe of a double HG) is split into a fraction f that goes straight on and
// a lobe of asymmetry kDeltaScaledMaxG,
//   P = f δ + (1 - f) P*,  f = (g - g*) / (1 - g*),  g* = kDeltaScaledMaxG,
// which keeps the first moment: f + (1 - f) g* = g. Light scattered into
// the δ stays on its ray, so the scaled medium has the scattering (1 - f)
// β_A and the extinction β_ext - f β_A of the aerosol (its absorption is
// unchanged), per channel. Its multiple scattering is smooth enough for the
// tables' nu tiles and the density's degree-28 expansion; the peaked lobe
// itself only enters the single scattering, which keeps the true medium and
// phase function and receives its sunlight through the scaled medium
// (precompute.cpp, single_scattering_tile). Orders >= 2 then miss the light
// within a few degrees of the sun that the δ carries: the sky there is too
// dark by day, and at sunset the glow is too bright within 2° of the sun
// and too faint 5-15° from it (tests/mars_accuracy.cpp).
// `forward_fraction` receives f (w f for a double HG) per channel. Without
// a lobe sharper than g*, returns `params` unchanged and f = 0.
inline constexpr float kDeltaScaledMaxG = 0.85f;
AtmosphereParams delta_scaled_params(const AtmosphereParams& params, vec3& forward_fraction);

// Every triple, each reading its tile of the spectral transmittance texture
// (Tables::spectral_transmittance). Large (~40 KB): allocate, don't copy.
std::unique_ptr<SpectralSets> make_spectral_sets(const Atmosphere& atmosphere, const TableSizes& sizes);

}  // namespace atmos::physics
