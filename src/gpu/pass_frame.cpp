// The engine plugin's GL-free part (see gpu/atmosphere_pass.hpp).
#include "gpu/atmosphere_pass.hpp"

#include <glm/gtc/matrix_transform.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "physics/checks.hpp"
#include "physics/moons.hpp"
#include "physics/parameters.hpp"

namespace atmos::gpu {

namespace {

// The view matrix must be rigid (rotation + translation): the pass turns
// its inverse into a rotation and a camera position.
void check_rigid(const glm::dmat4& view) {
  const glm::dmat3 r(view);
  const glm::dmat3 should_be_identity = glm::transpose(r) * r;
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k)
      if (std::abs(should_be_identity[c][k] - (c == k ? 1.0 : 0.0)) > 1e-6)
        throw Error("plugin input: the view matrix is not a rotation + translation (scale or shear: put the scale "
                    "in PlanetFrame::units_per_metre)");
  if (std::abs(view[0][3]) + std::abs(view[1][3]) + std::abs(view[2][3]) > 0.0 || view[3][3] != 1.0)
    throw Error("plugin input: the view matrix has a projective last row");
}

// The projection must be a perspective one (the camera at the view-space
// origin, looking along -z) and invertible.
void check_perspective(const glm::dmat4& projection) {
  if (std::abs(glm::determinant(projection)) < 1e-300)
    throw Error("plugin input: degenerate projection matrix (not invertible)");
  // clip w = -z for every OpenGL perspective projection.
  if (projection[0][3] != 0.0 || projection[1][3] != 0.0 || projection[3][3] != 0.0 || !(projection[2][3] < 0.0))
    throw Error("plugin input: the projection is not a perspective projection looking along -z (clip w must be -z)");
  if (!(projection[0][0] != 0.0 && projection[1][1] != 0.0))
    throw Error("plugin input: degenerate projection matrix (zero field of view scale)");
}

// Whether some surface the camera can see may have the sun below 10°
// (LOW_SUN_MU_S_TABLE), where aerial perspective integrates single
// scattering (scattering_to_distance) — and, for a camera above the
// atmosphere, some point of the atmosphere it sees, where the sky's rays
// integrate it (composite_sky_pixel, without the sky-view table). A point
// at altitude h that the camera sees is at most acos(R / r) + acos(R / (R +
// h)) away from the camera's nadir, in angle from the planet centre (the
// camera's horizon plus the point's own), with h up to kMaxSurfaceAltitude
// for surfaces and up to the top of the atmosphere for the air; the sun's
// zenith angle there differs from the one above the nadir by at most that
// much. The variant without the integration is several times faster on
// software rasterisers, which run every branch.
bool sun_may_be_low(const physics::AtmosphereParams& atmosphere, const glm::dvec3& camera, const glm::vec3& sun) {
  const double bottom = atmosphere.bottom_radius;
  const double r = std::max(glm::length(camera), bottom);
  const double highest = physics::camera_uses_sky_view(atmosphere, glm::vec3(camera))
                             ? gpu::kMaxSurfaceAltitude
                             : std::max(gpu::kMaxSurfaceAltitude, double(atmosphere.top_radius) - bottom);
  const double reach = std::acos(bottom / r) + std::acos(bottom / (bottom + highest));
  // The zenith of the camera the shaders see (camera_above_ground: below the
  // ground, and at the planet's centre, it stands on the ground).
  const glm::dvec3 zenith = glm::normalize(glm::dvec3(physics::camera_above_ground(atmosphere, glm::vec3(camera))));
  const double sun_zenith = std::acos(std::clamp(glm::dot(zenith, glm::dvec3(sun)), -1.0, 1.0));
  const double low_sun_zenith = std::acos(double(LOW_SUN_MU_S_TABLE));
  return sun_zenith + reach >= low_sun_zenith;
}

}  // namespace

