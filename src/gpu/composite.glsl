// atmos — the engine plugin's per-pixel work (AtmospherePass): from the
// engine's depth and colour at a pixel to the composited radiance.
//
// Shared by the pass's fragment shader (atmosphere_pass.frag.glsl) and
// volume (aerial_perspective.comp.glsl), after radiance_to_camera.glsl,
// aerial_perspective.glsl and the parts of the physics they need, and by its
// CPU twin (gpu/composite_cpp.hpp, for the tests), in the GLSL / C++ subset
// of physics/definitions.glsl.
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

// The per-frame inputs of the pass. On the GPU, surface_mode, low_sun,
// shadows, stars.enabled and whether there are moons are constants of the
// program variant (software rasterisers run both sides of every branch: a
// uniform would make every pixel pay for the shadow march, the G-buffer
// lighting, the twilight integration, the stars and the eclipse), the rest
// are uniforms.
struct PassFrame {
  vec3 camera;              // m, relative to the planet centre
  vec3 sun_direction;       // unit, towards the sun
  mat4 inverse_projection;  // NDC -> engine view space
  mat3 view_to_world;       // engine view space -> world axes, engine units -> metres
  vec4 depth_column;        // view_to_world * inverse_projection[2].xyz, inverse_projection[2].w (see PixelRay)
  float depth_column_view_z;  // inverse_projection[2].z
  int depth_encoding;       // DEPTH_*
  float log2_depth_far;     // DEPTH_LOGARITHMIC: log2(1 + F)
  int surface_mode;         // SURFACE_*
  mat3 radiance_to_srgb;    // tables' channels -> linear sRGB, cd/m²
  vec3 inverse_sun_srgb;    // 1 / (radiance_to_srgb * solar irradiance), per sRGB channel
  SkyViewFrame sky_view;    // directions of the sky-view table and of the volume (camera clamped above the ground)
  float light_scale;        // (sun illuminance / the atmosphere's own) / nits_per_unit
  bool sun_disc;
  StarField stars;          // enabled: a constant of the program variant on the GPU
  bool volume;              // surfaces read the aerial-perspective volume (cameras low in the atmosphere)
  float volume_weight;      // 1: the volume alone; below 1, mixed with the exact evaluation (a constant 1 or not)
  float ap_t_min;           // m, no surface is nearer (the camera's altitude above the highest surfaces)
  float ap_t_far;           // m, distance of the volume's last slice
  bool space_volume;        // surfaces read the volume of cameras above the atmosphere (see space_volume_lookup)
  mat4 world_to_clip;       // a direction in the world's axes -> the engine's clip space (projection x rotation)
  float surface_shell_radius;  // m, planet-centred: no surface is higher (see aerial_perspective_reach)
  bool low_sun;             // the sun may be low (< 10°) somewhere in view: integrate single scattering there
                            // (surfaces, and from above the atmosphere the sky's rays through it)
  bool night;               // surfaces whose segment lies in the planet's shadow (pixel_low_sun_classes):
                            // no single scattering, without integrating it (a constant of the variant)
  bool shadows;             // a shadow map is given
  int shadow_steps;
  mat4 shadow_matrix;       // camera-relative metres (world axes) -> the light's clip space
  float shadow_depth_bias;  // in the shadow map's depth units (see make_pass_frame)
  // The frame's moons (eclipse.glsl), planet-centred like the camera. On the
  // GPU no_moons() (a constant: the code of an eclipse folds away) or, in
  // the eclipse variant, the uniforms of table_bindings.glsl (uniform_moons).
  // With moons, low_sun is true and sky_view.full_azimuth too.
  Moons moons;
};

// Whether the engine drew nothing at this pixel: the depth is the clear
// value of the encoding (the far plane, or infinity).
INLINE bool depth_is_sky(float depth, int encoding) {
  return encoding == DEPTH_REVERSED_Z ? depth <= 0.0f : depth >= 1.0f;
}

// NDC z of the near plane: finite for every perspective projection, finite
// or infinite far plane, reversed or not.
INLINE float near_plane_ndc_z(int encoding) { return encoding == DEPTH_REVERSED_Z ? 1.0f : -1.0f; }

// The point of the pixel at window depth `depth`, relative to the camera in
// the world's axes, in metres.
INLINE vec3 world_offset_from_depth(IN(PassFrame) frame, IN(PixelRay) ray, float depth) {
  if (frame.depth_encoding == DEPTH_LOGARITHMIC) {
    // w, the distance along the view axis, from the depth; the direction
    // from the projection (the near plane's point of the pixel's ray).
    float w = exp2(depth * frame.log2_depth_far) - 1.0f;
    float z_near = near_plane_ndc_z(DEPTH_STANDARD);
    vec4 q = ray.world + z_near * frame.depth_column;
    float view_z = (ray.view_z + z_near * frame.depth_column_view_z) / q.w;
    return vec3(q) / q.w * (w / max(-view_z, 1e-30f));
  }
  float z = frame.depth_encoding == DEPTH_REVERSED_Z ? depth : 2.0f * depth - 1.0f;
  vec4 p = ray.world + z * frame.depth_column;
  return vec3(p) / p.w;
}

// The pixel's unit view ray, in the world's axes.
INLINE vec3 world_view_ray(IN(PassFrame) frame, IN(PixelRay) ray) {
  vec4 p = ray.world + near_plane_ndc_z(frame.depth_encoding) * frame.depth_column;
  return normalize(vec3(p) / p.w);
}

// Linear sRGB transmittance for colours the engine gives in linear sRGB: the
// colour of transmitted sunlight over the colour of sunlight, per sRGB
// channel (in the spectral mode's sRGB channels this is the transmittance
// itself; with three wavelengths it converts their transmittance).
INLINE vec3 srgb_transmittance(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, vec3 transmittance) {
  vec3 transmitted = frame.radiance_to_srgb * (atmosphere.solar_irradiance * transmittance);
  return clamp(transmitted * frame.inverse_sun_srgb, vec3(0.0f), vec3(1.0f));
}

// --- The aerial-perspective volume -------------------------------------------

