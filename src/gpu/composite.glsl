// atmos — the engine plugin's per-pixel work (AtmospherePass): from the
// engine's depth and colour at a pixel to the composited radiance.
//
// Shared by the pass's fragment shader (atmosphere_pass.frag.glsl, after
// functions.glsl and aerial_perspective.glsl) and its CPU twin
// (gpu/composite_cpp.hpp, for the tests), in the GLSL / C++ subset of
// physics/definitions.glsl.
//
// Frames. The CPU reduces the engine's double-precision matrices to
// camera-relative floats (see atmosphere_pass.cpp): `inverse_projection`
// takes NDC to the engine's view space, `view_to_world` rotates view space to
// the world's (= the planet's) axes and converts engine units to metres, so
// that a pixel's offset from the camera, in metres, never involves the
// camera's distance from the planet centre or the world origin.

#define DEPTH_STANDARD 0    // NDC z in [-1, 1] -> depth [0, 1], clear value 1
#define DEPTH_REVERSED_Z 1  // NDC z = depth (GL_ZERO_TO_ONE), near 1, far 0, clear value 0
#define DEPTH_LOGARITHMIC 2 // depth = log2(1 + w) / log2(1 + F), clear value 1

#define SURFACE_LIT_COLOUR 0
#define SURFACE_GBUFFER 1

// The per-frame inputs of the pass. On the GPU, surface_mode, low_sun and
// shadows are constants of the program variant (software rasterisers run
// both sides of every branch: a uniform would make every pixel pay for the
// shadow march, the G-buffer lighting and the twilight integration), the
// rest are uniforms.
struct PassFrame {
  vec3 camera;              // m, relative to the planet centre
  vec3 sun_direction;       // unit, towards the sun
  mat4 inverse_projection;  // NDC -> engine view space
  mat3 view_to_world;       // engine view space -> world axes, engine units -> metres
  int depth_encoding;       // DEPTH_*
  float log2_depth_far;     // DEPTH_LOGARITHMIC: log2(1 + F)
  int surface_mode;         // SURFACE_*
  mat3 radiance_to_srgb;    // tables' channels -> linear sRGB, cd/m²
  float light_scale;        // (sun illuminance / the atmosphere's own) / nits_per_unit
  bool sun_disc;
  bool volume;              // surfaces read the aerial-perspective volume (cameras low in the atmosphere)
  float volume_weight;      // 1: the volume alone; below 1, mixed with the exact evaluation (a constant 1 or not)
  float ap_t_min;           // m, no surface is nearer (the camera's altitude above the highest surfaces)
  float ap_t_far;           // m, distance of the volume's last slice
  bool low_sun;             // the sun may be low (< 10°) somewhere in view: integrate single scattering there
  bool shadows;             // a shadow map is given
  int shadow_steps;
  mat4 shadow_matrix;       // camera-relative metres (world axes) -> the light's clip space
  vec2 shadow_map_size;     // texels
  float shadow_depth_bias;  // in the shadow map's depth units (see make_pass_frame)
};

// Whether the engine drew nothing at this pixel: the depth is the clear
// value of the encoding (the far plane, or infinity).
INLINE bool depth_is_sky(float depth, int encoding) {
  return encoding == DEPTH_REVERSED_Z ? depth <= 0.0f : depth >= 1.0f;
}

// NDC z of the near plane: finite for every perspective projection, finite
// or infinite far plane, reversed or not.
INLINE float near_plane_ndc_z(int encoding) { return encoding == DEPTH_REVERSED_Z ? 1.0f : -1.0f; }

// The view-space point (engine units) of NDC (x, y) and a window depth.
INLINE vec3 view_position_from_depth(IN(PassFrame) frame, vec2 ndc, float depth) {
  if (frame.depth_encoding == DEPTH_LOGARITHMIC) {
    // w, the distance along the view axis, from the depth; the direction
    // from the projection (any finite point of the pixel's ray).
    float w = exp2(depth * frame.log2_depth_far) - 1.0f;
    vec4 p = frame.inverse_projection * vec4(ndc.x, ndc.y, near_plane_ndc_z(DEPTH_STANDARD), 1.0f);
    vec3 q = vec3(p) / p.w;
    return q * (w / max(-q.z, 1e-30f));
  }
  float z = frame.depth_encoding == DEPTH_REVERSED_Z ? depth : 2.0f * depth - 1.0f;
  vec4 p = frame.inverse_projection * vec4(ndc.x, ndc.y, z, 1.0f);
  return vec3(p) / p.w;
}