void aerial_perspective_reach(const physics::AtmosphereParams& params, const glm::dvec3& camera, float& t_min,
                              float& t_far) {
  // Far: the camera's horizon on the ground sphere plus the horizon of the
  // highest surface. Near: the camera's height above the highest surface.
  const double bottom = params.bottom_radius;
  const double r = std::max(glm::length(camera), bottom);
  t_far = float(std::sqrt(r * r - bottom * bottom) +
                std::sqrt(kMaxSurfaceAltitude * (2.0 * bottom + kMaxSurfaceAltitude)));
  t_min = float(std::max(r - bottom - kMaxSurfaceAltitude, 0.0));
}

float aerial_perspective_volume_weight(const physics::AtmosphereParams& params, const glm::dvec3& camera) {
  const double altitude = glm::length(camera) - double(params.bottom_radius);
  return float(std::clamp((kVolumeMaxAltitude - altitude) / (kVolumeMaxAltitude - kVolumeBlendAltitude), 0.0, 1.0));
}

void validate_frame_numbers(const FrameInput& input) {
  if (!is_finite(input.view) || !is_finite(input.projection))
    throw Error("plugin input: the view or projection matrix is not finite");
  check_rigid(input.view);
  check_perspective(input.projection);
  if (input.depth_encoding == DepthEncoding::logarithmic &&
      !(input.log_depth_far > 0.0 && std::isfinite(input.log_depth_far)))
    throw Error("plugin input: logarithmic depth needs log_depth_far > 0, got " + number_text(input.log_depth_far));
  if (!is_finite(input.sun_direction) || glm::length(input.sun_direction) == 0.0)
    throw Error("plugin input: the sun direction is zero or not finite");
  if (!(input.sun_illuminance_lux >= 0.0 && std::isfinite(input.sun_illuminance_lux)))
    throw Error("plugin input: sun_illuminance_lux " + number_text(input.sun_illuminance_lux) + " must be >= 0");
  if (!(input.nits_per_unit > 0.0 && std::isfinite(input.nits_per_unit)))
    throw Error("plugin input: nits_per_unit " + number_text(input.nits_per_unit) + " must be > 0");
  if (input.shadow_map != 0) {
    if (!is_finite(input.shadow_matrix)) throw Error("plugin input: the shadow matrix is not finite");
    if (input.shadow_matrix[0][3] != 0.0 || input.shadow_matrix[1][3] != 0.0 || input.shadow_matrix[2][3] != 0.0 ||
        input.shadow_matrix[3][3] != 1.0)
      throw Error("plugin input: the shadow matrix is not affine (the sun's shadow map needs an orthographic "
                  "projection)");
    if (!(input.shadow_bias_m >= 0.0 && std::isfinite(input.shadow_bias_m)))
      throw Error("plugin input: shadow_bias_m " + number_text(input.shadow_bias_m) + " must be >= 0");
    if (input.shadow_steps < 1 || input.shadow_steps > 256)
      throw Error("plugin input: shadow_steps " + std::to_string(input.shadow_steps) + " outside 1..256");
  }
}

double own_sun_illuminance(const physics::AtmosphereParams& params, const glm::mat3& radiance_to_srgb) {
  const glm::dvec3 sun_srgb = glm::dmat3(radiance_to_srgb) * glm::dvec3(params.solar_irradiance);
  return glm::dot(sun_srgb, glm::dvec3(0.2126, 0.7152, 0.0722));
}