// For a camera in the atmosphere, the light between the camera and a
// surface depends only on the direction and the distance of the surface.
// Every frame fills a volume over directions and distances with it (the idea
// of Hillaire 2020's aerial-perspective LUT, here over world directions
// rather than screen froxels: it needs no projection, serves any number of
// views from the same position, and concentrates texels at the horizon,
// where the light of long grazing paths changes fastest):
//  - x, y: the sky-view table's parameterisation (sky_view_table.glsl:
//    sky_view_uv_of_size): azimuth from the sun's vertical plane, and view
//    zenith angle split at the horizon, denser towards it;
//  - z: AP_SLICES distances, quadratic from ap_t_min (no surface is nearer:
//    the camera's height above the highest surfaces) to ap_t_far (the
//    farthest surface the camera can see, see aerial_perspective_reach), so
//    that the slices are short where the nearest surfaces are.
// Pixels interpolate it trilinearly; phase functions are applied per pixel,
// so the aerosol halo stays sharp.
//
// Why not the difference of two 4D lookups for every pixel (Schafhitzel,
// Falk & Ertl 2007, §4.2; scattering_to_point)? It costs ~10 lookups per pixel — which software
// rasterisers, running both sides of every branch, charge to sky pixels
// too — and for a short segment it subtracts two large values: near the
// camera the table's interpolation errors are as large as the segment's own
// light. So the volume integrates each direction's ray once, slice after
// slice (aerial_perspective_march_slice): single scattering and
// transmittance by quadrature along the ray itself (as
// integrate_single_scattering, per wavelength triple, with the planet's
// shadow and the reddened low sun exact), the smooth multiple scattering
// from the difference of two lookups (aerial_perspective_march_slice).
#define AP_WIDTH 64
#define AP_HEIGHT 96
#define AP_SLICES 32
// Quadrature intervals per slice (exponential_segment_integral).
#ifndef AP_SLICE_INTERVALS
#define AP_SLICE_INTERVALS 2
#endif
// Slices per evaluation of the diffuse visibility under an eclipse
// (aerial_perspective_march_slice); divides AP_SLICES.
#define AP_DIFFUSE_GROUP 2

INLINE float aerial_perspective_slice_distance(IN(PassFrame) frame, int slice) {
  float x = float(slice + 1) / float(AP_SLICES);
  return frame.ap_t_min + (frame.ap_t_far - frame.ap_t_min) * x * x;
}

// The light between the camera and a slice of one direction of the volume
// (phase-free, tables' channels).
struct AerialPerspectiveSlice {
  vec3 single_rayleigh;
  vec3 multiple;
  vec3 aerosol;
  vec3 transmittance;
};

// The march along one direction of the volume, slice after slice:
// aerial_perspective_march_begin, then aerial_perspective_march_slice for
// slices 0, 1, ... in order. The state is small (the running integrals), so
// that the compute shader stores each slice as it goes instead of holding a
// whole column.
struct AerialPerspectiveMarch {
  // The ray: camera at radius r (clamped above the ground), view and sun
  // cosines, whether it meets the ground sphere and where (d).
  float r;
  float mu;
  float mu_s;
  float nu;
  bool ground;
  float d;
  float t;  // distance of the last node
  // The ray in space (planet-centred start, unit direction): where the
  // moons' shadows fall (eclipse.glsl; unused without moons).
  vec3 origin;
  vec3 view_ray;
  // Per wavelength triple, at the last node: optical depth from the camera,
  // extinction, and the single-scattering integrands (scattering
  // coefficient x transmittance to the sun x transmittance from the camera,
  // Collienne 2013, eq. 3.13, without the solar irradiance).
  vec3 optical_depth[SPECTRAL_SET_CAPACITY];
  vec3 extinction[SPECTRAL_SET_CAPACITY];
  vec3 rayleigh_integrand[SPECTRAL_SET_CAPACITY];
  vec3 aerosol_integrand[SPECTRAL_SET_CAPACITY];
  // The single scattering from the camera to the last node, tables' channels.
  vec3 single_rayleigh;
  vec3 aerosol;
  // The multiple scattering (see aerial_perspective_march_slice).
  vec3 multiple_0;
  float t_previous;
  vec3 depth_previous;
  vec3 multiple_d;
  vec3 extinct_d;
  // Eclipses (see aerial_perspective_march_slice; unused without moons):
  // the diffuse visibility at the start and the end of the current group of
  // slices and their distances, the sums of the slices' diffuse visibility
  // so far weighted by the light each sends towards the camera and of those
  // weights, and the sum of the transmittance's channels at the last slice.
  float diffuse_start;
  float diffuse_end;
  float diffuse_t_start;
  float diffuse_t_end;
  float diffuse_sum;
  float diffuse_weight;
  float transmittance_previous;
};

// The medium of one wavelength triple at distance t along the march's ray:
// extinction, and the scattering coefficients times the transmittance to the
// sun. With the sun high (frame.low_sun false: above 10° at every point the
// volume reaches, see sun_may_be_low) the solar disc needs no averaging and
// no point is in the planet's shadow: one lookup instead of
// transmittance_to_sun's four (a constant in the shader). `sunlight`: the
// fraction of the sun the moons leave the node (sunlight_visible_fraction;
// 1 without moons).
INLINE void aerial_perspective_node(IN(AtmosphereParams) set, IN(sampler2D) spectral_transmittance_texture,
                                    IN(PassFrame) frame, IN(AerialPerspectiveMarch) m, float t, float sunlight,
                                    OUT(vec3) extinction, OUT(vec3) rayleigh_sunlit, OUT(vec3) aerosol_sunlit) {
  float r_t = clamp_radius(set, radius_along_ray(m.r, m.mu, t));
  float mu_s_t = clamp_cosine(mu_s_along_ray(m.r, m.mu_s, m.nu, t, r_t));
  vec3 beta_rayleigh;
  vec3 beta_aerosol;
  medium_at(set, r_t, beta_rayleigh, beta_aerosol, extinction);
  // Sunlight through the delta-M scaled medium, as in the single scattering
  // tables (single_scattering_tile; the view path keeps the true extinction:
  // the volume's segments are short).
  AtmosphereParams scaled = with_scaled_transmittance(set);
  vec3 to_sun = frame.low_sun ? transmittance_to_sun(scaled, spectral_transmittance_texture, r_t, mu_s_t)
                              : transmittance_to_top_atmosphere_boundary(scaled, spectral_transmittance_texture, r_t,
                                                                         mu_s_t);
  to_sun *= sunlight;
  rayleigh_sunlit = beta_rayleigh * to_sun;
  aerosol_sunlit = beta_aerosol * to_sun;
}