// The unit view ray through NDC (x, y), in the world's axes.
INLINE vec3 world_view_ray(IN(PassFrame) frame, vec2 ndc) {
  vec4 p = frame.inverse_projection * vec4(ndc.x, ndc.y, near_plane_ndc_z(frame.depth_encoding), 1.0f);
  return normalize(frame.view_to_world * (vec3(p) / p.w));
}

// Linear sRGB transmittance for colours the engine gives in linear sRGB: the
// colour of transmitted sunlight over the colour of sunlight, per sRGB
// channel (in the spectral mode's sRGB channels this is the transmittance
// itself; with three wavelengths it converts their transmittance).
INLINE vec3 srgb_transmittance(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, vec3 transmittance) {
  vec3 sun = frame.radiance_to_srgb * atmosphere.solar_irradiance;
  vec3 transmitted = frame.radiance_to_srgb * (atmosphere.solar_irradiance * transmittance);
  return clamp(transmitted / max(sun, vec3(1e-30f)), vec3(0.0f), vec3(1.0f));
}

// --- The aerial-perspective volume -------------------------------------------

// For a camera in the atmosphere, the light between the camera and a
// surface depends only on the direction and the distance of the surface.
// Every frame fills a volume over directions and distances with it (the idea
// of Hillaire 2020's aerial-perspective LUT, here over world directions
// rather than screen froxels: it needs no projection, serves any number of
// views from the same position, and concentrates texels at the horizon,
// where the light of long grazing paths changes fastest):
//  - x, y: the sky-view table's parameterisation (functions.glsl:
//    sky_view_uv_of_size): azimuth from the sun's vertical plane, and view
//    zenith angle split at the horizon, denser towards it;
//  - z: AP_SLICES distances, quadratic from ap_t_min (no surface is nearer:
//    the camera's height above the highest surfaces) to ap_t_far (the
//    farthest surface the camera can see, see aerial_perspective_reach), so
//    that the slices are short where the nearest surfaces are.
// Pixels interpolate it trilinearly; phase functions are applied per pixel,
// so the aerosol halo stays sharp.
//
// Why not the difference of two 4D lookups for every pixel (seed 001 §4.2,
// scattering_to_point)? It costs ~10 lookups per pixel — which software
// rasterisers, running both sides of every branch, charge to sky pixels
// too — and for a short segment it subtracts two large values: near the
// camera the table's interpolation errors are as large as the segment's own
// light. So the volume integrates each direction's ray once, slice after
// slice (compute_aerial_perspective_column): single scattering and
// transmittance by quadrature along the ray itself (as
// integrate_single_scattering, per wavelength triple, with the planet's
// shadow and the reddened low sun exact), the smooth multiple scattering
// from the difference of two lookups.
#define AP_WIDTH 64
#define AP_HEIGHT 96
#define AP_SLICES 32
// Simpson intervals per slice (the aerosol's 1.2 km scale height over a
// slice of a steep ray needs 4: 0.5 % error where 2 give 6 %).
#define AP_SLICE_INTERVALS 4

INLINE float aerial_perspective_slice_distance(IN(PassFrame) frame, int slice) {
  float x = float(slice + 1) / float(AP_SLICES);
  return frame.ap_t_min + (frame.ap_t_far - frame.ap_t_min) * x * x;
}

// The light between the camera and every slice of one direction of the
// volume (phase-free, tables' channels).
struct AerialPerspectiveColumn {
  vec3 single_rayleigh[AP_SLICES];
  vec3 multiple[AP_SLICES];
  vec3 aerosol[AP_SLICES];
  vec3 transmittance[AP_SLICES];
};