physics::PassFrame make_pass_frame(const FrameInput& input, const PlanetFrame& planet,
                                   const physics::AtmosphereParams& params, const glm::mat3& radiance_to_srgb,
                                   double own_sun_lux) {
  // The camera in the engine's world, in double: the inverse of the rigid
  // view matrix.
  const glm::dmat4 camera_to_world = glm::inverse(input.view);
  const glm::dvec3 camera_world(camera_to_world[3]);
  const glm::dvec3 camera_planet = (camera_world - planet.centre) / planet.units_per_metre;
  if (!is_finite(camera_planet) || glm::length(camera_planet) > 1e12)
    throw Error("plugin input: camera position is not finite or absurdly far (> 1e12 m from the planet)");
  physics::PassFrame frame{};
  frame.camera = glm::vec3(camera_planet);
  frame.sun_direction = glm::vec3(glm::normalize(input.sun_direction));
  // The moons (validated: atmos::validate_moons), planet-centred metres;
  // none when no moon can hide the sun from the atmosphere this frame
  // (moons_may_eclipse: a moon elsewhere in the sky costs nothing, and its
  // disc is the engine's to draw).
  try {
    frame.moons = physics::make_moons(params, input.moons);
  } catch (const Error& e) {
    throw Error(std::string("plugin input: FrameInput::moons: ") + e.what());
  }
  if (!physics::moons_may_eclipse(params, frame.moons, frame.sun_direction)) frame.moons = physics::no_moons();
  const bool eclipse = frame.moons.count > 0;
  const glm::dmat4 inverse_projection = glm::inverse(input.projection);
  const glm::dmat3 view_to_world = glm::dmat3(camera_to_world) / planet.units_per_metre;
  frame.inverse_projection = glm::mat4(inverse_projection);
  frame.view_to_world = glm::mat3(view_to_world);
  frame.depth_column = glm::vec4(glm::vec3(view_to_world * glm::dvec3(inverse_projection[2])), inverse_projection[2].w);
  frame.depth_column_view_z = float(inverse_projection[2].z);
  frame.depth_encoding = input.depth_encoding == DepthEncoding::standard     ? DEPTH_STANDARD
                         : input.depth_encoding == DepthEncoding::reversed_z ? DEPTH_REVERSED_Z
                                                                             : DEPTH_LOGARITHMIC;
  frame.log2_depth_far =
      input.depth_encoding == DepthEncoding::logarithmic ? float(std::log2(1.0 + input.log_depth_far)) : 0.0f;
  frame.surface_mode = input.surfaces == SurfaceMode::gbuffer ? SURFACE_GBUFFER : SURFACE_LIT_COLOUR;
  frame.radiance_to_srgb = radiance_to_srgb;
  frame.inverse_sun_srgb = 1.0f / glm::max(radiance_to_srgb * params.solar_irradiance, glm::vec3(1e-30f));
  frame.sky_view = physics::sky_view_frame(params, physics::camera_above_ground(params, frame.camera),
                                           frame.sun_direction);
  // An eclipse breaks the symmetry about the sun's vertical plane: the
  // sky-view table and the volume span the full azimuth.
  frame.sky_view.full_azimuth = eclipse;
  frame.light_scale =
      float((input.sun_illuminance_lux > 0.0 ? input.sun_illuminance_lux / own_sun_lux : 1.0) / input.nits_per_unit);
  frame.sun_disc = input.sun_disc;
  // A star's image: 0.6 of a pixel's angular size at the image centre
  // (projection[1][1] = 1 / tan(half the vertical field of view)), as the
  // renderer's (star_image_sigma).
  frame.stars.enabled = input.stars;
  frame.stars.sigma = float(0.6 * 2.0 / (std::abs(input.projection[1][1]) * double(input.height)));
  frame.volume_weight = aerial_perspective_volume_weight(params, camera_planet);
  frame.volume = frame.volume_weight > 0.0f;
  aerial_perspective_reach(params, camera_planet, frame.ap_t_min, frame.ap_t_far);
  // Directions in the world's axes to the engine's clip space: the view's
  // rotation, then the projection.
  frame.world_to_clip = glm::mat4(input.projection * glm::dmat4(glm::dmat3(input.view)));
  frame.surface_shell_radius = float(double(params.bottom_radius) + kMaxSurfaceAltitude);
  // With moons the single scattering is integrated everywhere (as
  // scattering_along_ray does), node by node in their shadows.
  frame.low_sun = eclipse || sun_may_be_low(params, camera_planet, frame.sun_direction);
  frame.shadows = input.shadow_map != 0;
  frame.shadow_steps = input.shadow_steps;
  frame.space_volume = uses_space_volume(params, frame);
  // Camera-relative metres -> the light's clip space: the engine's world
  // point is camera_world + offset * units_per_metre (composed in double,
  // so the camera's distance from the world origin never meets a float).
  frame.shadow_matrix = glm::mat4(input.shadow_matrix * glm::translate(glm::dmat4(1.0), camera_world) *
                                  glm::scale(glm::dmat4(1.0), glm::dvec3(planet.units_per_metre)));
  return frame;
}