// The march of direction (x, y) of the volume, at its camera.
INLINE AerialPerspectiveMarch aerial_perspective_march_begin(IN(AtmosphereParams) atmosphere,
                                                             IN(SpectralSets) spectral,
                                                             IN(sampler2D) spectral_transmittance_texture,
                                                             IN(sampler3D) multiple_scattering_texture,
                                                             IN(PassFrame) frame, int x, int y) {
  AerialPerspectiveMarch m;
  vec3 camera = camera_above_ground(atmosphere, frame.camera);
  vec2 uv = vec2((float(x) + 0.5f) / float(AP_WIDTH), (float(y) + 0.5f) / float(AP_HEIGHT));
  vec3 view_ray = sky_view_direction_of_size(frame.sky_view, uv, AP_WIDTH, AP_HEIGHT, m.ground);
  m.r = clamp_radius(atmosphere, length(camera));
  m.mu = clamp_cosine(dot(camera, view_ray) / m.r);
  m.mu_s = clamp_cosine(dot(camera, frame.sun_direction) / m.r);
  m.nu = clamp_cosine(dot(view_ray, frame.sun_direction));
  m.ground = ray_intersects_ground(atmosphere, m.r, m.mu);
  // The march follows the straight ray through the ground sphere: the
  // surfaces are the engine's (its terrain may rise above or dip below the
  // sphere), and a volume that stopped where each ray meets the sphere
  // would change abruptly between directions near the horizon, where that
  // distance does — which trilinear interpolation turns into errors of
  // percents. Below the sphere the medium is the ground's (clamp_radius).
  // Only the multiple scattering's table lookups stop at the ray's end.
  m.d = distance_to_nearest_atmosphere_boundary(atmosphere, m.r, m.mu, m.ground);
  m.t = 0.0f;
  m.origin = camera;
  m.view_ray = view_ray;
  float sunlight = 1.0f;
  if (frame.moons.count > 0)
    sunlight = sunlight_visible_fraction(frame.moons, atmosphere.sun_angular_radius, camera, frame.sun_direction);
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    m.optical_depth[k] = vec3(0.0f);
    aerial_perspective_node(spectral.set[k], spectral_transmittance_texture, frame, m, 0.0f, sunlight,
                            m.extinction[k], m.rayleigh_integrand[k], m.aerosol_integrand[k]);
  }
  m.single_rayleigh = vec3(0.0f);
  m.aerosol = vec3(0.0f);
  m.multiple_0 = ray_scattering_lookup(atmosphere, multiple_scattering_texture, m.r, m.mu, m.mu_s, m.nu, m.ground);
  m.t_previous = 0.0f;
  m.depth_previous = vec3(0.0f);
  m.multiple_d = vec3(0.0f);
  m.extinct_d = vec3(0.0f);
  m.diffuse_start = 1.0f;
  m.diffuse_end = 1.0f;
  m.diffuse_t_start = 0.0f;
  m.diffuse_t_end = 0.0f;
  // The medium of the first wavelength triple (the render parameters of the
  // spectral mode have none: see make_render_params).
  if (frame.moons.count > 0) {
    m.diffuse_end = diffuse_light_visible_fraction(spectral.set[0], spectral_transmittance_texture, frame.moons,
                                                   camera, frame.sun_direction);
  }
  m.diffuse_sum = 0.0f;
  m.diffuse_weight = 0.0f;
  m.transmittance_previous = 3.0f;
  return m;
}

