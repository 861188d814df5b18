// atmos — definitions shared by the C++ precomputation and the GLSL shaders.
//
// The physics (src/physics/*.glsl) is written in the common subset of GLSL
// 4.50 and C++20 + glm (see physics/shader_cpp.hpp for the C++ side and
// gpu/shader_source.cpp for the GLSL side):
//  - float literals carry an `f` suffix (valid in both languages),
//  - parameters are declared with IN(T) / OUT(T) / INOUT(T),
//  - functions are declared INLINE (C++ `inline`, nothing in GLSL),
//  - textures are `sampler2D` / `sampler3D`, read only through `texture()`,
//    which the C++ side implements with the exact GL_LINEAR / CLAMP_TO_EDGE
//    arithmetic,
//  - no swizzles, no struct constructors, no recursion.
//
// Units: lengths in metres, coefficients in m^-1, angles as cosines, spectral
// quantities per working wavelength (three at a time, one per vec3 channel).
//
// The parts of the physics, each using only this file and the parts above it
// (each names the parts it needs at its top):
//   stars.glsl                      the procedural star field
//   eclipse.glsl                    the solar disc and the moons that eclipse it
//   ray_geometry.glsl               rays in a spherical atmosphere
//   medium.glsl                     density profiles, scattering and extinction,
//                                   optical depth, phase functions, the ground
//   table_coordinates.glsl          (r, mu, mu_s, nu) <-> the tables' texture
//                                   coordinates
//   table_lookups.glsl              reading transmittance, scattering, irradiance
//   ray_integration.glsl            quadrature along rays, single scattering
//                                   integrated along them, eclipsed diffuse light
//   precomputation_integrands.glsl  single scattering, scattering density,
//                                   multiple scattering, irradiance: the orders
//   view_ray_scattering.glsl        the renderers' light along a view ray
//   aerial_perspective.glsl         the light between a camera and a point
//   sky_view_table.glsl             the per-frame sky-view table
//   radiance_to_camera.glsl         sky, ground, sun disc, stars, moons
// C++ compiles each part through physics/<part>_cpp.hpp, which includes the
// headers of the parts it needs; each shader lists the parts it uses
// (gpu/shader_source.cpp).
//
// Channels. The precomputation works on triples of wavelengths ("sets"). With
// one set (the three-wavelength mode) the tables' three channels ARE those
// wavelengths. With several (spectral mode, Elek & Kmoch 2010, §4.4) every
// linear quantity — scattered radiance, irradiance — is converted set by set
// to linear sRGB and summed, so that the run time reads one set of textures
// whose channels are linear sRGB divided by 683 lm/W (radiometric units,
// which keep 16-bit float textures far from overflow); see
// channels_to_srgb_matrix in physics/parameters.hpp.

#define MAX_CONSTITUENTS 4
#define MAX_DENSITY_KNOTS 8
// Knots of the scattering tables' r axis (AtmosphereParams.scattering_r_axis).
#define SCATTERING_R_AXIS_KNOTS 33

#define PHASE_HENYEY_GREENSTEIN 0
#define PHASE_CORNETTE_SHANKS 1
#define PHASE_DOUBLE_HENYEY_GREENSTEIN 2

const float PI = 3.14159265358979f;

// Number density of a constituent relative to its reference density, as a
// function of altitude: exponential without knots (knot_count 0, scale_height
// > 0), else piecewise linear through the knots and zero outside them
// (ozone-like layers). The kind is the integer knot_count so that shaders
// know it at compile time while the heights are uniforms (see
// gpu/shader_source.cpp).
struct DensityProfile {
  float scale_height;
  int knot_count;
  float knot_altitude[MAX_DENSITY_KNOTS];
  float knot_density[MAX_DENSITY_KNOTS];
};

