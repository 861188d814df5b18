// atmos — the per-frame sky-view table: its parameterisation over view
// directions, which cameras use it and with which program variant, and its
// texels.
//
// Needs: view_ray_scattering.glsl (and the parts it needs).

// The sky-view table: scattering_along_ray for one camera and sun, over view
// directions, recomputed every frame (the idea of Hillaire 2020's sky-view
// LUT). Integrating a low-sun ray costs ~50 evaluations of the medium and of
// the transmittance to the sun — seconds per frame for a full screen on a
// software rasteriser. But for a given camera and sun a view ray is fixed by
// its direction, so a small 2D table over directions holds the result, with
// mu_s exact; the render pass then reads 2 texels per pixel instead of the
// 4 (3D) texels of the 4D tables. Parameterisation:
//  - x: azimuth phi in [0, π] from the sun's vertical plane (the radiance is
//    symmetric about it), linear; in [-π, π] for an eclipse, which breaks
//    the symmetry (SkyViewFrame.full_azimuth);
//  - y: view zenith angle, split at the ground's horizon like the scattering
//    table's mu (ground rays below 0.5, the others above, so that the
//    discontinuity falls between texels), each half with texels concentrated
//    towards the horizon (x = sqrt of the normalised angle from it), between
//    the nadir and the horizon for ground rays and between the horizon and
//    the zenith for the others.
// Texels hold view_ray_terms: the phase-free values of scattering_along_ray
// (phase functions are applied per pixel, so the sun's aerosol halo stays
// sharp) and what is at the ray's end (the lit ground sphere, or the
// transmittance to space for the sun disc), in three textures.
// Used for cameras in the atmosphere: from space, the lit atmosphere near the
// terminator spans a few degrees of view and the table blurs it (30 % errors
// at 2 planet radii), so rays are evaluated one by one there.
#define SKY_VIEW_WIDTH 96
#define SKY_VIEW_HEIGHT 256

struct SkyViewFrame {
  vec3 zenith;          // unit vector from the planet centre to the camera
  vec3 sun_side;        // horizontal unit vector towards the sun's azimuth
  vec3 across;          // zenith x sun_side
  float theta_horizon;  // view zenith angle of the ground's horizon
  // x spans the azimuth from -pi to pi instead of 0 to pi: for an eclipse,
  // whose moons' shadows are not symmetric about the sun's vertical plane
  // (at half the azimuthal resolution).
  bool full_azimuth;
};

// Whether a camera (relative to the planet centre) uses the sky-view table.
INLINE bool camera_uses_sky_view(IN(AtmosphereParams) atmosphere, vec3 camera) {
  return length(camera) <= atmosphere.top_radius;
}

// `camera` relative to the planet centre, at or above the ground.
INLINE SkyViewFrame sky_view_frame(IN(AtmosphereParams) atmosphere, vec3 camera, vec3 sun_direction) {
  SkyViewFrame frame;
  float r = length(camera);
  frame.zenith = camera / r;
  vec3 side = sun_direction - frame.zenith * dot(sun_direction, frame.zenith);
  if (dot(side, side) < 1e-10f) {
    // Sun at the zenith or nadir: every azimuth is the same, pick one.
    side = abs(frame.zenith.x) < 0.9f ? cross(frame.zenith, vec3(1.0f, 0.0f, 0.0f))
                                      : cross(frame.zenith, vec3(0.0f, 1.0f, 0.0f));
  }
  frame.sun_side = normalize(side);
  frame.across = cross(frame.zenith, frame.sun_side);
  // pi/2 + the horizon's dip, asin(rho / r): accurate near the ground, where
  // asin(R / r) ~ asin(1 - 3e-7) would lose most of its digits.
  frame.theta_horizon = 0.5f * PI + asin(horizon_length(atmosphere, r) / r);
  frame.full_azimuth = false;
  return frame;
}

// Texture coordinates of a view direction in a table of width x height
// texels with this parameterisation; `ground` says which half (the
// caller's ray_intersects_ground, so that both agree at the horizon). The
// engine plugin's aerial-perspective volume (gpu/composite.glsl) uses it
// with its own size.
INLINE vec2 sky_view_uv_of_size(IN(SkyViewFrame) frame, vec3 view_ray, bool ground, int width, int height) {
  float theta = acos(clamp_cosine(dot(view_ray, frame.zenith)));
  float across = dot(view_ray, frame.across);
  float x_phi = frame.full_azimuth ? 0.5f + 0.5f * atan(across, dot(view_ray, frame.sun_side)) / PI
                                   : atan(abs(across), dot(view_ray, frame.sun_side)) / PI;
  float v;
  if (ground) {
    float x = safe_sqrt((theta - frame.theta_horizon) / max(PI - frame.theta_horizon, 1e-7f));
    v = 0.5f - 0.5f * texture_coord_from_unit_range(min(x, 1.0f), height / 2);
  } else {
    float x = safe_sqrt((frame.theta_horizon - theta) / frame.theta_horizon);
    v = 0.5f + 0.5f * texture_coord_from_unit_range(min(x, 1.0f), height / 2);
  }
  return vec2(texture_coord_from_unit_range(x_phi, width), v);
}