// Advances the march to the end of slice s (the next one) and returns the
// light between the camera and it: single scattering and transmittance by
// quadrature along the ray itself at every wavelength triple (as
// integrate_single_scattering: the planet's shadow and the reddened low sun
// exact), AP_SLICE_INTERVALS intervals per slice, each integrated as an
// exponential (exponential_segment_integral: the slices grow quadratically
// with the distance, to kilometres, which a trapezoid or Simpson's rule
// would need several nodes per slice to follow through the aerosol layer);
// the smooth multiple scattering from the difference of two lookups.
// Eclipses (frame.moons): each node gets the fraction of the sun the moons
// leave it (sunlight_visible_fraction), and the multiple scattering up to
// the slice is dimmed by the mean of diffuse_light_visible_fraction along
// the ray so far, weighted by the light each slice sends towards the camera
// (the drop of the transmittance over it), as ray_diffuse_visibility does
// for whole rays — the documented approximation of ray_integration.glsl
// (diffuse_light_visible_fraction). That
// fraction changes over tens of kilometres (its rings start 8 km out) and
// costs ~30 overlaps: it is evaluated at the camera and at the ends of
// groups of AP_DIFFUSE_GROUP slices (17 points per ray, where
// ray_diffuse_visibility has 2) and interpolated linearly in distance to
// each slice's middle. Against one evaluation per slice (a camera 300 m up
// in totality, G-buffer surfaces, 1920x1080), the image is within 0.9 %
// (mean 0.2 %) of it for 0.6 of the volume's time; groups of 4 give 3.8 %
// (0.5 %) for 0.4. The slices' distances are the same in every direction,
// so the groups are too (no divergence).
INLINE AerialPerspectiveSlice aerial_perspective_march_slice(IN(AtmosphereParams) atmosphere,
                                                             IN(SpectralSets) spectral,
                                                             IN(sampler2D) spectral_transmittance_texture,
                                                             IN(sampler3D) multiple_scattering_texture,
                                                             IN(PassFrame) frame, INOUT(AerialPerspectiveMarch) m,
                                                             int s) {
  float t_s = aerial_perspective_slice_distance(frame, s);
  float t_start = m.t;
  float h = (t_s - m.t) / float(AP_SLICE_INTERVALS);
  AerialPerspectiveSlice slice;
  slice.transmittance = vec3(0.0f);
  for (int k = 0; k < SPECTRAL_COUNT(spectral); ++k) {
    vec3 rayleigh = vec3(0.0f);
    vec3 aerosol = vec3(0.0f);
    for (int i = 1; i <= AP_SLICE_INTERVALS; ++i) {
      vec3 extinction;
      vec3 rayleigh_sunlit;
      vec3 aerosol_sunlit;
      float sunlight = 1.0f;
      if (frame.moons.count > 0) {
        sunlight = sunlight_visible_fraction(frame.moons, atmosphere.sun_angular_radius,
                                             m.origin + m.view_ray * (m.t + float(i) * h), frame.sun_direction);
      }
      aerial_perspective_node(spectral.set[k], spectral_transmittance_texture, frame, m, m.t + float(i) * h,
                              sunlight, extinction, rayleigh_sunlit, aerosol_sunlit);
      m.optical_depth[k] += exponential_segment_integral(m.extinction[k], extinction, h);
      m.extinction[k] = extinction;
      vec3 transmittance = exp(-m.optical_depth[k]);
      vec3 rayleigh_integrand = rayleigh_sunlit * transmittance;
      vec3 aerosol_integrand = aerosol_sunlit * transmittance;
      rayleigh += exponential_segment_integral(m.rayleigh_integrand[k], rayleigh_integrand, h);
      aerosol += exponential_segment_integral(m.aerosol_integrand[k], aerosol_integrand, h);
      m.rayleigh_integrand[k] = rayleigh_integrand;
      m.aerosol_integrand[k] = aerosol_integrand;
    }
    vec3 sun = spectral.set[k].solar_irradiance;
    m.single_rayleigh += spectral.to_channels[k] * (sun * rayleigh);
    // Weighted by the triple's aerosol phase function and divided by the
    // channels' below, as spectral_single_scattering (exact when the phase
    // function changes with wavelength inside a channel).
    m.aerosol += spectral.to_channels[k] * (sun * aerosol * aerosol_phase_function(spectral.set[k], m.nu));
    slice.transmittance += spectral.to_channels[k] * (sun * exp(-m.optical_depth[k]));
  }
  m.t = t_s;
  slice.single_rayleigh = m.single_rayleigh;
  slice.aerosol = m.aerosol / aerosol_phase_function(atmosphere, m.nu);
  // Sunlight-weighted, as channel_transmittance.
  slice.transmittance = max(slice.transmittance / max(atmosphere.solar_irradiance, vec3(1e-30f)), vec3(0.0f));

  // Multiple scattering: M(0) - T(0, t) M(t), the two lookups in the ray's
  // half of the table. Beyond the end d of a ray that meets the ground
  // sphere, the single scattering and transmittance go on through the
  // ground's medium, but the tables end at d. Frozen at its value at d, the
  // multiple scattering would be cut off there while the rest grows, and the
  // interpolation between the slices around d (or between the camera and
  // the first slice) would lose most of it for surfaces before d (from 2 m,
  // 1° down, 100 m away: 30-80 % of the in-scatter). So it goes on in
  // proportion to the extinction, with the ray's mean ratio above the
  // sphere: M(t) = M(d) (1 - T(0,t)) / (1 - T(0,d)), T(0,d) from the
  // optical depth interpolated linearly between the slices around d.
  float t = min(t_s, m.d);
  float r_t = clamp_radius(atmosphere, radius_along_ray(m.r, m.mu, t));
  float mu_t = clamp_cosine(mu_along_ray(m.r, m.mu, t, r_t));
  float mu_s_t = clamp_cosine(mu_s_along_ray(m.r, m.mu_s, m.nu, t, r_t));
  vec3 multiple_t = ray_scattering_lookup(atmosphere, multiple_scattering_texture, r_t, mu_t, mu_s_t, m.nu, m.ground);
  vec3 depth = -log(max(slice.transmittance, vec3(1e-30f)));
  if (m.ground && t_s > m.d) {
    if (m.t_previous <= m.d) {  // the first slice beyond d
      vec3 transmittance_d =
          exp(-mix(m.depth_previous, depth, (m.d - m.t_previous) / (t_s - m.t_previous)));
      m.multiple_d = max(m.multiple_0 - transmittance_d * multiple_t, vec3(0.0f));
      m.extinct_d = vec3(1.0f) - transmittance_d;
    }
    // (Rays shorter than ~1e-6 of extinction: frozen, nothing to scale.)
    for (int i = 0; i < 3; ++i)
      slice.multiple[i] = m.extinct_d[i] > 1e-6f
                              ? m.multiple_d[i] * (1.0f - slice.transmittance[i]) / m.extinct_d[i]
                              : m.multiple_d[i];
  } else {
    slice.multiple = max(m.multiple_0 - slice.transmittance * multiple_t, vec3(0.0f));
  }
  if (frame.moons.count > 0) {
    float transmittance_sum = slice.transmittance.x + slice.transmittance.y + slice.transmittance.z;
    float sent = max(m.transmittance_previous - transmittance_sum, 0.0f);
    m.transmittance_previous = transmittance_sum;
    if (s % AP_DIFFUSE_GROUP == 0) {
      m.diffuse_start = m.diffuse_end;
      m.diffuse_t_start = m.diffuse_t_end;
      m.diffuse_t_end = aerial_perspective_slice_distance(frame, s + AP_DIFFUSE_GROUP - 1);
      m.diffuse_end = diffuse_light_visible_fraction(spectral.set[0], spectral_transmittance_texture, frame.moons,
                                                     m.origin + m.view_ray * m.diffuse_t_end, frame.sun_direction);
    }
    float x = (0.5f * (t_start + t_s) - m.diffuse_t_start) / max(m.diffuse_t_end - m.diffuse_t_start, 1e-6f);
    float visible = mix(m.diffuse_start, m.diffuse_end, clamp(x, 0.0f, 1.0f));
    m.diffuse_sum += sent * visible;
    m.diffuse_weight += sent;
    slice.multiple *= m.diffuse_weight > 0.0f ? m.diffuse_sum / m.diffuse_weight : visible;
  }
  m.t_previous = t_s;
  m.depth_previous = depth;
  return slice;
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
  return sky_view_uv_of_size(frame.sky_view, view_ray, ground, AP_WIDTH, AP_HEIGHT);
}

// --- The volume of cameras above the atmosphere ------------------------------

// Seen from above the atmosphere every surface lies in the shell between the
// ground sphere and surface_shell_radius, so the light between the camera
// and a surface depends on the pixel's direction and on where in that shell
// its ray ends. Each frame fills a volume with it:
//  - x, y: the image's directions, texel centres at the NDC (2 x + 1) /
//    SPACE_VOLUME_WIDTH - 1 (resp. height): a pixel's direction is
//    interpolated between the four nearest (world_to_clip projects a view
//    ray back to its NDC);
//  - z: SPACE_VOLUME_SLICES distances along the ray from t_0, where it
//    enters the shell, to t_1, where it meets the ground sphere or, if it
//    misses it, its point nearest to the planet (space_volume_span; the two
//    points meet at the limb, so t_1 is continuous across it), quadratic
//    towards t_1, t = t_1 - (t_1 - t_0) (1 - z)², z = k / (SLICES - 1):
//    the slices are densest where the air is (a vertical ray's 25 km in 15
//    intervals, the last 110 m long, the one at 2 km about 0.9 km). A
//    surface beyond t_1 on a ray that misses the ground sphere (a mountain
//    behind the limb, past the ray's lowest point) reads the light to t_1.
// Each texel holds the exact light to its point, from the function the
// pixels would evaluate (eclipsed_scattering_to_point), so the volume's
// only error is the interpolation between texels, and each pixel pays three
// texture reads instead of the table differences (eight reads of the 4D
// tables). Between two slices the weight is linear in t, as
// aerial_perspective_lookup's. Where the light changes faster than the
// texels (about 0.8° apart with a 60° field of view) the interpolation
// would blur it: across the limb (rays that meet the ground sphere and rays
// that miss it, whose table half and horizon fix differ), near it (the air
// mass grows as 1 / cos of the ground's zenith angle, which seen from afar
// changes by degrees from one texel to the next) and in the low-sun band
// (the terminator's twilight, hundreds of kilometres wide, is a few texels
// seen from afar). So only the surfaces whose four nearest columns are all
// regular (gpu/pass_frame.cpp: space_volume_columns: their rays meet the
// ground sphere less than 75.5° from the zenith with an air mass within 10
// % of their neighbours', and need no low-sun integration) read the volume
// (space_volume_covers: the CPU marks the columns in a texture, 1 or 0,
// whose bilinear value is 1 only if the four are); the others are evaluated
// exactly, per pixel, and only the regular columns are computed. Frames
// with moons or a shadow map do without it (gpu::uses_space_volume).
#define SPACE_VOLUME_WIDTH 128
#define SPACE_VOLUME_HEIGHT 72
#define SPACE_VOLUME_SLICES 16

