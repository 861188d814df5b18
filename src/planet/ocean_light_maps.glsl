// The sea's light maps (src/planet/ocean.cpp): the atmosphere's light at
// the sea's surface, tabulated once from the pass's tables so that each sea
// pixel reads it with one filtered fetch instead of evaluating the tables'
// functions, and the rough surface's reflectance of the sky, tabulated
// from the 16-node slope quadrature (physics/water.glsl). Appended after the pass's GLSL library in the sea's shader
// (ocean.frag.glsl) and in the shader that fills the maps
// (ocean_light_maps.frag.glsl).
//
// Why three and one parameters suffice: the atmosphere is spherically
// symmetric and every sea point lies at the same radius R (the sea level),
// so the sky's radiance there depends only on the view's zenith cosine μ,
// the sun's μ_s and the azimuth φ between the view and the sun about the
// zenith (Bruneton & Neyret 2008, §4: their table's r is fixed here), and
// the sun's irradiance and the sky's irradiance on the horizontal surface
// depend only on μ_s.
//
// The maps' coordinates: a parameter u in [0, 1] is spread over the n
// texels so that u = 0 and u = 1 fall on the first and last texels'
// centres (linear filtering then interpolates between tabulated values
// everywhere, without clamping at the ends). The parameters concentrate
// texels where the light changes fastest:
//   the view's elevation:  u = √μ          (μ ≥ 0; the horizon's haze and glow),
//   the sun's:             u = ½ + ½ sgn(μ_s) √|μ_s|  (sunrise, sunset, twilight),
//   the azimuth:           u = sin(φ / 2) = √((1 − cos φ) / 2)
//                          (even about the sun, for the aerosols' forward peak; no arccosine).
// The maps of the atmosphere's light hold its logarithm: in the twilight the
// sky darkens by orders of magnitude as the sun sinks, about exponentially
// (the light's path through the air lengthens), which interpolating the
// logarithm follows and interpolating the radiance would not (up to 25 %
// too bright between texels 1.5 degrees of the sun's elevation apart).

#define OCEAN_SKY_MAP_SIZE 64      // texels per axis of the sky's radiance (azimuth, view, sun)
const float kOceanLeastRadiance = 1e-30;  // the floor of the light maps (of their logarithm)
#define OCEAN_REFLECTANCE_MAP_SIZE 32  // texels per axis of the reflectance (view, two slope deviations)
#define OCEAN_LIGHT_MAP_SIZE 512   // texels of the irradiances along μ_s
// The irradiances' rows: E_sky, then E_sun at each triple of working
// wavelengths (SPECTRAL_SET_CAPACITY, the pass's count of triples).
#define OCEAN_LIGHT_MAP_ROWS (1 + SPECTRAL_SET_CAPACITY)
// The light from below over the downwelling irradiance (below).
#define OCEAN_BELOW_MAP_WIDTH 64    // along √μ_v
#define OCEAN_BELOW_MAP_HEIGHT 257  // along ½ + ½ sgn(μ_s) √|μ_s| (odd: a texel centre at μ_s = 0, the kink of max(μ_s, 0))
#define OCEAN_BELOW_MAP_DEPTH 32    // along ln(1 + H / 1 m) / ln(1 + H_deep / 1 m)

// The atmosphere's light at a sea point `point` (planet-centred, m), from the
// pass's functions (engine_library.glsl) but in the tables' channels, as
// the water's radiance is summed (water.glsl, water_spectral_radiance) and
// converted to colour at the end with ATMOS_RADIANCE_TO_SRGB, as the pass
// converts its own. The sky's radiance in `direction`:
vec3 ocean_sky_radiance(vec3 point, vec3 direction, vec3 sun) {
  vec3 transmittance;
#if ATMOS_INSTANT
  return instant_radiance_to_distance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture,
                                      atmos_instant_multiple_scattering_texture, camera_above_ground(ATMOSPHERE, point),
                                      direction, sun, -1.0, true, transmittance);
#else
  return sky_radiance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, atmos_scattering_texture,
                      atmos_single_aerosol_texture, atmos_multiple_scattering_texture,
                      camera_above_ground(ATMOSPHERE, point), direction, sun, transmittance);