void set_shadow_depth_bias(const FrameInput& input, int width, int height, physics::PassFrame& frame) {
  // The map's texel footprint (m) from the rows of the camera-relative
  // shadow matrix (clip units per metre), and its depth per metre.
  const glm::dmat4 m(frame.shadow_matrix);
  const auto row_length = [&](int row) { return glm::length(glm::dvec3(m[0][row], m[1][row], m[2][row])); };
  const double texel_m = std::max(2.0 / (double(width) * row_length(0)), 2.0 / (double(height) * row_length(1)));
  const double bias_m = input.shadow_bias_m > 0.0 ? input.shadow_bias_m : 1.5 * texel_m;
  frame.shadow_depth_bias = float(0.5 * row_length(2) * bias_m);
}

CpuSkyView compute_sky_view_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                const runtime::TableSamplers& samplers, const glm::vec3& camera,
                                const glm::vec3& sun, const physics::Moons& moons) {
  CpuSkyView view;
  for (auto& t : view.textures) t.assign(size_t(SKY_VIEW_WIDTH) * SKY_VIEW_HEIGHT, glm::vec3(0.0f));
  physics::SkyViewFrame frame = physics::sky_view_frame(params, physics::camera_above_ground(params, camera), sun);
  frame.full_azimuth = moons.count > 0;
  const bool low_sun = moons.count > 0 || physics::sun_may_be_low_on_view_rays(params, camera, sun);
  tbb::parallel_for(0, SKY_VIEW_HEIGHT, [&](int y) {
    for (int x = 0; x < SKY_VIEW_WIDTH; ++x) {
      // The texel centre, as gl_FragCoord gives it to the sky-view pass.
      const glm::vec2 uv((float(x) + 0.5f) / float(SKY_VIEW_WIDTH), (float(y) + 0.5f) / float(SKY_VIEW_HEIGHT));
      const size_t i = size_t(y) * SKY_VIEW_WIDTH + size_t(x);
      physics::compute_sky_view_texel(params, spectral, samplers.spectral_optical_depth, samplers.scattering,
                                      samplers.single_aerosol, samplers.multiple_scattering,
                                      samplers.indirect_irradiance, frame, camera, sun, uv, low_sun, moons,
                                      view.textures[0][i],
                                      view.textures[1][i], view.textures[2][i]);
    }
  });
  return view;
}

CpuVolume compute_volume_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                             const runtime::TableSamplers& samplers, const physics::PassFrame& frame) {
  CpuVolume volume;
  const size_t size = size_t(AP_WIDTH) * AP_HEIGHT * AP_SLICES;
  for (auto& t : volume.textures) t.assign(size, glm::vec3(0.0f));
  volume.textures[3].assign(size, glm::vec3(1.0f));
  if (!frame.volume) return volume;
  tbb::parallel_for(0, AP_HEIGHT, [&](int y) {
    for (int x = 0; x < AP_WIDTH; ++x) {
      auto march = std::make_unique<physics::AerialPerspectiveMarch>(physics::aerial_perspective_march_begin(
          params, spectral, samplers.spectral_optical_depth, samplers.multiple_scattering, frame, x, y));
      for (int z = 0; z < AP_SLICES; ++z) {
        const physics::AerialPerspectiveSlice slice = physics::aerial_perspective_march_slice(
            params, spectral, samplers.spectral_optical_depth, samplers.multiple_scattering, frame, *march, z);
        const size_t i = (size_t(z) * AP_HEIGHT + size_t(y)) * AP_WIDTH + size_t(x);
        volume.textures[0][i] = slice.single_rayleigh + slice.multiple;
        volume.textures[1][i] = slice.single_rayleigh;
        volume.textures[2][i] = slice.aerosol;
        volume.textures[3][i] = slice.transmittance;
      }
    }
  });
  return volume;
}