// The part [t_0, t_1] (distances from the camera) of a view ray from a
// camera above the atmosphere where it may meet a surface; t_0 = t_1 = 0
// for a ray that misses the atmosphere. Discriminants written without
// cancellation, as distance_to_top_atmosphere_boundary's.
INLINE void space_volume_span(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, vec3 view_ray, OUT(float) t_0,
                              OUT(float) t_1) {
  t_0 = 0.0f;
  t_1 = 0.0f;
  vec3 start = frame.camera;
  if (!enter_atmosphere(atmosphere, start, view_ray)) return;
  float entry = length(start - frame.camera);
  float r = length(start);
  float mu = clamp_cosine(dot(start, view_ray) / r);
  float nearest = max(-r * mu, 0.0f);
  float to_end = ray_intersects_ground(atmosphere, r, mu) ? distance_to_bottom_atmosphere_boundary(atmosphere, r, mu)
                                                          : nearest;
  float shell = frame.surface_shell_radius;
  float discriminant = (r * mu) * (r * mu) - (r - shell) * (r + shell);
  float to_shell = discriminant >= 0.0f ? max(-r * mu - sqrt(discriminant), 0.0f) : nearest;
  t_0 = entry + min(to_shell, to_end);
  t_1 = entry + to_end;
}

INLINE float space_volume_slice_distance(float t_0, float t_1, int slice) {
  float x = 1.0f - float(slice) / float(SPACE_VOLUME_SLICES - 1);
  return t_1 - (t_1 - t_0) * x * x;
}

// The view ray of texel column (x, y) of the space volume.
INLINE vec3 space_volume_view_ray(IN(PassFrame) frame, int x, int y) {
  vec2 ndc = vec2((2.0f * float(x) + 1.0f) / float(SPACE_VOLUME_WIDTH) - 1.0f,
                  (2.0f * float(y) + 1.0f) / float(SPACE_VOLUME_HEIGHT) - 1.0f);
  return world_view_ray(frame, pixel_ray(frame.inverse_projection, frame.view_to_world, ndc));
}

// Whether any texel of a column needs the low-sun integration (frame.low_sun
// without moons): the weight of its whole segment, up to t_1, is above zero
// (the sun is lowest at an end of a segment, see low_sun_weight, and every
// texel's segment is a part of this one, from the same start). The others
// give the same light without it.
INLINE bool space_volume_column_needs_low_sun(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, vec3 view_ray) {
  if (frame.moons.count > 0) return true;
  float t_0;
  float t_1;
  space_volume_span(atmosphere, frame, view_ray, t_0, t_1);
  AtmosphereSegment segment;
  if (!atmosphere_segment(atmosphere, frame.camera, view_ray, t_1, frame.sun_direction, segment)) return false;
  return segment_low_sun_weight(segment, clamp_cosine(dot(view_ray, frame.sun_direction))) > 0.0f;
}

// The texel of slice `slice` of the column of `view_ray`: the light to its
// point as light_to_distance evaluates it exactly (`low_sun`: the frame's,
// or false where the column does not need it). Without `split` (a frame
// without shadows) single_rayleigh holds the multiple scattering too.
INLINE PathScattering space_volume_texel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                         IN(sampler2D) spectral_transmittance_texture,
                                         IN(sampler3D) scattering_texture, IN(sampler3D) single_aerosol_texture,
                                         IN(sampler3D) multiple_scattering_texture, IN(PassFrame) frame,
                                         vec3 view_ray, int slice, bool low_sun, bool split) {
  float t_0;
  float t_1;
  space_volume_span(atmosphere, frame, view_ray, t_0, t_1);
  float t = space_volume_slice_distance(t_0, t_1, slice);
  vec3 transmittance;
  float nu;
  return eclipsed_scattering_to_point(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                      single_aerosol_texture, multiple_scattering_texture, frame.camera,
                                      view_ray * t, frame.sun_direction, low_sun, split, frame.moons, transmittance,
                                      nu);
}

// Whether the pixel's surface reads the space volume: its four nearest
// columns are regular (`regular_columns`: 1 or 0 per column, see above).
INLINE bool space_volume_covers(IN(PassFrame) frame, IN(sampler2D) regular_columns, IN(PixelRay) ray) {
  vec4 clip = frame.world_to_clip * vec4(world_view_ray(frame, ray), 0.0f);
  vec2 uv = 0.5f * vec2(clip.x, clip.y) / clip.w + 0.5f;
  return texture(regular_columns, uv).x >= 0.9999f;
}