// Column (x, y) of the volume.
INLINE AerialPerspectiveColumn compute_aerial_perspective_column(
    IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral, IN(sampler2D) spectral_transmittance_texture,
    IN(sampler3D) multiple_scattering_texture, IN(PassFrame) frame, int x, int y) {
  vec3 camera = camera_above_ground(atmosphere, frame.camera);
  SkyViewFrame directions = sky_view_frame(atmosphere, camera, frame.sun_direction);
  bool ground;
  vec2 uv = vec2((float(x) + 0.5f) / float(AP_WIDTH), (float(y) + 0.5f) / float(AP_HEIGHT));
  vec3 view_ray = sky_view_direction_of_size(directions, uv, AP_WIDTH, AP_HEIGHT, ground);
  float r = clamp_radius(atmosphere, length(camera));
  float mu = clamp_cosine(dot(camera, view_ray) / r);
  float mu_s = clamp_cosine(dot(camera, frame.sun_direction) / r);
  float nu = clamp_cosine(dot(view_ray, frame.sun_direction));
  ground = ray_intersects_ground(atmosphere, r, mu);
  // The column follows the straight ray through the ground sphere: the
  // surfaces are the engine's (its terrain may rise above or dip below the
  // sphere), and a volume that stopped where each ray meets the sphere
  // would change abruptly between directions near the horizon, where that
  // distance does — which trilinear interpolation turns into errors of
  // percents. Below the sphere the medium is the ground's (clamp_radius).
  // Only the multiple scattering's table lookups stop at the ray's end.
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ground);
  AerialPerspectiveColumn c;
  for (int s = 0; s < AP_SLICES; ++s) {
    c.single_rayleigh[s] = vec3(0.0f);
    c.multiple[s] = vec3(0.0f);
    c.aerosol[s] = vec3(0.0f);
    c.transmittance[s] = vec3(0.0f);
  }
  for (int k = 0; k < spectral.count; ++k) {
    // Running integrals from the camera, at this triple's wavelengths:
    // optical depth (trapezoids between nodes) and single scattering
    // without the solar irradiance (Simpson per slice).
    vec3 optical_depth = vec3(0.0f);
    vec3 rayleigh = vec3(0.0f);
    vec3 aerosol = vec3(0.0f);
    vec3 previous_extinction = extinction_at(spectral.set[k], r);
    float t0 = 0.0f;
    for (int s = 0; s < AP_SLICES; ++s) {
      float t1 = aerial_perspective_slice_distance(frame, s);
      float h = (t1 - t0) / float(AP_SLICE_INTERVALS);
      for (int i = 0; i <= AP_SLICE_INTERVALS; ++i) {
        float t = t0 + float(i) * h;
        float r_t = clamp_radius(spectral.set[k], radius_along_ray(r, mu, t));
        float mu_s_t = clamp_cosine(mu_s_along_ray(r, mu_s, nu, t, r_t));
        vec3 beta_rayleigh;
        vec3 beta_aerosol;
        vec3 extinction;
        medium_at(spectral.set[k], r_t, beta_rayleigh, beta_aerosol, extinction);
        if (i > 0) optical_depth += 0.5f * (previous_extinction + extinction) * h;
        previous_extinction = extinction;
        // With the sun high (frame.low_sun false: above 10° at every point
        // the volume reaches, see sun_may_be_low) the solar disc needs no
        // averaging and no point is in the planet's shadow: one lookup
        // instead of transmittance_to_sun's four (a constant in the shader).
        vec3 to_sun = frame.low_sun
                          ? transmittance_to_sun(spectral.set[k], spectral_transmittance_texture, r_t, mu_s_t)
                          : transmittance_to_top_atmosphere_boundary(spectral.set[k], spectral_transmittance_texture,
                                                                     r_t, mu_s_t);
        vec3 light = simpson_weight(i, AP_SLICE_INTERVALS, h) * exp(-optical_depth) * to_sun;
        rayleigh += light * beta_rayleigh;
        aerosol += light * beta_aerosol;
      }
      t0 = t1;
      vec3 sun = spectral.set[k].solar_irradiance;
      c.single_rayleigh[s] += spectral.to_channels[k] * (sun * rayleigh);
      c.aerosol[s] += spectral.to_channels[k] * (sun * aerosol);
      c.transmittance[s] += spectral.to_channels[k] * (sun * exp(-optical_depth));
    }
  }
  vec3 multiple_0 = scattering_lookup(atmosphere, multiple_scattering_texture, r, mu, mu_s, nu, ground);
  // Beyond the end d of a ray that meets the ground sphere, the column's
  // single scattering and transmittance go on through the ground's medium,
  // but the tables end at d. Frozen at its value at d, the multiple
  // scattering would be cut off there while the rest grows, and the
  // interpolation between the slices around d (or between the camera and
  // the first slice) would lose most of it for surfaces before d (from 2 m,
  // 1° down, 100 m away: 30-80 % of the in-scatter). So it goes on in
  // proportion to the extinction, with the ray's mean ratio above the
  // sphere: M(t) = M(d) (1 - T(0,t)) / (1 - T(0,d)), T(0,d) from the
  // column's optical depth interpolated linearly between the slices around d.
  float t_previous = 0.0f;
  vec3 depth_previous = vec3(0.0f);
  vec3 multiple_d = vec3(0.0f);
  vec3 extinct_d = vec3(0.0f);  // 1 - T(0,d)
  for (int s = 0; s < AP_SLICES; ++s) {
    // Sunlight-weighted, as channel_transmittance.
    c.transmittance[s] = max(c.transmittance[s] / max(atmosphere.solar_irradiance, vec3(1e-30f)), vec3(0.0f));
    float t_s = aerial_perspective_slice_distance(frame, s);
    float t = min(t_s, d);
    float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, t));
    float mu_t = clamp_cosine(mu_along_ray(r, mu, t, r_t));
    float mu_s_t = clamp_cosine(mu_s_along_ray(r, mu_s, nu, t, r_t));
    vec3 multiple_t = scattering_lookup(atmosphere, multiple_scattering_texture, r_t, mu_t, mu_s_t, nu, ground);
    vec3 depth = -log(max(c.transmittance[s], vec3(1e-30f)));
    if (ground && t_s > d) {
      if (t_previous <= d) {  // the first slice beyond d
        vec3 transmittance_d = exp(-mix(depth_previous, depth, (d - t_previous) / (t_s - t_previous)));
        multiple_d = max(multiple_0 - transmittance_d * multiple_t, vec3(0.0f));
        extinct_d = vec3(1.0f) - transmittance_d;
      }
      // (Rays shorter than ~1e-6 of extinction: frozen, nothing to scale.)
      for (int i = 0; i < 3; ++i)
        c.multiple[s][i] = extinct_d[i] > 1e-6f ? multiple_d[i] * (1.0f - c.transmittance[s][i]) / extinct_d[i]
                                                : multiple_d[i];
    } else {
      c.multiple[s] = max(multiple_0 - c.transmittance[s] * multiple_t, vec3(0.0f));
    }
    t_previous = t_s;
    depth_previous = depth;
  }
  return c;
}

