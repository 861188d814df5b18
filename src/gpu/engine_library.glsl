// atmos — the GLSL library for engines that shade in their own shaders
// (AtmospherePass::glsl_library; GLSL only). Appended after the physics it
// uses (gpu/shader_source.cpp: kEngineLibraryPhysics, up to
// view_ray_scattering.glsl and aerial_perspective.glsl), with
// ATMOS_UNIT_0..4 (the texture units) and ATMOS_RADIANCE_TO_SRGB (read from
// the parameter block, like ATMOSPHERE and SPECTRAL) defined.
//
// Conventions of every atmos_* function:
//  - positions in metres relative to the planet centre, in the engine's world
//    axes; directions are unit vectors in the same axes;
//  - radiance in linear sRGB, cd/m² (luminance scale), for the sun at the
//    atmosphere's own illuminance (scale it as FrameInput::sun_illuminance_lux
//    and nits_per_unit scale the pass, to stay consistent with it);
//  - irradiance in the same units times sr (so that albedo / PI times it is
//    a radiance in cd/m²).
// The shared part also defines the functions and macros of atmos's physics
// (PI, IN, OUT, INLINE, transmittance_along_ray, ...): avoid those names.
//
// ATMOS_INSTANT is 1 for a pass of the instant mode (Hillaire 2020,
// docs/instant.md), whose tables hold no 4D table: the sky and the aerial
// perspective are then integrated along the ray at each call
// (instant_atmosphere.glsl: instant_radiance_to_distance, 24 intervals),
// through the optical depth and the multiple-scattering table; the
// irradiance, the transmittance and the eclipse factors read the same
// tables as in the exact mode.

layout(binding = ATMOS_UNIT_0) uniform sampler2D atmos_optical_depth_texture;
layout(binding = ATMOS_UNIT_3) uniform sampler2D atmos_irradiance_texture;
#if ATMOS_INSTANT
layout(binding = ATMOS_UNIT_1) uniform sampler2D atmos_instant_multiple_scattering_texture;

// The march's light in the tables' channels, converted as the exact
// functions convert theirs (below).
vec3 atmos_instant_radiance(vec3 camera, vec3 view_ray, vec3 sun, float t_end, out vec3 transmittance) {
  vec3 channels = instant_radiance_to_distance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture,
                                               atmos_instant_multiple_scattering_texture, camera, view_ray, sun, t_end,
                                               true, transmittance);
  vec3 s = ATMOS_RADIANCE_TO_SRGB * ATMOSPHERE.solar_irradiance;
  transmittance = clamp(ATMOS_RADIANCE_TO_SRGB * (ATMOSPHERE.solar_irradiance * transmittance) / max(s, vec3(1e-30)),
                        vec3(0.0), vec3(1.0));
  return max(ATMOS_RADIANCE_TO_SRGB * channels, vec3(0.0));
}
#else
layout(binding = ATMOS_UNIT_1) uniform sampler3D atmos_scattering_texture;
layout(binding = ATMOS_UNIT_2) uniform sampler3D atmos_single_aerosol_texture;
layout(binding = ATMOS_UNIT_4) uniform sampler3D atmos_multiple_scattering_texture;
#endif

// Radiance of the sky (or of the atmosphere in front of the planet's sphere)
// along a view ray from `camera`, excluding the sun disc and the ground
// itself, and the transmittance of that path (linear sRGB, for sunlight).
vec3 atmos_sky_radiance(vec3 camera, vec3 view_ray, vec3 sun, out vec3 transmittance) {
#if ATMOS_INSTANT
  return atmos_instant_radiance(camera_above_ground(ATMOSPHERE, camera), view_ray, sun, -1.0, transmittance);
#else
  vec3 channels = sky_radiance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, atmos_scattering_texture,
                               atmos_single_aerosol_texture, atmos_multiple_scattering_texture,
                               camera_above_ground(ATMOSPHERE, camera), view_ray, sun, transmittance);
  vec3 s = ATMOS_RADIANCE_TO_SRGB * ATMOSPHERE.solar_irradiance;
  transmittance = clamp(ATMOS_RADIANCE_TO_SRGB * (ATMOSPHERE.solar_irradiance * transmittance) / max(s, vec3(1e-30)),
                        vec3(0.0), vec3(1.0));
  return ATMOS_RADIANCE_TO_SRGB * channels;
#endif
}