INLINE vec2 sky_view_uv(IN(SkyViewFrame) frame, vec3 view_ray, bool ground) {
  return sky_view_uv_of_size(frame, view_ray, ground, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT);
}

// The view direction of texture coordinates uv in a table of width x
// height texels, and whether its ray is in the ground half.
INLINE vec3 sky_view_direction_of_size(IN(SkyViewFrame) frame, vec2 uv, int width, int height, OUT(bool) ground) {
  float theta;
  ground = uv.y < 0.5f;
  if (ground) {
    float x = unit_range_from_texture_coord(1.0f - 2.0f * uv.y, height / 2);
    theta = frame.theta_horizon + x * x * (PI - frame.theta_horizon);
  } else {
    float x = unit_range_from_texture_coord(2.0f * uv.y - 1.0f, height / 2);
    theta = frame.theta_horizon * (1.0f - x * x);
  }
  float x_phi = unit_range_from_texture_coord(uv.x, width);
  float phi = frame.full_azimuth ? PI * (2.0f * x_phi - 1.0f) : PI * x_phi;
  return frame.zenith * cos(theta) + (frame.sun_side * cos(phi) + frame.across * sin(phi)) * sin(theta);
}

INLINE vec3 sky_view_direction(IN(SkyViewFrame) frame, vec2 uv, OUT(bool) ground) {
  return sky_view_direction_of_size(frame, uv, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT, ground);
}

// Whether the sun may be low (below LOW_SUN_MU_S_TABLE, where
// scattering_along_ray integrates single scattering) at some point of the
// view rays of a camera in the atmosphere. The sun's zenith angle at a point
// differs from the one above the camera by at most the angle between them
// seen from the planet centre, which for the points of the atmosphere the
// camera sees is at most acos(R / r) + acos(R / R_top) (the camera's horizon
// on the ground sphere plus the top's), here with 0.01 rad to spare for
// rounding. The sky-view table of a camera for which this is false needs no
// integration (a program variant without it: by day, the table in half the
// time).
INLINE bool sun_may_be_low_on_view_rays(IN(AtmosphereParams) atmosphere, vec3 camera, vec3 sun_direction) {
  float r = max(length(camera), atmosphere.bottom_radius);
  float reach = acos(atmosphere.bottom_radius / r) + acos(atmosphere.bottom_radius / atmosphere.top_radius);
  float sun_zenith = acos(clamp_cosine(dot(camera / r, sun_direction)));
  return sun_zenith + reach + 0.01f >= acos(LOW_SUN_MU_S_TABLE);
}

// One texel of the sky-view table (uv at the texel centre) of the camera
// whose frame is `frame` (sky_view_frame, computed once per frame on the
// CPU, so that the table and its readers agree on the directions to the
// last bit): view_ray_terms of its view direction. `low_sun_path`:
// sun_may_be_low_on_view_rays for the camera (a constant in shaders), or
// true with moons, whose table must also span the full azimuth (the
// eclipse breaks the symmetry about the sun's vertical: see SkyViewFrame).
INLINE void compute_sky_view_texel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                   IN(sampler2D) spectral_transmittance_texture,
                                   IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                   IN(sampler3D) multiple_scattering_texture, IN(sampler2D) irradiance_texture,
                                   IN(SkyViewFrame) frame, vec3 camera, vec3 sun_direction, vec2 uv,
                                   bool low_sun_path, IN(Moons) moons, OUT(vec3) rayleigh, OUT(vec3) aerosol,
                                   OUT(vec3) surface) {
  camera = camera_above_ground(atmosphere, camera);
  bool ground;
  vec3 view_ray = sky_view_direction(frame, uv, ground);
  // The half of the table decides, not the ray's own test: at the horizon
  // both must agree with the readers' ray_intersects_ground, which chose
  // this half.
  view_ray_terms(atmosphere, spectral, spectral_transmittance_texture, scattering_texture, single_aerosol_texture,
                 multiple_scattering_texture, irradiance_texture, camera, view_ray, sun_direction, ground,
                 low_sun_path, moons, rayleigh, aerosol, surface);
}