// The light between the camera and the point at distance t along the view
// ray, from the space volume's four textures (as aerial_perspective_lookup:
// single Rayleigh + multiple, single Rayleigh alone, single aerosol,
// transmittance).
INLINE PathScattering space_volume_lookup(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame,
                                          IN(sampler3D) ap_rayleigh, IN(sampler3D) ap_single_rayleigh,
                                          IN(sampler3D) ap_aerosol, IN(sampler3D) ap_transmittance, vec3 view_ray,
                                          float t, bool split) {
  vec4 clip = frame.world_to_clip * vec4(view_ray, 0.0f);
  vec2 uv = 0.5f * vec2(clip.x, clip.y) / clip.w + 0.5f;
  float t_0;
  float t_1;
  space_volume_span(atmosphere, frame, view_ray, t_0, t_1);
  float z = float(SPACE_VOLUME_SLICES - 1);
  if (t_1 > t_0) {
    float x = clamp((t_1 - t) / (t_1 - t_0), 0.0f, 1.0f);
    float slice = min(floor((1.0f - sqrt(x)) * float(SPACE_VOLUME_SLICES - 1)), float(SPACE_VOLUME_SLICES - 2));
    float t_a = space_volume_slice_distance(t_0, t_1, int(slice));
    float t_b = space_volume_slice_distance(t_0, t_1, int(slice) + 1);
    z = slice + clamp((t - t_a) / max(t_b - t_a, 1e-30f), 0.0f, 1.0f);
  }
  vec3 uvw = vec3(uv.x, uv.y, (z + 0.5f) / float(SPACE_VOLUME_SLICES));
  PathScattering s;
  vec3 rayleigh = vec3(texture(ap_rayleigh, uvw));
  s.single_rayleigh = rayleigh;
  s.multiple = vec3(0.0f);
  if (split) {
    s.single_rayleigh = vec3(texture(ap_single_rayleigh, uvw));
    s.multiple = max(rayleigh - s.single_rayleigh, vec3(0.0f));
  }
  s.aerosol = vec3(texture(ap_aerosol, uvw));
  s.transmittance = vec3(texture(ap_transmittance, uvw));
  return s;
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
// (percentage-closer filtering, by the texture unit: a sampler2DShadow with
// linear filtering, one fetch): a visibility that changes continuously
// across a shadow's edge instead of flipping between 0 and 1, which would
// alias the shafts' samples. A bias in depth (frame.shadow_depth_bias: a
// length in metres converted to the map's depth) keeps lit surfaces from
// shadowing themselves. Outside the map: lit. `p`: the point in the light's
// clip space.
INLINE float shadow_visibility_at(IN(PassFrame) frame, IN(sampler2DShadow) shadow_map, vec4 p) {
  if (abs(p.x) > 1.0f || abs(p.y) > 1.0f || abs(p.z) > 1.0f) return 1.0f;
  return texture(shadow_map, vec3(0.5f * p.x + 0.5f, 0.5f * p.y + 0.5f, 0.5f * p.z + 0.5f - frame.shadow_depth_bias));
}

// The same for the point at camera-relative `offset` (m).
INLINE float shadow_visibility(IN(PassFrame) frame, IN(sampler2DShadow) shadow_map, vec3 offset) {
  return shadow_visibility_at(frame, shadow_map, frame.shadow_matrix * vec4(offset, 1.0f));
}

// ln of the single-scattering integrands of the two constituents — scattering
// coefficient x transmittance from the camera x transmittance to the sun
// (Collienne 2013, eq. 3.13), summed over the wavelengths of one triple — at
// distance t along the view ray, given the optical depth from the camera
// there. Zero light (the planet's shadow) is ln = -80.
INLINE vec2 log_single_scattering_integrands(IN(AtmosphereParams) set, IN(sampler2D) spectral_transmittance_texture,
                                             IN(PassFrame) frame, vec3 view_ray, float t, vec3 optical_depth) {
  vec3 point = frame.camera + view_ray * t;
  float r = clamp_radius(set, length(point));
  float mu_s = clamp_cosine(dot(point, frame.sun_direction) / r);
  vec3 beta_rayleigh;
  vec3 beta_aerosol;
  vec3 extinction;
  medium_at(set, r, beta_rayleigh, beta_aerosol, extinction);
  vec3 sunlight = exp(-optical_depth) * transmittance_to_top_atmosphere_boundary(set, spectral_transmittance_texture,
                                                                                 r, mu_s);
  if (ray_intersects_ground(set, r, mu_s)) sunlight = vec3(0.0f);
  return log(max(vec2(dot(beta_rayleigh, sunlight), dot(beta_aerosol, sunlight)), vec2(1e-35f)));
}

// Fractions of the single Rayleigh and aerosol scattering of the view ray's
// first `t_end` metres that come from points the terrain does not shadow.
// The ray is sampled at frame.shadow_steps points (offset by `dither` in
// [0, 1) of a step, which turns banding into noise), each weighted by the
// single-scattering integrand of its constituent at the wavelengths of the
// middle triple (log_single_scattering_integrands), so that the shafts
// follow the haze layer and the reddened, dimmer sunlight low in the
// atmosphere.
//
// The integrands are smooth along the ray; the shadow is not. So the
// integrands are evaluated at three anchors only (the camera, t_end / 2 and
// t_end; optical depth between them as exponential segments) and their
// logarithms interpolated by the parabola through the anchors — exact for
// exponential profiles, which steep rays see — and stepped with two
// products per sample, as the incremental Gaussian of Collienne 2013, §4.6.1,
// steps
// its weights: w(s + ds) = w(s) k(s), k(s + ds) = k(s) q. Each sample then
// costs one shadow-map fetch (shadow_visibility, its light-space position
// stepped likewise) and a few products instead of the medium and a table
// lookup: 10x cheaper on llvmpipe.
INLINE void lit_fractions(IN(SpectralSets) spectral, IN(sampler2D) spectral_transmittance_texture, IN(PassFrame) frame,
                          IN(sampler2DShadow) shadow_map, vec3 view_ray, float t_end, float dither,
                          OUT(float) lit_rayleigh, OUT(float) lit_aerosol) {
  int middle = (SPECTRAL_COUNT(spectral) - 1) / 2;
  // The anchors: ln w at s = 0, 1/2, 1 of t_end.
  vec3 extinction_0 = extinction_at(spectral.set[middle], clamp_radius(spectral.set[middle], length(frame.camera)));
  vec3 extinction_1 =
      extinction_at(spectral.set[middle], clamp_radius(spectral.set[middle], length(frame.camera + view_ray * (0.5f * t_end))));
  vec3 extinction_2 =
      extinction_at(spectral.set[middle], clamp_radius(spectral.set[middle], length(frame.camera + view_ray * t_end)));
  vec3 depth_1 = exponential_segment_integral(extinction_0, extinction_1, 0.5f * t_end);
  vec3 depth_2 = depth_1 + exponential_segment_integral(extinction_1, extinction_2, 0.5f * t_end);
  vec2 l0 = log_single_scattering_integrands(spectral.set[middle], spectral_transmittance_texture, frame, view_ray,
                                             0.0f, vec3(0.0f));
  vec2 l1 = log_single_scattering_integrands(spectral.set[middle], spectral_transmittance_texture, frame, view_ray,
                                             0.5f * t_end, depth_1);
  vec2 l2 = log_single_scattering_integrands(spectral.set[middle], spectral_transmittance_texture, frame, view_ray,
                                             t_end, depth_2);
  // Only relative weights matter: the largest anchor is ln w = 0, and no
  // anchor is more than 30 below it (a shadowed anchor is "e^-30 of the
  // rest", which keeps the parabola from plunging towards -80).
  vec2 top = max(max(l0, l1), l2);
  l0 = max(l0 - top, vec2(-30.0f));
  l1 = max(l1 - top, vec2(-30.0f));
  l2 = max(l2 - top, vec2(-30.0f));
  // ln w(s) = l0 + b s + c s², through the three anchors.
  vec2 b = -3.0f * l0 + 4.0f * l1 - l2;
  vec2 c = 2.0f * l0 - 4.0f * l1 + 2.0f * l2;
  float ds = 1.0f / float(frame.shadow_steps);
  float s0 = dither * ds;
  // Overshoot of the parabola between anchors is bounded (ln w <= 4, e^4).
  vec2 w = exp(min(l0 + b * s0 + c * s0 * s0, vec2(4.0f)));
  vec2 k = exp(b * ds + c * (2.0f * s0 + ds) * ds);
  vec2 q = exp(2.0f * c * ds * ds);
  // The sample's position in the light's clip space, stepped too (the
  // shadow matrix is affine).
  vec4 light_0 = frame.shadow_matrix * vec4(view_ray * (s0 * t_end), 1.0f);
  vec4 light_step = frame.shadow_matrix * vec4(view_ray * (ds * t_end), 0.0f);
  vec2 sum = vec2(0.0f);
  vec2 lit_sum = vec2(0.0f);
  for (int i = 0; i < frame.shadow_steps; ++i) {
    vec4 p = light_0 + float(i) * light_step;
    float visible = shadow_visibility_at(frame, shadow_map, p);
    sum += w;
    lit_sum += visible * w;
    w = min(w * k, vec2(1e30f));
    k = min(k * q, vec2(1e30f));
  }
  lit_rayleigh = sum.x > 0.0f ? lit_sum.x / sum.x : 1.0f;
  lit_aerosol = sum.y > 0.0f ? lit_sum.y / sum.y : 1.0f;
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
  if (frame.space_volume)
    return space_volume_lookup(atmosphere, frame, ap_rayleigh, ap_single_rayleigh, ap_aerosol, ap_transmittance,
                               view_ray, t, split);
  PathScattering volume;
  if (frame.volume) {
    volume = aerial_perspective_lookup(frame, ap_rayleigh, ap_single_rayleigh, ap_aerosol, ap_transmittance,
                                       aerial_perspective_uv(atmosphere, frame, view_ray), t, split);
    if (frame.volume_weight >= 1.0f) return volume;
  }
  vec3 transmittance;
  float nu;
  PathScattering exact = eclipsed_scattering_to_point(
      atmosphere, spectral, spectral_transmittance_texture, scattering_texture, single_aerosol_texture,
      multiple_scattering_texture, frame.camera, view_ray * t, frame.sun_direction, frame.low_sun,
      split || frame.night, frame.moons, transmittance, nu);
  if (frame.night) {
    // What the low-sun path gives a segment in the planet's shadow: the
    // tables' multiple scattering, split from their single scattering, and
    // the integrated single scattering, which is zero there
    // (spectral_single_scattering: ray_in_planet_shadow), at full weight.
    exact.single_rayleigh = vec3(0.0f);
    exact.aerosol = vec3(0.0f);
  }
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
                                       IN(sampler2DShadow) shadow_map, vec3 view_ray, float t_max, float dither) {
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

// Everything that reaches the camera through one pixel where the engine drew
// nothing (depth at the clear value), in linear sRGB divided by
// nits_per_unit (the engine's units): the sky, the planet's sphere below the
// horizon, the sun disc and the stars (radiance_along_view_ray; eclipsed by
// frame.moons, whose discs hide what lies behind them), minus the single
// scattering the terrain shadows (the shafts' weights along the ray ignore
// the moons' shadows). `ray`: the pixel's (pixel_ray); `dither` in [0, 1):
// the shaft samples' offset for this pixel.
INLINE vec3 composite_sky_pixel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                                IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                                IN(sampler2D) irradiance_texture, IN(sampler2D) sky_view_rayleigh_texture,
                                IN(sampler2D) sky_view_aerosol_texture, IN(sampler2D) sky_view_surface_texture,
                                bool use_sky_view, IN(sampler3D) ap_rayleigh, IN(sampler3D) ap_single_rayleigh,
                                IN(sampler3D) ap_aerosol, IN(sampler3D) ap_transmittance, IN(PassFrame) frame,
                                IN(sampler2DShadow) shadow_map, IN(PixelRay) ray, float dither) {
  vec3 view_ray = world_view_ray(frame, ray);
  vec3 radiance = radiance_along_view_ray_low_sun(
      atmosphere, spectral, spectral_transmittance_texture, scattering_texture, single_aerosol_texture,
      multiple_scattering_texture, irradiance_texture, sky_view_rayleigh_texture, sky_view_aerosol_texture,
      sky_view_surface_texture, use_sky_view, frame.sky_view, frame.camera, view_ray, frame.sun_direction,
      frame.sun_disc, frame.stars, frame.moons,
      true,  // frame.moons: only moons that may eclipse (make_pass_frame)
      frame.low_sun);
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

// Everything that reaches the camera through one pixel where the engine drew
// a surface at window depth `depth`: its lit colour (or the surface lit here
// from `albedo` and `normal`, with the shadow map's visibility) times the
// transmittance to the camera, plus the in-scatter in between minus its
// shadowed part; same units and arguments as composite_sky_pixel. With
// moons the in-scatter is eclipsed (the volume, or
// eclipsed_scattering_to_point) and so is the G-buffer lighting; lit colour
// is the engine's.
INLINE vec3 composite_surface_pixel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                                    IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                                    IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                                    IN(sampler2D) irradiance_texture, IN(sampler3D) ap_rayleigh,
                                    IN(sampler3D) ap_single_rayleigh, IN(sampler3D) ap_aerosol,
                                    IN(sampler3D) ap_transmittance, IN(PassFrame) frame, IN(sampler2DShadow) shadow_map,
                                    IN(PixelRay) ray, float depth, vec3 colour, vec3 albedo, vec3 normal,
                                    float dither) {
  vec3 offset = world_offset_from_depth(frame, ray, depth);
  float t = length(offset);
  vec3 view_ray = t > 0.0f ? offset / t : world_view_ray(frame, ray);
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
    // sky, from the tables at the surface point (Collienne 2013, §4.3.3).
    vec3 point = frame.camera + offset;
    float r = length(point);
    vec3 up = point / r;
    vec3 n = dot(normal, normal) > 0.0f ? normalize(normal) : up;
    vec3 sky_irradiance;
    vec3 sun_irradiance = sun_and_sky_irradiance_at(atmosphere, spectral, spectral_transmittance_texture,
                                                    irradiance_texture, r, up, n, frame.sun_direction,
                                                    sky_irradiance);
    if (frame.shadows) sun_irradiance *= shadow_visibility(frame, shadow_map, offset);
    if (frame.moons.count > 0) {
      // Eclipses, as view_ray_terms lights the ground sphere: the part of the
      // sun the moons leave the point, and the diffuse light's documented
      // approximation (the medium of the first wavelength triple).
      sun_irradiance *=
          sunlight_visible_fraction(frame.moons, atmosphere.sun_angular_radius, point, frame.sun_direction);
      sky_irradiance *= diffuse_light_visible_fraction(spectral.set[0], spectral_transmittance_texture, frame.moons,
                                                       point, frame.sun_direction);
    }
    // The light's sRGB is clamped at zero, as the sky's is: a saturated
    // spectrum lies outside the sRGB gamut, and a negative channel times the
    // albedo would give a negative surface radiance.
    vec3 light = max(frame.radiance_to_srgb * (sun_irradiance + sky_irradiance), vec3(0.0f));
    surface = albedo * (1.0f / PI) * light * frame.light_scale;
  }
  return surface * srgb_transmittance(atmosphere, frame, s.transmittance) +
         max(frame.radiance_to_srgb * in_scatter, vec3(0.0f)) * frame.light_scale;
}

