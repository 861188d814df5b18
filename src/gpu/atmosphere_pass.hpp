// The engine plugin's GL-free part: validation of a frame's numbers, the
// reduction of the engine's double-precision frame to the camera-relative
// floats of composite.glsl (PassFrame), and the CPU twin of the pass for the
// tests. AtmospherePass::render() uploads exactly the PassFrame built here.
#pragma once

#include <glm/glm.hpp>

#include <vector>

#include "atmos/plugin.hpp"
#include "gpu/composite_cpp.hpp"
#include "runtime/table_samplers.hpp"

namespace atmos::gpu {

// Throws atmos::Error for what render() refuses without looking at any
// texture: non-finite or non-rigid view, singular or non-perspective
// projection, bad depth-encoding parameters, zero sun, bad scales, a
// non-affine shadow matrix (when a shadow map is given), bad step counts.
// (Bad moons need the atmosphere: make_pass_frame.)
void validate_frame_numbers(const FrameInput& input);

// The PassFrame of a validated input: computed in double, rounded once.
// `own_sun_lux`: the atmosphere's sun illuminance (see sun_illuminance_lux).
// Throws atmos::Error for an absurd camera position and for invalid moons
// (atmos::validate_moons). With moons: low_sun and sky_view.full_azimuth.
physics::PassFrame make_pass_frame(const FrameInput& input, const PlanetFrame& planet,
                                   const physics::AtmosphereParams& params, const glm::mat3& radiance_to_srgb,
                                   double own_sun_lux);

// Highest surface the pass expects an engine to draw above the ground
// sphere (Olympus Mons rises 22 km): the aerial-perspective volume reaches
// the horizon of such a surface, and the low-sun test assumes none higher
// (a higher surface under a low sun gets the tables' twilight interpolation;
// one beyond the volume's reach gets its last slice).
constexpr double kMaxSurfaceAltitude = 25e3;

// The depth bias of shadow_visibility for a width x height shadow map:
// `input`'s shadow_bias_m, or 1.5 texels of the map's footprint, in its
// depth units.
void set_shadow_depth_bias(const FrameInput& input, int width, int height, physics::PassFrame& frame);

// The illuminance of the atmosphere's own sun, lux: the luminance of its
// irradiance in the render channels.
double own_sun_illuminance(const physics::AtmosphereParams& params, const glm::mat3& radiance_to_srgb);

// This frame's sky-view table on the CPU, texel by texel as the GPU pass
// computes it (for cameras in the atmosphere); with moons, eclipsed and
// over the full azimuth (SkyViewFrame.full_azimuth).
struct CpuSkyView {
  std::vector<glm::vec3> textures[3];  // rayleigh, aerosol, surface (functions.glsl: view_ray_terms)
  physics::sampler2D sampler(int i) const { return {SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT, textures[i].data()}; }
};
CpuSkyView compute_sky_view_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                const runtime::TableSamplers& samplers, const glm::vec3& camera,
                                const glm::vec3& sun, const physics::Moons& moons = physics::no_moons());

// The aerial-perspective volume (composite.glsl) serves cameras below
// kVolumeMaxAltitude: the terrain and flight views whose surfaces are near,
// where the difference of two table lookups is ill-conditioned and costly
// per pixel. From higher up every surface is tens of kilometres away, the
// difference is well-conditioned, and the volume's slices — quadratic in
// distance — would be too long where a downward ray crosses the aerosol
// layer (4 % off at 45° from 100 km, against 0.3 % for the exact
// evaluation). Between kVolumeBlendAltitude and kVolumeMaxAltitude both are
// evaluated and mixed linearly in altitude (the weight of the volume), so
// that nothing jumps at the switch.
constexpr double kVolumeMaxAltitude = 25e3;
constexpr double kVolumeBlendAltitude = 15e3;
float aerial_perspective_volume_weight(const physics::AtmosphereParams& params, const glm::dvec3& camera);

// The distances the aerial-perspective volume spans for a camera (m,
// planet-centred): from its height above a surface at kMaxSurfaceAltitude
// (no surface is nearer) to its horizon on the ground sphere plus the
// horizon of such a surface (none is farther).
void aerial_perspective_reach(const physics::AtmosphereParams& params, const glm::dvec3& camera, float& t_min,
                              float& t_far);