#endif
}
// the sky's irradiance on the horizontal;
vec3 ocean_sky_irradiance(vec3 point, vec3 sun) {
  vec3 sky;
  sun_and_sky_irradiance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, atmos_irradiance_texture, point,
                         normalize(point), sun, sky);
  return sky;
}
// the sun's irradiance normal to it at the wavelengths of triple k (its
// solar irradiance times its transmittance to the sun, with the planet's
// shadow, as channel_transmittance sums them);
vec3 ocean_set_sun_irradiance(int k, vec3 point, vec3 sun) {
  float r = length(point);
  return SPECTRAL.set[k].solar_irradiance * transmittance_to_sun(SPECTRAL.set[k], atmos_optical_depth_texture,
                                                                  clamp_radius(ATMOSPHERE, r),
                                                                  clamp_cosine(dot(point, sun) / r));
}
// and the transmittance towards a light in direction l, per channel, for a
// light of the sun's spectrum.
vec3 ocean_transmittance_to_light(vec3 point, vec3 l) {
  float r = length(point);
  return channel_transmittance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, PATH_TO_SUN,
                               clamp_radius(ATMOSPHERE, r), clamp_cosine(dot(point, l) / r));
}

// The texture coordinate of parameter u on an axis of n texels, and back.
float ocean_map_coordinate(float u, int n) { return (clamp(u, 0.0, 1.0) * float(n - 1) + 0.5) / float(n); }
float ocean_map_parameter(int texel, int n) { return float(texel) / float(n - 1); }

float ocean_elevation_parameter(float mu) { return sqrt(clamp(mu, 0.0, 1.0)); }
float ocean_elevation_cosine(float u) { return u * u; }
float ocean_sun_parameter(float mu_s) { return 0.5 + 0.5 * sign(mu_s) * sqrt(min(abs(mu_s), 1.0)); }
float ocean_sun_cosine(float u) {
  float x = 2.0 * u - 1.0;
  return sign(x) * x * x;
}
float ocean_azimuth_parameter(float cos_phi) { return sqrt(clamp(0.5 - 0.5 * cos_phi, 0.0, 1.0)); }
float ocean_azimuth(float u) { return 2.0 * asin(clamp(u, 0.0, 1.0)); }

// The reflectance map. water_sky_reflectance depends on the view's cosine
// μ_v to the normal and on the slopes' covariance in the frame of the
// view's azimuth: the variances v_a along it and v_b across it, and their
// covariance c_ab = (σ_u² − σ_c²) cos ψ sin ψ (ψ the view's azimuth from
// upwind). The map tabulates it with c_ab = 0 (the frame's axes along the
// wind) over √μ_v and the standard deviations √v_a, √v_b on a log scale
// from 0.003 (the BRDF's least variance, 1e-5) to 0.45 (Cox & Munk's at
// 60 m/s). With c_ab = 0 the mean reflected direction lies in the plane of
// the normal and the view, so its cosine to the normal (alpha) gives it.
// Leaving out c_ab, which Cox & Munk's anisotropy keeps within 15 % of
// √(v_a v_b), is the map's approximation (its error: docs/water.md).
const float kOceanLeastDeviation = 0.003162278;  // √1e-5
const float kOceanGreatestDeviation = 0.45;
float ocean_deviation_parameter(float sigma) {
  return log(clamp(sigma, kOceanLeastDeviation, kOceanGreatestDeviation) / kOceanLeastDeviation) /
         log(kOceanGreatestDeviation / kOceanLeastDeviation);
}
float ocean_deviation(float u) {
  return kOceanLeastDeviation * exp(u * log(kOceanGreatestDeviation / kOceanLeastDeviation));
}

// The least view elevation the sea's sky is read at: directions below it
// are lifted to it (ocean.frag.glsl, sky_seen_from_sea), as the map's
// first row is filled.
const float kOceanLeastSkyCosine = 1e-4;

// The light from below. Over water deeper than H_deep, where e^{−2 κ H}
// < 1e-5 at every working wavelength (κ = a + b_b; the exponents of the
// column and of the seabed, κ (1/μ_d + D_u/μ_u), are at least 2.03 κ), the
// light leaving the water (water_spectral_radiance) is the deep column's;
// at every depth it depends on μ_v, μ_s and H only, through the sun's and
// the sky's irradiance at the level's radius, the water and the seabed's
// albedo (constant for an Ocean). The map holds it over the channels'
// downwelling irradiance D = Σ_k to_channels[k] E_sun,k max(μ_s, 0) + E_sky,
// a ratio that varies slowly (the surface's transmittance, the refracted
// cosines, the sun's share of the light) where D itself falls by orders of
// magnitude (the twilight); the sea's shader multiplies it by D from the
// light map. Depths on a log scale up to H_deep (deep_water_depth), where
// the seabed's light falls off fastest.
float ocean_depth_parameter(float depth, float deep) { return log(1.0 + max(depth, 0.0)) / log(1.0 + deep); }
float ocean_depth(float u, float deep) { return exp(u * log(1.0 + deep)) - 1.0; }