// The light between the camera and the point at distance t in the
// direction of texture coordinates uv (sky_view_uv_of_size), from the
// volume's four textures: single Rayleigh + multiple, single Rayleigh alone
// (for the shafts), single aerosol, transmittance. Between two slices the
// interpolation weight is linear in t, not in the slice coordinate: over a
// slice the light grows about linearly with the distance (interpolating in
// sqrt(t) would be 4 % off between the first slices). Between the camera
// (no light, transmittance 1) and the first slice likewise (beyond
// ap_t_min nothing but air without surfaces is there, seen from high up). With `split`,
// single_rayleigh and multiple are apart (one fetch more); without,
// single_rayleigh holds both.
INLINE PathScattering aerial_perspective_lookup(IN(PassFrame) frame, IN(sampler3D) ap_rayleigh,
                                                IN(sampler3D) ap_single_rayleigh, IN(sampler3D) ap_aerosol,
                                                IN(sampler3D) ap_transmittance, vec2 uv, float t, bool split) {
  t = max(t, 0.0f);
  float slice = min(floor(sqrt(max(t - frame.ap_t_min, 0.0f) / (frame.ap_t_far - frame.ap_t_min)) *
                              float(AP_SLICES) -
                          1.0f),
                    float(AP_SLICES - 1));
  float fade = 1.0f;
  float z;
  if (slice < 0.0f) {
    fade = t / aerial_perspective_slice_distance(frame, 0);
    z = 0.5f;
  } else if (slice >= float(AP_SLICES - 1)) {
    z = float(AP_SLICES) - 0.5f;  // beyond the last slice: its value (CLAMP_TO_EDGE)
  } else {
    float t_0 = aerial_perspective_slice_distance(frame, int(slice));
    float t_1 = aerial_perspective_slice_distance(frame, int(slice) + 1);
    z = slice + clamp((t - t_0) / (t_1 - t_0), 0.0f, 1.0f) + 0.5f;
  }
  vec3 uvw = vec3(uv.x, uv.y, z / float(AP_SLICES));
  PathScattering s;
  vec3 rayleigh = fade * vec3(texture(ap_rayleigh, uvw));
  s.single_rayleigh = rayleigh;
  s.multiple = vec3(0.0f);
  if (split) {
    s.single_rayleigh = fade * vec3(texture(ap_single_rayleigh, uvw));
    s.multiple = max(rayleigh - s.single_rayleigh, vec3(0.0f));
  }
  s.aerosol = fade * vec3(texture(ap_aerosol, uvw));
  s.transmittance = mix(vec3(1.0f), vec3(texture(ap_transmittance, uvw)), fade);
  return s;
}