// The regular columns of the space volume (composite.glsl:
// space_volume_covers, see space_volume_columns): the largest air mass at
// the ground (75.5° from the zenith) and relative step of it between
// neighbouring columns.
constexpr float kSpaceVolumeMaxAirMass = 4.0f;
constexpr float kSpaceVolumeMaxAirMassStep = 0.1f;

// The least fraction of the space volume's columns that must be regular for
// the volume to pay: it adds a classifying draw over the whole image (on
// llvmpipe about what the exact evaluation of 8 % of the image's surfaces
// costs more than reading the volume), and the columns are spread evenly
// over the image.
constexpr double kSpaceVolumeMinRegularFraction = 0.1;

bool uses_space_volume(const physics::AtmosphereParams& params, const physics::PassFrame& frame) {
  if (physics::camera_uses_sky_view(params, frame.camera) || frame.shadows || frame.moons.count > 0) return false;
  const size_t regular = space_volume_columns(params, frame).order.size();
  return double(regular) >= kSpaceVolumeMinRegularFraction * double(SPACE_VOLUME_WIDTH * SPACE_VOLUME_HEIGHT);
}

SpaceVolumeColumns space_volume_columns(const physics::AtmosphereParams& params, const physics::PassFrame& frame) {
  SpaceVolumeColumns columns;
  const size_t count = size_t(SPACE_VOLUME_WIDTH) * SPACE_VOLUME_HEIGHT;
  columns.regular.assign(count, glm::vec3(0.0f));
  // Per column: the air mass 1 / mu at the ray's ground point (0 for a ray
  // that misses the ground sphere), and whether it needs the low sun.
  std::vector<float> air_mass(count, 0.0f);
  std::vector<bool> needs(count, false);
  for (int y = 0; y < SPACE_VOLUME_HEIGHT; ++y)
    for (int x = 0; x < SPACE_VOLUME_WIDTH; ++x) {
      const int index = y * SPACE_VOLUME_WIDTH + x;
      const glm::vec3 view_ray = physics::space_volume_view_ray(frame, x, y);
      needs[size_t(index)] = frame.low_sun && physics::space_volume_column_needs_low_sun(params, frame, view_ray);
      glm::vec3 start = frame.camera;
      if (physics::enter_atmosphere(params, start, view_ray)) {
        const float r = glm::length(start);
        const float mu = physics::clamp_cosine(glm::dot(start, view_ray) / r);
        if (physics::ray_intersects_ground(params, r, mu)) {
          const float d = physics::distance_to_bottom_atmosphere_boundary(params, r, mu);
          air_mass[size_t(index)] = 1.0f / std::max(-physics::mu_along_ray(r, mu, d, params.bottom_radius), 1e-6f);
        }
      }
    }
  // Regular: the ray meets the ground sphere no more than 1 /
  // kSpaceVolumeMaxAirMass from grazing, needs no low sun, and the air mass
  // of each neighbouring column differs from its own by less than
  // kSpaceVolumeMaxAirMassStep of it: towards the limb the air mass changes
  // faster than the texels follow (seen from afar a texel spans degrees of
  // the ground's zenith angle there), and linear interpolation over a
  // relative step s errs by about s² / 8 of the light.
  for (int y = 0; y < SPACE_VOLUME_HEIGHT; ++y)
    for (int x = 0; x < SPACE_VOLUME_WIDTH; ++x) {
      const size_t i = size_t(y) * SPACE_VOLUME_WIDTH + size_t(x);
      const float m = air_mass[i];
      bool regular = m > 0.0f && m <= kSpaceVolumeMaxAirMass && !needs[i];
      for (const glm::ivec2 step : {glm::ivec2(1, 0), glm::ivec2(-1, 0), glm::ivec2(0, 1), glm::ivec2(0, -1)}) {
        const int nx = x + step.x, ny = y + step.y;
        if (nx < 0 || ny < 0 || nx >= SPACE_VOLUME_WIDTH || ny >= SPACE_VOLUME_HEIGHT) continue;
        const float n = air_mass[size_t(ny) * SPACE_VOLUME_WIDTH + size_t(nx)];
        regular = regular && std::abs(n - m) <= kSpaceVolumeMaxAirMassStep * m;
      }
      if (regular) {
        columns.regular[i] = glm::vec3(1.0f);
        columns.order.push_back(int(i));
      }
    }
  return columns;
}