// A sky pixel whose ray misses the atmosphere (a camera above it looking
// past the planet): only the light from beyond reaches the camera, the
// stars, the sun disc or a moon (radiance_beyond_atmosphere), unattenuated
// and without shafts (they lie in the atmosphere). The same as
// composite_sky_pixel for such a pixel, without the atmosphere's work.
INLINE bool sky_ray_misses_atmosphere(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, IN(PixelRay) ray) {
  vec3 start = camera_above_ground(atmosphere, frame.camera);
  return !enter_atmosphere(atmosphere, start, world_view_ray(frame, ray));
}

INLINE vec3 composite_space_pixel(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, IN(PixelRay) ray) {
  vec3 beyond = radiance_beyond_atmosphere(atmosphere, camera_above_ground(atmosphere, frame.camera),
                                           world_view_ray(frame, ray), frame.sun_direction, frame.sun_disc,
                                           frame.stars, frame.moons);
  return max(frame.radiance_to_srgb * beyond, vec3(0.0f)) * frame.light_scale;
}

// Whether the pixel's light needs the low-sun path (a frame with
// frame.low_sun, no moons): the weight of the integration on its segment in
// the atmosphere (segment_low_sun_weight) is above zero. For a surface the
// segment is the one light_to_distance evaluates, to the surface's point;
// for the sky, the whole ray through the atmosphere (view_ray_terms from
// space; the shafts' segments are parts of it, and the sun is lowest at an
// end of a ray, so a part of a ray whose weight is zero has a zero weight
// too). Pixels where it is false give the same light with frame.low_sun
// false, without the integration: the pass draws the two kinds with
// different programs (atmosphere_pass.frag.glsl). `night`: besides, the
// segment lies in the planet's shadow cylinder (ray_in_planet_shadow, the
// test that makes the integration return zero): for a surface, the light of
// frame.night, without the integration.
INLINE bool pixel_low_sun_classes(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, IN(PixelRay) ray,
                                   float depth, OUT(bool) night) {
  night = false;
  vec3 view_ray;
  float t;
  if (depth_is_sky(depth, frame.depth_encoding)) {
    view_ray = world_view_ray(frame, ray);
    t = 1e30f;  // to the ray's end (atmosphere_segment stops at the ground or the top)
  } else {
    // The segment of light_to_distance and eclipsed_scattering_to_point,
    // from the same floats.
    vec3 offset = world_offset_from_depth(frame, ray, depth);
    t = length(offset);
    view_ray = t > 0.0f ? offset / t : world_view_ray(frame, ray);
    offset = view_ray * t;
    t = length(offset);
    view_ray = t > 0.0f ? offset / t : vec3(0.0f, 0.0f, 1.0f);
  }
  AtmosphereSegment segment;
  if (!atmosphere_segment(atmosphere, camera_above_ground(atmosphere, frame.camera), view_ray, t,
                          frame.sun_direction, segment))
    return false;
  float nu = clamp_cosine(dot(view_ray, frame.sun_direction));
  night = ray_in_planet_shadow(atmosphere, segment.mu_s,
                               mu_s_at_ray_end(segment.r, segment.mu, segment.mu_s, nu, segment.t));
  return segment_low_sun_weight(segment, nu) > 0.0f;
}