// Texture coordinates of the volume for a view ray from the camera.
INLINE vec2 aerial_perspective_uv(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, vec3 view_ray) {
  vec3 camera = camera_above_ground(atmosphere, frame.camera);
  float r = length(camera);
  bool ground = ray_intersects_ground(atmosphere, r, clamp_cosine(dot(camera, view_ray) / r));
  return sky_view_uv_of_size(sky_view_frame(atmosphere, camera, frame.sun_direction), view_ray, ground, AP_WIDTH,
                             AP_HEIGHT);
}

// --- Terrain shadows and light shafts ---------------------------------------

// The part [t_in, t_out] of the view ray (from the camera, unit `view_ray`,
// up to distance t_max) inside the shadow map's clip cube; false if none.
// The shadow matrix is affine (an orthographic sun), so the ray stays a line
// in the light's clip space: a slab test.
INLINE bool shadow_map_interval(IN(PassFrame) frame, vec3 view_ray, float t_max, OUT(float) t_in, OUT(float) t_out) {
  vec4 a = frame.shadow_matrix * vec4(0.0f, 0.0f, 0.0f, 1.0f);
  vec4 b = frame.shadow_matrix * vec4(view_ray, 0.0f);
  t_in = 0.0f;
  t_out = t_max;
  for (int i = 0; i < 3; ++i) {
    float origin = a[i];
    float slope = b[i];
    if (abs(slope) < 1e-20f) {
      if (origin < -1.0f || origin > 1.0f) return false;
    } else {
      float t0 = (-1.0f - origin) / slope;
      float t1 = (1.0f - origin) / slope;
      t_in = max(t_in, min(t0, t1));
      t_out = min(t_out, max(t0, t1));
    }
  }
  return t_out > t_in;
}