CpuVolume compute_space_volume_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                   const runtime::TableSamplers& samplers, const physics::PassFrame& frame) {
  CpuVolume volume;
  volume.width = SPACE_VOLUME_WIDTH;
  volume.height = SPACE_VOLUME_HEIGHT;
  volume.slices = SPACE_VOLUME_SLICES;
  const size_t size = size_t(SPACE_VOLUME_WIDTH) * SPACE_VOLUME_HEIGHT * SPACE_VOLUME_SLICES;
  for (auto& t : volume.textures) t.assign(size, glm::vec3(0.0f));
  const SpaceVolumeColumns columns = space_volume_columns(params, frame);
  tbb::parallel_for(0, int(columns.order.size()), [&](int k) {
    const int index = columns.order[size_t(k)];
    const int x = index % SPACE_VOLUME_WIDTH, y = index / SPACE_VOLUME_WIDTH;
    const glm::vec3 view_ray = physics::space_volume_view_ray(frame, x, y);
    for (int z = 0; z < SPACE_VOLUME_SLICES; ++z) {
      const physics::PathScattering p = physics::space_volume_texel(
          params, spectral, samplers.spectral_optical_depth, samplers.scattering, samplers.single_aerosol,
          samplers.multiple_scattering, frame, view_ray, z, false, false);
      const size_t i = (size_t(z) * SPACE_VOLUME_HEIGHT + size_t(y)) * SPACE_VOLUME_WIDTH + size_t(x);
      volume.textures[0][i] = p.single_rayleigh + p.multiple;
      volume.textures[1][i] = p.single_rayleigh;
      volume.textures[2][i] = p.aerosol;
      volume.textures[3][i] = p.transmittance;
    }
  });
  return volume;
}

std::vector<AerialPerspectiveSample> aerial_perspective_cpu(const Atmosphere& atmosphere, const Tables& tables,
                                                            const glm::dvec3& camera, const glm::dvec3& sun,
                                                            const std::vector<glm::dvec3>& offsets, bool use_volume) {
  check_tables_match(atmosphere, tables);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const runtime::TableSamplers samplers = runtime::make_samplers(tables);
  physics::PassFrame frame{};
  frame.camera = glm::vec3(camera);
  frame.sun_direction = glm::vec3(glm::normalize(sun));
  frame.sky_view = physics::sky_view_frame(params, physics::camera_above_ground(params, frame.camera),
                                           frame.sun_direction);
  frame.volume_weight = use_volume ? aerial_perspective_volume_weight(params, camera) : 0.0f;
  frame.volume = frame.volume_weight > 0.0f;
  aerial_perspective_reach(params, camera, frame.ap_t_min, frame.ap_t_far);
  frame.low_sun = sun_may_be_low(params, camera, frame.sun_direction);
  frame.moons = physics::no_moons();
  const CpuVolume volume = compute_volume_cpu(params, *spectral, samplers, frame);
  std::vector<AerialPerspectiveSample> out(offsets.size());
  for (size_t i = 0; i < offsets.size(); ++i) {
    const float t = float(glm::length(offsets[i]));
    const glm::vec3 view_ray(glm::normalize(offsets[i]));
    const physics::PathScattering s = physics::light_to_distance(
        params, *spectral, samplers.spectral_optical_depth, samplers.scattering, samplers.single_aerosol,
        samplers.multiple_scattering, volume.sampler(0), volume.sampler(1), volume.sampler(2), volume.sampler(3),
        frame, view_ray, t, true);
    const float nu = physics::clamp_cosine(glm::dot(view_ray, frame.sun_direction));
    out[i].single = glm::dvec3(physics::phase_weighted_scattering(params, s.single_rayleigh, s.aerosol, nu));
    out[i].multiple = glm::dvec3(s.multiple * physics::rayleigh_phase_function(nu));
    out[i].transmittance = glm::dvec3(s.transmittance);
  }
  return out;
}