// This frame's aerial-perspective volume on the CPU, as the compute pass
// fills it (textures: single Rayleigh + multiple, single Rayleigh,
// single aerosol, transmittance; all zero / one when !frame.volume),
// eclipsed by frame.moons.
struct CpuVolume {
  int width = AP_WIDTH;
  int height = AP_HEIGHT;
  int slices = AP_SLICES;
  std::vector<glm::vec3> textures[4];
  physics::sampler3D sampler(int i) const { return {width, height, slices, textures[i].data()}; }
};
CpuVolume compute_volume_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                             const runtime::TableSamplers& samplers, const physics::PassFrame& frame);

// Whether surfaces read the space volume (composite.glsl: space_volume_lookup):
// a camera above the atmosphere, in a frame without a shadow map (the
// shafts' segments need not end in the shell of the surfaces) and without
// moons (every column would need the low-sun integration: none is regular),
// with at least a tenth of the volume's columns regular (space_volume_columns;
// fewer cover too few pixels to pay for their classifying draw). Needs
// frame.camera, sun_direction, low_sun, shadows, moons, inverse_projection,
// view_to_world, depth_column, depth_encoding and surface_shell_radius.
bool uses_space_volume(const physics::AtmosphereParams& params, const physics::PassFrame& frame);

// Whether the pass sorts its pixels into their classes with one draw that
// exports each pixel's stencil bits, where the driver offers
// GL_ARB_shader_stencil_export (true, the default), or with a classifying
// draw per class (false; what drivers without the extension do). A test
// hook: both give the same image.
void set_stencil_export(bool enabled);

// The regular columns of the space volume (composite.glsl:
// space_volume_covers): `regular`, per column, 1 where its ray meets the
// ground sphere steeply enough, needs no low-sun integration
// (space_volume_column_needs_low_sun) and its neighbours' air mass is close
// to its own, else 0; `order`, their indices (y * SPACE_VOLUME_WIDTH + x),
// the only columns the pass computes (no covered pixel reads another).
struct SpaceVolumeColumns {
  std::vector<int> order;
  std::vector<glm::vec3> regular;
};
SpaceVolumeColumns space_volume_columns(const physics::AtmosphereParams& params, const physics::PassFrame& frame);

// The space volume on the CPU, as the compute pass fills it (the same four
// textures as CpuVolume's, SPACE_VOLUME_WIDTH x SPACE_VOLUME_HEIGHT x
// SPACE_VOLUME_SLICES; the regular columns, zero elsewhere).
CpuVolume compute_space_volume_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                   const runtime::TableSamplers& samplers, const physics::PassFrame& frame);

// The light between a camera (m, planet-centred) and the points
// camera + offsets[i], in the tables' channels (for three wavelengths: the
// spectral radiance at each, W m^-2 sr^-1 nm^-1, comparable with
// atmos/reference.hpp), as the plugin computes it for surfaces: from the
// aerial-perspective volume (use_volume, cameras in the atmosphere) or
// exactly (scattering_to_point). For accuracy tests.
struct AerialPerspectiveSample {
  glm::dvec3 single{0.0};         // single scattering (Rayleigh + aerosol), with phase functions
  glm::dvec3 multiple{0.0};       // orders >= 2
  glm::dvec3 transmittance{1.0};  // sunlight-weighted (see channel_transmittance)
};
std::vector<AerialPerspectiveSample> aerial_perspective_cpu(const Atmosphere& atmosphere, const Tables& tables,
                                                            const glm::dvec3& camera, const glm::dvec3& sun,
                                                            const std::vector<glm::dvec3>& offsets, bool use_volume);

// The engine's buffers on the CPU, rows bottom-up as in OpenGL (pixel (x, y)
// at index y * width + x). Empty vectors for what the mode does not read.
struct CpuEngineBuffers {
  std::vector<float> depth;
  std::vector<glm::vec3> colour;
  std::vector<glm::vec3> albedo;
  std::vector<glm::vec3> normal;
  int shadow_width = 0;
  int shadow_height = 0;
  std::vector<glm::vec3> shadow_depth;  // depth in x, GL_LINEAR sampled like the pass's shadow sampler
};

// The CPU twin of AtmospherePass::render() at the given pixels (x, y from the
// bottom-left, as gl_FragCoord): the same PassFrame, tables, sky-view table
// and composite_pixel(). Validates the numbers as render() does.
// `space_volume` false evaluates the surfaces of a camera above the
// atmosphere exactly, per pixel, instead of through the space volume (the
// volume's accuracy test).
std::vector<glm::vec3> composite_cpu(const Atmosphere& atmosphere, const Tables& tables, const PlanetFrame& planet,
                                     const FrameInput& input, const CpuEngineBuffers& buffers,
                                     const std::vector<glm::ivec2>& pixels, bool space_volume = true);

}  // namespace atmos::gpu