// How much the point at camera-relative `offset` (m) sees the sun past the
// engine's geometry: its depth in the light's clip space compared with the
// shadow map's four nearest texels, the four results weighted bilinearly
// (percentage-closer filtering): a visibility that changes continuously
// across a shadow's edge instead of flipping between 0 and 1, which would
// alias the shafts' samples. A bias in depth (frame.shadow_depth_bias: a
// length in metres converted to the map's depth) keeps lit surfaces from
// shadowing themselves. Outside the map: lit.
INLINE float shadow_visibility(IN(PassFrame) frame, IN(sampler2D) shadow_map, vec3 offset) {
  vec4 p = frame.shadow_matrix * vec4(offset, 1.0f);
  if (abs(p.x) > 1.0f || abs(p.y) > 1.0f || abs(p.z) > 1.0f) return 1.0f;
  float depth = 0.5f * p.z + 0.5f - frame.shadow_depth_bias;
  // Texel coordinates of the point, relative to the centre of the texel
  // below and to the left of it.
  vec2 size = frame.shadow_map_size;
  float x = (0.5f * p.x + 0.5f) * size.x - 0.5f;
  float y = (0.5f * p.y + 0.5f) * size.y - 0.5f;
  float x0 = floor(x);
  float y0 = floor(y);
  float fx = x - x0;
  float fy = y - y0;
  float visible = 0.0f;
  for (int k = 0; k < 4; ++k) {
    float dx = float(k % 2);
    float dy = float(k / 2);
    // The texel's centre: texture() returns exactly its depth there.
    float occluder = texture(shadow_map, vec2((x0 + dx + 0.5f) / size.x, (y0 + dy + 0.5f) / size.y)).x;
    float weight = (dx > 0.5f ? fx : 1.0f - fx) * (dy > 0.5f ? fy : 1.0f - fy);
    visible += depth <= occluder ? weight : 0.0f;
  }
  return visible;
}

// Fractions of the single Rayleigh and aerosol scattering of the view ray's
// first `t_end` metres that come from points the terrain does not shadow.
// The ray is sampled at `steps` points (offset by `dither` in [0, 1) of a
// step, which turns banding into noise); each sample weighs by the
// single-scattering integrand of its constituent — scattering coefficient x
// transmittance from the camera x transmittance to the sun (seed 000
// eq. 3.13) — at the wavelengths of the middle triple, so that the shafts
// follow the haze layer and the reddened, dimmer sunlight low in the
// atmosphere.
INLINE void lit_fractions(IN(SpectralSets) spectral, IN(sampler2D) spectral_transmittance_texture, IN(PassFrame) frame,
                          IN(sampler2D) shadow_map, vec3 view_ray, float t_end, float dither,
                          OUT(float) lit_rayleigh, OUT(float) lit_aerosol) {
  int middle = (spectral.count - 1) / 2;
  float dt = t_end / float(frame.shadow_steps);
  float sum_rayleigh = 0.0f;
  float sum_aerosol = 0.0f;
  float lit_sum_rayleigh = 0.0f;
  float lit_sum_aerosol = 0.0f;
  vec3 optical_depth = vec3(0.0f);
  for (int i = 0; i < frame.shadow_steps; ++i) {
    float t = (float(i) + dither) * dt;
    vec3 offset = view_ray * t;
    vec3 point = frame.camera + offset;
    float r = clamp_radius(spectral.set[middle], length(point));
    float mu_s = clamp_cosine(dot(point, frame.sun_direction) / r);
    vec3 beta_rayleigh;
    vec3 beta_aerosol;
    vec3 extinction;
    medium_at(spectral.set[middle], r, beta_rayleigh, beta_aerosol, extinction);
    vec3 sunlight = exp(-optical_depth) *
                    transmittance_to_top_atmosphere_boundary(spectral.set[middle], spectral_transmittance_texture, r,
                                                             mu_s);
    if (ray_intersects_ground(spectral.set[middle], r, mu_s)) sunlight = vec3(0.0f);
    optical_depth += extinction * dt;
    float visible = shadow_visibility(frame, shadow_map, offset);
    float w_rayleigh = dot(beta_rayleigh, sunlight);
    float w_aerosol = dot(beta_aerosol, sunlight);
    sum_rayleigh += w_rayleigh;
    sum_aerosol += w_aerosol;
    lit_sum_rayleigh += visible * w_rayleigh;
    lit_sum_aerosol += visible * w_aerosol;
  }
  lit_rayleigh = sum_rayleigh > 0.0f ? lit_sum_rayleigh / sum_rayleigh : 1.0f;
  lit_aerosol = sum_aerosol > 0.0f ? lit_sum_aerosol / sum_aerosol : 1.0f;
}

