// The instant approximate mode's GL-free part (see gpu/instant.hpp).
#include "gpu/instant.hpp"

#include <tbb/parallel_for.h>

#include <memory>

#include "gpu/instant_composite_cpp.hpp"
#include "physics/parameters.hpp"

namespace atmos::gpu {

namespace {

// Stands in for the 4D tables, which the instant mode's composite never
// reads (its variants read the sky-view table and the volume).
const glm::vec3 kNoTexel(0.0f);
const physics::sampler3D kNoTable{1, 1, 1, &kNoTexel};

}  // namespace

void make_instant_frame(const physics::AtmosphereParams& params, physics::PassFrame& frame) {
  frame.volume = physics::camera_uses_sky_view(params, frame.camera);
  frame.volume_weight = 1.0f;
  frame.space_volume = false;
}

InstantSamplers make_instant_samplers(const InstantTables& tables) {
  const TableSizes& s = tables.sizes;
  InstantSamplers out;
  out.spectral_optical_depth = {s.transmittance_mu * tables.transmittance_tiles(), s.transmittance_r,
                                tables.spectral_optical_depth.data()};
  out.multiple_scattering = {tables.multiple_scattering_mu_s * tables.spectral_sets(), tables.multiple_scattering_r,
                             tables.multiple_scattering.data()};
  out.indirect_irradiance = {s.irradiance_mu_s, s.irradiance_r, tables.indirect_irradiance.data()};
  return out;
}

CpuSkyView compute_instant_sky_view_cpu(const physics::AtmosphereParams& params,
                                        const physics::SpectralSets& spectral, const InstantSamplers& samplers,
                                        const glm::vec3& camera, const glm::vec3& sun) {
  CpuSkyView view;
  for (auto& t : view.textures) t.assign(size_t(SKY_VIEW_WIDTH) * SKY_VIEW_HEIGHT, glm::vec3(0.0f));
  const physics::SkyViewFrame frame =
      physics::sky_view_frame(params, physics::camera_above_ground(params, camera), sun);
  const bool low_sun = physics::sun_may_be_low_on_view_rays(params, camera, sun);
  tbb::parallel_for(0, SKY_VIEW_HEIGHT, [&](int y) {
    for (int x = 0; x < SKY_VIEW_WIDTH; ++x) {
      const glm::vec2 uv((float(x) + 0.5f) / float(SKY_VIEW_WIDTH), (float(y) + 0.5f) / float(SKY_VIEW_HEIGHT));
      const size_t i = size_t(y) * SKY_VIEW_WIDTH + size_t(x);
      physics::compute_instant_sky_view_texel(params, spectral, samplers.spectral_optical_depth,
                                              samplers.multiple_scattering, samplers.indirect_irradiance, frame,
                                              camera, sun, uv, low_sun, view.textures[0][i], view.textures[1][i],
                                              view.textures[2][i]);
    }
  });
  return view;
}

CpuVolume compute_instant_volume_cpu(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                     const InstantSamplers& samplers, const physics::PassFrame& frame) {
  CpuVolume volume;
  const size_t size = size_t(AP_WIDTH) * AP_HEIGHT * AP_SLICES;
  for (auto& t : volume.textures) t.assign(size, glm::vec3(0.0f));
  volume.textures[3].assign(size, glm::vec3(1.0f));
  if (!frame.volume) return volume;
  tbb::parallel_for(0, AP_HEIGHT, [&](int y) {
    for (int x = 0; x < AP_WIDTH; ++x) {
      auto march = std::make_unique<physics::InstantMarch>(physics::instant_volume_begin(
          params, spectral, samplers.spectral_optical_depth, samplers.multiple_scattering, frame, x, y));
      for (int z = 0; z < AP_SLICES; ++z) {
        const physics::AerialPerspectiveSlice slice = physics::instant_volume_slice(
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

std::vector<glm::vec3> composite_instant_cpu(const Atmosphere& atmosphere, const InstantTables& tables,
                                             const PlanetFrame& planet, const FrameInput& input,
                                             const CpuEngineBuffers& buffers, const std::vector<glm::ivec2>& pixels) {
  check_tables_match(atmosphere, tables);
  validate_frame_numbers(input);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const glm::mat3 matrix = physics::channels_to_srgb_matrix(tables.wavelengths_nm);
  physics::PassFrame frame = make_pass_frame(input, planet, params, matrix, own_sun_illuminance(params, matrix));
  if (frame.moons.count > 0) throw Error("plugin input: the instant mode draws no eclipses");
  if (input.shadow_map != 0) set_shadow_depth_bias(input, buffers.shadow_width, buffers.shadow_height, frame);
  make_instant_frame(params, frame);
  const InstantSamplers samplers = make_instant_samplers(tables);
  const bool sky_view_camera = physics::camera_uses_sky_view(params, frame.camera);
  CpuSkyView sky_view;
  CpuVolume volume;
  if (sky_view_camera) {
    sky_view = compute_instant_sky_view_cpu(params, *spectral, samplers, frame.camera, frame.sun_direction);
    volume = compute_instant_volume_cpu(params, *spectral, samplers, frame);
  }
  // The composite's variant: no low-sun integration (atmosphere_pass.cpp).
  physics::PassFrame composite_frame = frame;
  composite_frame.low_sun = false;
  const std::vector<glm::vec3> no_columns(1, glm::vec3(0.0f));
  const physics::sampler2D regular_sampler{1, 1, no_columns.data()};
  const physics::sampler2DShadow shadow_map{buffers.shadow_width, buffers.shadow_height,
                                           buffers.shadow_depth.data()};
  std::vector<glm::vec3> out(pixels.size());
  tbb::parallel_for(size_t(0), pixels.size(), [&](size_t k) {
    const glm::ivec2 pixel = pixels[k];
    const size_t i = size_t(pixel.y) * size_t(input.width) + size_t(pixel.x);
    const glm::vec2 centre(float(pixel.x) + 0.5f, float(pixel.y) + 0.5f);
    const glm::vec2 ndc = centre / glm::vec2(float(input.width), float(input.height)) * 2.0f - 1.0f;
    const bool gbuffer = frame.surface_mode == SURFACE_GBUFFER;
    const physics::PixelRay ray = physics::pixel_ray(frame.inverse_projection, frame.view_to_world, ndc);
    const glm::vec3 colour = gbuffer ? glm::vec3(0.0f) : buffers.colour[i];
    const glm::vec3 albedo = gbuffer ? buffers.albedo[i] : glm::vec3(0.0f);
    const glm::vec3 normal = gbuffer ? buffers.normal[i] : glm::vec3(0.0f, 0.0f, 1.0f);
    if (!sky_view_camera) {
      out[k] = physics::instant_space_pixel(params, *spectral, samplers.spectral_optical_depth,
                                            samplers.multiple_scattering, samplers.indirect_irradiance, frame, ray,
                                            buffers.depth[i], colour, albedo, normal);
      return;
    }
    out[k] = physics::composite_pixel(
        params, *spectral, samplers.spectral_optical_depth, kNoTable, kNoTable, kNoTable,
        samplers.indirect_irradiance, sky_view.sampler(0), sky_view.sampler(1), sky_view.sampler(2), true,
        volume.sampler(0), volume.sampler(1), volume.sampler(2), volume.sampler(3), regular_sampler,
        composite_frame, shadow_map, ray, buffers.depth[i], colour, albedo, normal, physics::pixel_dither(centre));
  });
  return out;
}

std::vector<glm::dvec3> instant_sky_radiance_cpu(const Atmosphere& atmosphere, const InstantTables& tables,
                                                 const glm::dvec3& camera, const glm::dvec3& sun,
                                                 const std::vector<glm::dvec3>& views) {
  check_tables_match(atmosphere, tables);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const InstantSamplers samplers = make_instant_samplers(tables);
  const glm::vec3 camera_f(camera);
  const glm::vec3 sun_f(glm::normalize(sun));
  if (!physics::camera_uses_sky_view(params, camera_f))
    throw Error("instant_sky_radiance_cpu: the camera is above the atmosphere");
  const CpuSkyView sky_view = compute_instant_sky_view_cpu(params, *spectral, samplers, camera_f, sun_f);
  const physics::SkyViewFrame frame =
      physics::sky_view_frame(params, physics::camera_above_ground(params, camera_f), sun_f);
  physics::StarField stars{};
  stars.enabled = false;
  std::vector<glm::dvec3> out(views.size());
  for (size_t i = 0; i < views.size(); ++i)
    out[i] = glm::dvec3(physics::radiance_along_view_ray_low_sun(
        params, *spectral, samplers.spectral_optical_depth, kNoTable, kNoTable, kNoTable,
        samplers.indirect_irradiance, sky_view.sampler(0), sky_view.sampler(1), sky_view.sampler(2), true, frame,
        camera_f, glm::vec3(glm::normalize(views[i])), sun_f, false, stars, physics::no_moons(), false, false));
  return out;
}

std::vector<AerialPerspectiveSample> instant_aerial_perspective_cpu(const Atmosphere& atmosphere,
                                                                    const InstantTables& tables,
                                                                    const glm::dvec3& camera, const glm::dvec3& sun,
                                                                    const std::vector<glm::dvec3>& offsets) {
  check_tables_match(atmosphere, tables);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const InstantSamplers samplers = make_instant_samplers(tables);
  physics::PassFrame frame{};
  frame.camera = glm::vec3(camera);
  frame.sun_direction = glm::vec3(glm::normalize(sun));
  if (!physics::camera_uses_sky_view(params, frame.camera))
    throw Error("instant_aerial_perspective_cpu: the camera is above the atmosphere");
  frame.sky_view = physics::sky_view_frame(params, physics::camera_above_ground(params, frame.camera),
                                           frame.sun_direction);
  aerial_perspective_reach(params, camera, frame.ap_t_min, frame.ap_t_far);
  frame.low_sun = true;
  frame.moons = physics::no_moons();
  make_instant_frame(params, frame);
  const CpuVolume volume = compute_instant_volume_cpu(params, *spectral, samplers, frame);
  std::vector<AerialPerspectiveSample> out(offsets.size());
  for (size_t i = 0; i < offsets.size(); ++i) {
    const float t = float(glm::length(offsets[i]));
    const glm::vec3 view_ray(glm::normalize(offsets[i]));
    const physics::PathScattering s =
        physics::aerial_perspective_lookup(frame, volume.sampler(0), volume.sampler(1), volume.sampler(2),
                                           volume.sampler(3), physics::aerial_perspective_uv(params, frame, view_ray),
                                           t, true);
    const float nu = physics::clamp_cosine(glm::dot(view_ray, frame.sun_direction));
    out[i].single = glm::dvec3(physics::phase_weighted_scattering(params, s.single_rayleigh, s.aerosol, nu));
    out[i].multiple = glm::dvec3(s.multiple * physics::rayleigh_phase_function(nu));
    out[i].transmittance = glm::dvec3(s.transmittance);
  }
  return out;
}

}  // namespace atmos::gpu