// In-scattered radiance between `camera` and the point camera + `offset`
// (aerial perspective), and the transmittance between them (linear sRGB):
// a surface of radiance L at the point is seen as L * transmittance + the
// returned radiance.
vec3 atmos_radiance_to_point(vec3 camera, vec3 offset, vec3 sun, out vec3 transmittance) {
#if ATMOS_INSTANT
  float t = length(offset);
  if (!(t > 0.0)) {
    transmittance = vec3(1.0);
    return vec3(0.0);
  }
  return atmos_instant_radiance(camera_above_ground(ATMOSPHERE, camera), offset / t, sun, t, transmittance);
#else
  float nu;
  PathScattering s = scattering_to_point(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, atmos_scattering_texture,
                                         atmos_single_aerosol_texture, atmos_multiple_scattering_texture, camera,
                                         offset, sun, true, false, transmittance, nu);
  vec3 sun_srgb = ATMOS_RADIANCE_TO_SRGB * ATMOSPHERE.solar_irradiance;
  transmittance =
      clamp(ATMOS_RADIANCE_TO_SRGB * (ATMOSPHERE.solar_irradiance * transmittance) / max(sun_srgb, vec3(1e-30)),
            vec3(0.0), vec3(1.0));
  return max(ATMOS_RADIANCE_TO_SRGB * path_radiance(ATMOSPHERE, s, nu), vec3(0.0));
#endif
}

// Irradiance of the sun (returned; with the planet's shadow and the
// atmosphere's transmittance, not the engine's shadows) and of the sky
// (`sky_irradiance`) on a surface at `point` with unit normal `normal`.
vec3 atmos_sun_and_sky_irradiance(vec3 point, vec3 normal, vec3 sun, out vec3 sky_irradiance) {
  vec3 sky;
  vec3 direct = sun_and_sky_irradiance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, atmos_irradiance_texture,
                                       point, normal, sun, sky);
  sky_irradiance = ATMOS_RADIANCE_TO_SRGB * sky;
  return ATMOS_RADIANCE_TO_SRGB * direct;
}

// Transmittance from `point` to the sun (linear sRGB, averaged over the
// solar disc, 0 in the planet's shadow): the colour of direct sunlight there
// relative to the sunlight at the top of the atmosphere.
vec3 atmos_transmittance_to_sun(vec3 point, vec3 sun) {
  float r = length(point);
  vec3 t = channel_transmittance(ATMOSPHERE, SPECTRAL, atmos_optical_depth_texture, PATH_TO_SUN,
                                 clamp_radius(ATMOSPHERE, r), clamp_cosine(dot(point, sun) / r));
  vec3 s = ATMOS_RADIANCE_TO_SRGB * ATMOSPHERE.solar_irradiance;
  return clamp(ATMOS_RADIANCE_TO_SRGB * (ATMOSPHERE.solar_irradiance * t) / max(s, vec3(1e-30)), vec3(0.0),
               vec3(1.0));
}

// Eclipses (FrameInput::moons): the factors by which the moons dim, at
// `point`, the sun's irradiance (the part of the limb-darkened sun they
// leave visible: eclipse.glsl, sunlight_visible_fraction) and the sky's
// (the documented approximation for diffuse light: ray_integration.glsl,
// diffuse_light_visible_fraction) — what the pass applies to the surfaces
// it lights itself (SurfaceMode::gbuffer); an engine that lights its own
// surfaces multiplies atmos_sun_and_sky_irradiance's two results by them.
// `moon_spheres[i]`: xyz the centre (planet-centred metres, the frame of
// FrameInput::moons), w the radius; `moon_count`: how many, at most
// MOON_CAPACITY (4). Costs ~60 disc overlaps per call with a moon, nothing
// without (moon_count 0).
void atmos_eclipse(vec3 point, vec3 sun, int moon_count, vec4 moon_spheres[MOON_CAPACITY], out float sun_factor,
                   out float sky_factor) {
  Moons moons = no_moons();
  moons.count = clamp(moon_count, 0, MOON_CAPACITY);
  for (int i = 0; i < MOON_CAPACITY; ++i) moons.sphere[i] = moon_spheres[i];
  sun_factor = sunlight_visible_fraction(moons, ATMOSPHERE.sun_angular_radius, point, sun);
  sky_factor = diffuse_light_visible_fraction(SPECTRAL.set[0], atmos_optical_depth_texture, moons, point, sun);
}