// The light between the camera and the point at distance t along the view
// ray: from the volume (frame.volume), evaluated exactly, or — for cameras
// in the band below the volume's top altitude (frame.volume_weight between
// 0 and 1, see make_pass_frame) — both, mixed, so that the image does not
// jump when a climbing camera switches from one to the other (they differ
// by a few percent for steep rays from high up: the volume's slices are
// long there).
INLINE PathScattering light_to_distance(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                        IN(sampler2D) spectral_transmittance_texture,
                                        IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                        IN(sampler3D) multiple_scattering_texture, IN(sampler3D) ap_rayleigh,
                                        IN(sampler3D) ap_single_rayleigh, IN(sampler3D) ap_aerosol,
                                        IN(sampler3D) ap_transmittance, IN(PassFrame) frame, vec3 view_ray, float t,
                                        bool split) {
  PathScattering volume;
  if (frame.volume) {
    volume = aerial_perspective_lookup(frame, ap_rayleigh, ap_single_rayleigh, ap_aerosol, ap_transmittance,
                                       aerial_perspective_uv(atmosphere, frame, view_ray), t, split);
    if (frame.volume_weight >= 1.0f) return volume;
  }
  vec3 transmittance;
  float nu;
  PathScattering exact = scattering_to_point(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                             single_aerosol_texture, multiple_scattering_texture, frame.camera,
                                             view_ray * t, frame.sun_direction, frame.low_sun, split, transmittance,
                                             nu);
  if (!frame.volume) return exact;
  float w = frame.volume_weight;
  exact.single_rayleigh = mix(exact.single_rayleigh, volume.single_rayleigh, w);
  exact.multiple = mix(exact.multiple, volume.multiple, w);
  exact.aerosol = mix(exact.aerosol, volume.aerosol, w);
  exact.transmittance = mix(exact.transmittance, volume.transmittance, w);
  return exact;
}

// The single scattering (phase-weighted radiance, tables' channels) that the
// terrain's shadows remove from the first `t_max` metres of the view ray
// from the camera (0 without a shadow map or outside it).
INLINE vec3 shadowed_single_scattering(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                       IN(sampler2D) spectral_transmittance_texture,
                                       IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                       IN(sampler3D) multiple_scattering_texture, IN(sampler3D) ap_rayleigh,
                                       IN(sampler3D) ap_single_rayleigh, IN(sampler3D) ap_aerosol,
                                       IN(sampler3D) ap_transmittance, IN(PassFrame) frame,
                                       IN(sampler2D) shadow_map, vec3 view_ray, float t_max, float dither) {
  float t_in;
  float t_out;
  if (!frame.shadows || !shadow_map_interval(frame, view_ray, t_max, t_in, t_out)) return vec3(0.0f);
  float lit_rayleigh;
  float lit_aerosol;
  lit_fractions(spectral, spectral_transmittance_texture, frame, shadow_map, view_ray, t_out, dither, lit_rayleigh,
                lit_aerosol);
  PathScattering s = light_to_distance(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                       single_aerosol_texture, multiple_scattering_texture, ap_rayleigh,
                                       ap_single_rayleigh, ap_aerosol, ap_transmittance, frame, view_ray, t_out, true);
  return phase_weighted_scattering(atmosphere, s.single_rayleigh * (1.0f - lit_rayleigh),
                                   s.aerosol * (1.0f - lit_aerosol),
                                   clamp_cosine(dot(view_ray, frame.sun_direction)));
}

// --- The pixel ---------------------------------------------------------------

// Interleaved gradient noise (Jimenez 2014, "Next generation post processing
// in Call of Duty: Advanced Warfare"): a per-pixel offset in [0, 1) of the
// shaft samples that turns their banding into fine noise. `pixel`: the pixel
// centre (gl_FragCoord.xy).
INLINE float pixel_dither(vec2 pixel) {
  return fract(52.9829189f * fract(dot(pixel, vec2(0.06711056f, 0.00583715f))));
}