INLINE bool pixel_needs_low_sun_path(IN(AtmosphereParams) atmosphere, IN(PassFrame) frame, IN(PixelRay) ray,
                                     float depth) {
  bool night;
  return pixel_low_sun_classes(atmosphere, frame, ray, depth, night);
}

// The pixel, whichever it is, with the frame's variant (the CPU twin; the
// pass sorts the pixels into classes in a stencil mask and draws each class
// with its own program, see atmosphere_pass.frag.glsl).
INLINE vec3 composite_pixel(IN(AtmosphereParams) atmosphere, IN(SpectralSets) spectral,
                            IN(sampler2D) spectral_transmittance_texture, IN(sampler3D) scattering_texture,
                            IN(sampler3D) single_aerosol_texture, IN(sampler3D) multiple_scattering_texture,
                            IN(sampler2D) irradiance_texture, IN(sampler2D) sky_view_rayleigh_texture,
                            IN(sampler2D) sky_view_aerosol_texture, IN(sampler2D) sky_view_surface_texture,
                            bool use_sky_view, IN(sampler3D) ap_rayleigh, IN(sampler3D) ap_single_rayleigh,
                            IN(sampler3D) ap_aerosol, IN(sampler3D) ap_transmittance,
                            IN(sampler2D) space_volume_regular_columns, IN(PassFrame) frame,
                            IN(sampler2DShadow) shadow_map, IN(PixelRay) ray, float depth, vec3 colour, vec3 albedo,
                            vec3 normal, float dither) {
  if (depth_is_sky(depth, frame.depth_encoding))
    return composite_sky_pixel(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                               single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                               sky_view_rayleigh_texture, sky_view_aerosol_texture, sky_view_surface_texture,
                               use_sky_view, ap_rayleigh, ap_single_rayleigh, ap_aerosol, ap_transmittance, frame,
                               shadow_map, ray, dither);
  // Surfaces the space volume does not cover are evaluated exactly.
  PassFrame surface_frame = frame;
  if (frame.space_volume && !space_volume_covers(frame, space_volume_regular_columns, ray))
    surface_frame.space_volume = false;
  return composite_surface_pixel(atmosphere, spectral, spectral_transmittance_texture, scattering_texture,
                                 single_aerosol_texture, multiple_scattering_texture, irradiance_texture, ap_rayleigh,
                                 ap_single_rayleigh, ap_aerosol, ap_transmittance, surface_frame, shadow_map, ray,
                                 depth, colour, albedo, normal, dither);
}