// Everything the functions need to know, for one triple of wavelengths:
// the medium (atmos::Atmosphere resampled at three wavelengths) and the sizes
// of the lookup tables. Built by physics/parameters.cpp.
struct AtmosphereParams {
  float bottom_radius;                          // m, ground
  float top_radius;                             // m, top of the atmosphere
  int constituent_count;
  DensityProfile density[MAX_CONSTITUENTS];
  vec3 scattering[MAX_CONSTITUENTS];            // m^-1 at reference density
  vec3 absorption[MAX_CONSTITUENTS];            // m^-1 at reference density
  int is_aerosol[MAX_CONSTITUENTS];             // 0: Rayleigh phase function, 1: the aerosol phase function
  // The aerosol phase function, one set of parameters per channel: for a
  // wavelength triple its three wavelengths; for the render parameters of the
  // spectral mode the representative wavelengths of the sRGB channels (see
  // make_render_params).
  int aerosol_phase_kind;                       // PHASE_HENYEY_GREENSTEIN, _CORNETTE_SHANKS or _DOUBLE_HENYEY_GREENSTEIN
  vec3 aerosol_g;                               // asymmetry parameter (of the forward lobe)
  vec3 aerosol_g_back;                          // double HG: asymmetry parameter of the second lobe (else 0)
  vec3 aerosol_forward_weight;                  // double HG: weight of the first lobe (else 1)
  vec3 ground_albedo;
  vec3 solar_irradiance;                        // W m^-2 nm^-1 at the top of the atmosphere
  float sun_angular_radius;                     // rad
  float mu_s_min;                               // lowest sun zenith cosine kept in the scattering tables

  // Table sizes (texels).
  int transmittance_mu_size;
  int transmittance_r_size;
  int irradiance_mu_s_size;
  int irradiance_r_size;
  int scattering_nu_size;
  int scattering_mu_s_size;
  int scattering_mu_size;
  int scattering_r_size;

  // The transmittance texture these parameters read: `transmittance_tiles`
  // tables side by side, this one being tile `transmittance_tile` (see
  // transmittance_uv_from_r_mu). 1 and 0 for the render tables; the spectral
  // sets read tile k of the spectral transmittance texture.
  int transmittance_tile;
  int transmittance_tiles;
  // The tile the single scattering's transmittance to the sun reads: the
  // optical depth of the delta-M scaled medium (delta_scaled_params,
  // parameters.hpp), so that sunlight scattered into the aerosol's forward
  // peak on its way to the scattering point still arrives there, within a
  // few degrees of the sun's direction (after the single-scattering
  // correction of Nakajima & Tanaka 1988, J. Quant. Spectrosc. Radiat.
  // Transfer 40, 51, which uses the scaled transmittances with the true
  // phase function; here on the sun's path only, see precompute.cpp). The
  // same as transmittance_tile where nothing is scaled.
  int single_scattering_tile;
  // 1: the nu axis of the 4D tables is uniform in the scattering angle
  // acos(nu), for atmospheres with an aerosol lobe sharper than
  // kDeltaScaledMaxG (see nu_from_unit_range); 0: uniform in nu.
  int scattering_nu_in_angle;
  // Warp of the mu axis of the 4D tables towards log-spaced distances
  // (0: linear in distance, 1: log; see scattering_u_mu).
  float scattering_mu_log_weight;
  // The r axis of the 4D tables (see scattering_x_r_from_rho_fraction):
  // with weight 0 Bruneton's x_r = rho / H; else x_r is the piecewise-linear
  // map whose values at rho / H = i / (SCATTERING_R_AXIS_KNOTS - 1) are
  // scattering_r_axis[i] (0 at the ground, 1 at the top, increasing).
  float scattering_r_optical_depth_weight;
  float scattering_r_axis[SCATTERING_R_AXIS_KNOTS];
  // Optical depth over which the multiple scattering's nodes along a view
  // ray are uniform in optical depth (0: they follow the transmittance; see
  // source_integration_nodes).
  float source_flat_optical_depth;
  // Height above the ground of the scattering tables' radius row 1
  // (scattering_row_height(1), table_coordinates.glsl), stored because the
  // run time needs it for every lookup of a ray to the ground in a thick
  // atmosphere (ray_scattering_lookup) and shader compilers do not fold the
  // search through the r axis's knots.
  float scattering_row_1_height;
};

// Most wavelength triples a spectral precomputation may use (48 wavelengths).
// The shaders define the actual count instead (gpu/shader_source.cpp).
#ifndef SPECTRAL_SET_CAPACITY
#define SPECTRAL_SET_CAPACITY 16
#endif

// The medium at each wavelength triple, for what the run time computes
// spectrally (the low-sun single scattering, scattering_along_ray): set k
// has its own coefficients and solar irradiance, reads tile k of the spectral
// transmittance texture, and `to_channels[k]` converts its radiance to the
// tables' channels (the identity in the three-wavelength mode).
struct SpectralSets {
  int count;
  AtmosphereParams set[SPECTRAL_SET_CAPACITY];
  mat3 to_channels[SPECTRAL_SET_CAPACITY];
};