// Everything that reaches the camera through one pixel, in linear sRGB
// divided by nits_per_unit (the engine's units):
//  - sky pixels (depth at the clear value): the sky, the planet's sphere
//    below the horizon and the sun disc (radiance_along_view_ray), minus
//    the single scattering the terrain shadows;
//  - surface pixels: the engine's lit colour (or the surface lit here from
//    `albedo` and `normal`, with the shadow map's visibility) times the
//    transmittance to the camera, plus the in-scatter in between minus its
//    shadowed part.
// `ndc`: the pixel centre in NDC; `dither` in [0, 1): the shaft samples'
// offset for this pixel.
INLINE vec3 composite_pixel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                            IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                            IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                            IN(sampler2D) irradiance_texture, IN(sampler2D) sky_view_rayleigh_texture,
                            IN(sampler2D) sky_view_aerosol_texture, bool use_sky_view, IN(sampler3D) ap_rayleigh,
                            IN(sampler3D) ap_single_rayleigh, IN(sampler3D) ap_aerosol,
                            IN(sampler3D) ap_transmittance, IN(PassFrame) frame, IN(sampler2D) shadow_map, vec2 ndc,
                            float depth, vec3 colour, vec3 albedo, vec3 normal, float dither) {
  if (depth_is_sky(depth, frame.depth_encoding)) {
    vec3 view_ray = world_view_ray(frame, ndc);
    vec3 radiance = radiance_along_view_ray(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                            single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                                            sky_view_rayleigh_texture, sky_view_aerosol_texture, use_sky_view,
                                            frame.camera, view_ray, frame.sun_direction, frame.sun_disc);
    if (frame.shadows) {
      // Up to where the ray leaves the atmosphere or meets the ground.
      vec3 start = camera_above_ground(atmosphere, frame.camera);
      float r = length(start);
      float mu = clamp_cosine(dot(start, view_ray) / r);
      float t_max = r <= atmosphere.top_radius
                        ? distance_to_nearest_atmosphere_boundary(atmosphere, r, mu,
                                                                  ray_intersects_ground(atmosphere, r, mu))
                        : 0.0f;
      radiance -= shadowed_single_scattering(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                             single_aerosol_texture, multiple_scattering_texture, ap_rayleigh,
                                             ap_single_rayleigh, ap_aerosol, ap_transmittance, frame, shadow_map,
                                             view_ray, t_max, dither);
    }
    return max(frame.radiance_to_srgb * radiance, vec3(0.0f)) * frame.light_scale;
  }

  vec3 offset = frame.view_to_world * view_position_from_depth(frame, ndc, depth);
  float t = length(offset);
  vec3 view_ray = t > 0.0f ? offset / t : world_view_ray(frame, ndc);
  PathScattering s = light_to_distance(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                       single_aerosol_texture, multiple_scattering_texture, ap_rayleigh,
                                       ap_single_rayleigh, ap_aerosol, ap_transmittance, frame, view_ray, t,
                                       frame.shadows);
  vec3 in_scatter = path_radiance(atmosphere, s, clamp_cosine(dot(view_ray, frame.sun_direction)));
  if (frame.shadows) {
    in_scatter -= shadowed_single_scattering(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                             single_aerosol_texture, multiple_scattering_texture, ap_rayleigh,
                                             ap_single_rayleigh, ap_aerosol, ap_transmittance, frame, shadow_map,
                                             view_ray, t, dither);
  }
  vec3 surface = colour;
  if (frame.surface_mode == SURFACE_GBUFFER) {
    // Lambertian under the sun (shadowed by the engine's geometry) and the
    // sky, from the tables at the surface point (seed 000 §4.3.3).
    vec3 point = frame.camera + offset;
    float r = length(point);
    vec3 up = point / r;
    vec3 n = dot(normal, normal) > 0.0f ? normalize(normal) : up;
    vec3 sky_irradiance;
    vec3 sun_irradiance = sun_and_sky_irradiance_at(atmosphere, spectral, spectral_transmittance_texture,
                                                    irradiance_texture, r, up, n, frame.sun_direction,
                                                    sky_irradiance);
    if (frame.shadows) sun_irradiance *= shadow_visibility(frame, shadow_map, offset);
    surface = albedo * (1.0f / PI) * (frame.radiance_to_srgb * (sun_irradiance + sky_irradiance)) * frame.light_scale;
  }
  return surface * srgb_transmittance(atmosphere, frame, s.transmittance) +
         max(frame.radiance_to_srgb * in_scatter, vec3(0.0f)) * frame.light_scale;
}
