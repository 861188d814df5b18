// atmos — the instant mode's parts of the engine plugin's pass (shared by
// instant_aerial_perspective.comp.glsl, atmosphere_pass.frag.glsl and their
// CPU twin, gpu/instant_composite_cpp.hpp).
//
// The aerial-perspective volume: the exact mode's volume (composite.glsl:
// its directions, slices and textures, read by the same
// aerial_perspective_lookup), each direction marched through the
// multiple-scattering table (physics/instant_atmosphere.glsl) instead of the
// 4D tables: Hillaire 2020's aerial-perspective volume, over the world
// directions of the sky-view table rather than screen froxels, as the exact
// mode's.
//
// Needs: composite.glsl, instant_atmosphere.glsl.

// The march of direction (x, y) of the volume, at its camera. As the exact
// mode's (aerial_perspective_march_begin), the march follows the straight
// ray through the ground sphere (the engine's surfaces may lie below it),
// with the medium of the ground there (clamp_radius).
INLINE InstantMarch instant_volume_begin(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                         IN(sampler2D) transmittance_texture,
                                         IN(sampler2D) multiple_scattering_texture, IN(PassFrame) frame, int x,
                                         int y) {
  vec3 camera = camera_above_ground(atmosphere, frame.camera);
  vec2 uv = vec2((float(x) + 0.5f) / float(AP_WIDTH), (float(y) + 0.5f) / float(AP_HEIGHT));
  bool ground;
  vec3 view_ray = sky_view_direction_of_size(frame.sky_view, uv, AP_WIDTH, AP_HEIGHT, ground);
  return instant_march_begin(atmosphere, spectral, transmittance_texture, multiple_scattering_texture, camera,
                             view_ray, frame.sun_direction, frame.low_sun);
}

// Advances the march to slice s (the next one) and returns the light
// between the camera and it, INSTANT_SLICE_INTERVALS intervals per slice.
INLINE AerialPerspectiveSlice instant_volume_slice(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                                   IN(sampler2D) transmittance_texture,
                                                   IN(sampler2D) multiple_scattering_texture, IN(PassFrame) frame,
                                                   INOUT(InstantMarch) m, int s) {
  instant_march_to(spectral, transmittance_texture, multiple_scattering_texture, m,
                   aerial_perspective_slice_distance(frame, s), INSTANT_SLICE_INTERVALS, frame.low_sun);
  AerialPerspectiveSlice slice;
  instant_march_light(atmosphere, spectral, m, slice.single_rayleigh, slice.multiple, slice.aerosol,
                      slice.transmittance);
  return slice;
}

// A pixel of a camera above the atmosphere in the instant mode, whatever it
// shows: no sky-view table serves such a camera (sky_view_table.glsl) and
// no volume its surfaces, so its ray is integrated per pixel from where it
// enters the atmosphere (as Hillaire 2020 renders views from space): to the
// ground sphere or the top for the sky (instant_view_ray_terms, with what
// lies beyond), to the surface for the engine's surfaces, lit as
// composite_surface_pixel lights them (without shadow map: frames with one
// draw the sky and the surfaces from above the atmosphere unshadowed in
// this mode). Same units as composite_pixel.
INLINE vec3 instant_space_pixel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                IN(sampler2D) transmittance_texture, IN(sampler2D) multiple_scattering_texture,
                                IN(sampler2D) irradiance_texture, IN(PassFrame) frame, IN(PixelRay) ray, float depth,
                                vec3 colour, vec3 albedo, vec3 normal) {
  vec3 camera = camera_above_ground(atmosphere, frame.camera);
  bool sky = depth_is_sky(depth, frame.depth_encoding);
  vec3 offset = vec3(0.0f);
  float t = 0.0f;
  vec3 view_ray = world_view_ray(frame, ray);
  if (!sky) {
    offset = world_offset_from_depth(frame, ray, depth);
    t = length(offset);
    if (t > 0.0f) view_ray = offset / t;
  }
  vec3 start = camera;
  bool inside = enter_atmosphere(atmosphere, start, view_ray);
  float nu = clamp_cosine(dot(view_ray, frame.sun_direction));
  if (sky) {
    vec3 beyond = radiance_beyond_atmosphere(atmosphere, camera, view_ray, frame.sun_direction, frame.sun_disc,
                                             frame.stars, frame.moons);
    vec3 radiance = beyond;
    if (inside) {
      float r = clamp_radius(atmosphere, length(start));
      bool ground = ray_intersects_ground(atmosphere, r, clamp_cosine(dot(start, view_ray) / r));
      vec3 rayleigh;
      vec3 aerosol;
      vec3 surface;
      instant_view_ray_terms(atmosphere, spectral, transmittance_texture, multiple_scattering_texture,
                             irradiance_texture, start, view_ray, frame.sun_direction, ground, frame.low_sun,
                             rayleigh, aerosol, surface);
      radiance = phase_weighted_scattering(atmosphere, rayleigh, aerosol, nu) + (ground ? surface : surface * beyond);
    }
    return max(frame.radiance_to_srgb * radiance, vec3(0.0f)) * frame.light_scale;
  }
  vec3 transmittance;
  vec3 in_scatter = instant_radiance_to_distance(atmosphere, spectral, transmittance_texture,
                                                 multiple_scattering_texture, camera, view_ray,
                                                 frame.sun_direction, t, frame.low_sun, transmittance);
  vec3 surface = colour;
  if (frame.surface_mode == SURFACE_GBUFFER) {
    vec3 point = frame.camera + offset;
    float r = length(point);
    vec3 up = point / r;
    vec3 n = dot(normal, normal) > 0.0f ? normalize(normal) : up;
    vec3 sky_irradiance;
    vec3 sun_irradiance = sun_and_sky_irradiance_at(atmosphere, spectral, transmittance_texture, irradiance_texture,
                                                    r, up, n, frame.sun_direction, sky_irradiance);
    vec3 light = max(frame.radiance_to_srgb * (sun_irradiance + sky_irradiance), vec3(0.0f));
    surface = albedo * (1.0f / PI) * light * frame.light_scale;
  }
  return surface * srgb_transmittance(atmosphere, frame, transmittance) +
         max(frame.radiance_to_srgb * in_scatter, vec3(0.0f)) * frame.light_scale;
}