std::vector<glm::vec3> composite_cpu(const Atmosphere& atmosphere, const Tables& tables, const PlanetFrame& planet,
                                     const FrameInput& input, const CpuEngineBuffers& buffers,
                                     const std::vector<glm::ivec2>& pixels, bool space_volume) {
  check_tables_match(atmosphere, tables);
  validate_frame_numbers(input);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const glm::mat3 matrix = physics::channels_to_srgb_matrix(tables.wavelengths_nm);
  physics::PassFrame frame = make_pass_frame(input, planet, params, matrix, own_sun_illuminance(params, matrix));
  if (input.shadow_map != 0) set_shadow_depth_bias(input, buffers.shadow_width, buffers.shadow_height, frame);
  const runtime::TableSamplers samplers = runtime::make_samplers(tables);
  const bool sky_view_camera = physics::camera_uses_sky_view(params, frame.camera);
  // Cameras above the atmosphere evaluate every ray; their table stays unread.
  CpuSkyView sky_view;
  if (sky_view_camera)
    sky_view = compute_sky_view_cpu(params, *spectral, samplers, frame.camera, frame.sun_direction, frame.moons);
  if (!space_volume) frame.space_volume = false;
  const CpuVolume volume = frame.space_volume ? compute_space_volume_cpu(params, *spectral, samplers, frame)
                                              : compute_volume_cpu(params, *spectral, samplers, frame);
  std::vector<glm::vec3> regular_columns(1, glm::vec3(0.0f));
  if (frame.space_volume) regular_columns = space_volume_columns(params, frame).regular;
  const physics::sampler2D regular_sampler = frame.space_volume
                                                 ? physics::sampler2D{SPACE_VOLUME_WIDTH, SPACE_VOLUME_HEIGHT,
                                                                      regular_columns.data()}
                                                 : physics::sampler2D{1, 1, regular_columns.data()};
  const physics::sampler2DShadow shadow_map{buffers.shadow_width, buffers.shadow_height,
                                           buffers.shadow_depth.data()};
  std::vector<glm::vec3> out(pixels.size());
  tbb::parallel_for(size_t(0), pixels.size(), [&](size_t k) {
    const glm::ivec2 pixel = pixels[k];
    const size_t i = size_t(pixel.y) * size_t(input.width) + size_t(pixel.x);
    // The pixel centre, as gl_FragCoord gives it to the pass.
    const glm::vec2 centre(float(pixel.x) + 0.5f, float(pixel.y) + 0.5f);
    const glm::vec2 ndc = centre / glm::vec2(float(input.width), float(input.height)) * 2.0f - 1.0f;
    const bool gbuffer = frame.surface_mode == SURFACE_GBUFFER;
    const physics::PixelRay ray = physics::pixel_ray(frame.inverse_projection, frame.view_to_world, ndc);
    out[k] = physics::composite_pixel(
        params, *spectral, samplers.spectral_optical_depth, samplers.scattering, samplers.single_aerosol,
        samplers.multiple_scattering, samplers.indirect_irradiance, sky_view.sampler(0), sky_view.sampler(1),
        sky_view.sampler(2), sky_view_camera, volume.sampler(0), volume.sampler(1), volume.sampler(2),
        volume.sampler(3), regular_sampler, frame, shadow_map, ray, buffers.depth[i],
        gbuffer ? glm::vec3(0.0f) : buffers.colour[i], gbuffer ? buffers.albedo[i] : glm::vec3(0.0f),
        gbuffer ? buffers.normal[i] : glm::vec3(0.0f, 0.0f, 1.0f), physics::pixel_dither(centre));
  });
  return out;
}

}  // namespace atmos::gpu
