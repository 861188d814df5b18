// The sea's fragment shader (src/planet/ocean.cpp, include/atmos/ocean.hpp),
// appended after "#version 450 core", AtmospherePass::glsl_library(),
// physics/water.glsl, ocean_light_maps.glsl and ocean_waves.glsl. Each
// pixel intersects its view ray with the sea-level sphere, and near the
// camera with the displaced waves (ocean_waves.glsl), shades the point with
// the water's physics lit by the atmosphere's functions, and writes
// radiance / nits_per_unit and the point's reversed-Z depth.
//
// The ray and the sphere, in camera-relative float arithmetic: with r_c the
// camera's distance from the centre, R the sphere's radius, up the camera's
// zenith and d the ray, the distance t to the sphere solves
// t² + 2 b t + c = 0, b = r_c (up · d), c = r_c² − R² = (r_c − R)(r_c + R)
// (computed in double on the CPU: the camera's height above the sea
// survives at any altitude). The nearer root, t = c / (−b + √(b² − c)),
// has no cancellation for the descending rays (b < 0) that meet the sphere
// from above, so the point is exact to float's relative precision at 2 m
// above the sea as at 100 planet radii.
//
// Waves and levels of detail (Bruneton, Neyret & Holzschuch 2010, §4): the
// sea's height is a sum of sine waves h = Σ a_i sin(k_i · x + φ_i), whose
// slopes ∇h = Σ a_i cos(k_i · x + φ_i) k_i tilt the normal, and whose
// slope variance ½ a_i² k_i² (per axis: the squares of k_i's upwind and
// crosswind components) is part of Cox & Munk 1954's total. A wave is kept
// in the normal with a weight w_i that goes from 1 to 0 as its phase
// changes by π/4 to π/2 across the pixel's footprint on the sea (a
// wavelength over 8 to 4 pixels); the variance it no longer shows,
// (1 − w_i²) ½ a_i² k_i², widens the slope distribution of the BRDF,
// whose variance is Cox & Munk's less what the normal shows. The slopes'
// total variance is Cox & Munk's at every distance, which keeps the mean
// radiance where waves fade into the BRDF. The footprint is the pixel's
// angle times the distance, stretched by 1 / μ_v along the view's azimuth.
// Wave phases are the world's: k_i · (camera + offset) with k_i · camera
// reduced modulo 2π in double on the CPU.
//
// The radiance (docs/water.md): the glint f(v, l) E_sun (N · l) with the
// microfacet BRDF over the unresolved slopes about the tilted normal N; the
// sky reflected by those slopes (WATER_SKY_SAMPLE_COUNT sky lookups from
// the point, or with OCEAN_SKY_MEAN_DIRECTION one lookup in their mean
// direction times the rough surface's reflectance); and the light leaving
// the water (Lee et al. 1999) through the flat surface, with the seabed at
// the bathymetry's depth. E_sun is the sun's irradiance normal to it at the
// point (transmittance and the planet's shadow) at each triple of the
// atmosphere's working wavelengths, E_sky the sky's on the horizontal; the
// glint and the light from below are evaluated at every working wavelength
// and summed into the tables' channels (water_spectral_radiance), the
// reflected sky and the moons' and stars' glints in the channels with the
// water's optics at the channels' wavelengths (water_optics); the sum is
// converted to colour with the pass's matrix (ATMOS_RADIANCE_TO_SRGB); with OCEAN_ECLIPSE the moons' factors dim the sun's part and
// the sky's (atmos_eclipse), as for the terrain; with OCEAN_MOONS the
// moons' own light is mirrored through the glint's BRDF. The sky's radiance, E_sun
// and E_sky are read from the light maps (ocean_light_maps.glsl), which
// tabulate the pass's functions at sea level, the rough surface's
// reflectance of the sky from a map of water_sky_reflectance, and the light
// from below from a map of water_spectral_radiance over the downwelling
// irradiance (but in the eclipse's program); with
// OCEAN_DIRECT_LIGHT (a test's program) the shader evaluates those
// functions instead.

layout(location = 0) out vec4 colour;

uniform mat4 clip_from_offset;    // camera-relative m -> clip space
uniform mat4 offset_from_clip;    // its inverse
uniform vec2 viewport_size;       // pixels
uniform vec3 camera_planet;       // m, planet-centred
uniform vec3 camera_up;           // unit: camera_planet / r_c
uniform float camera_radius;      // r_c, m
uniform float camera_height_term; // r_c² − R², m²
uniform float pixel_angle;        // rad per pixel near the image centre
uniform vec3 sun_direction;       // unit, planet axes
uniform float light_scale;        // (sun illuminance / the atmosphere's own) / nits_per_unit

// The water's optics at the channels' wavelengths (the reflected sky, the
// moons' and stars' glints) and at every working wavelength (the sun's
// glint, the light from below).
uniform vec3 sea_refractive_index;
uniform vec3 sea_absorption;
uniform vec3 sea_backscattering;
uniform vec3 sea_diffuse_reflectance;
uniform vec2 sea_slope_variance;  // Cox & Munk's, upwind and crosswind
uniform WaterSpectrum sea_spectrum;

uniform vec3 wind_upwind;  // unit, tangent at the waves' anchor
// The waves (wave_count, wave_vector, wave_in_wind, wave_phase): ocean_waves.glsl.
uniform float sea_radius;  // m: R, the level's sphere
// 0 when no wave can displace the surface anywhere in the image: a wave
// displaces only where its amplitude a spans a pixel, a sin θ_v / (t α) > 1
// (ocean_waves.glsl), and every sea point is at least the camera's height
// h above the level away, so none can once max a_i < h α. A uniform
// branch: the software rasteriser skips the selection and the march
// instead of running them under an empty mask.
uniform int waves_can_displace;

uniform samplerCube bathymetry;  // r: the ground's height (m above the datum), g: its least over 3 x 3 texels,
                                 // b: the lake mask (1 lake, 0 not)
uniform sampler3D sky_map;       // the sky's radiance at sea level (ocean_light_maps.glsl): azimuth, view, sun
uniform sampler2D light_map;     // row 0: E_sky on the horizontal, row 1 + k: E_sun at triple k, along the sun's parameter
uniform sampler3D reflectance_map;  // the rough surface's reflectance of the sky (rgb) and its mean direction (a)
uniform sampler3D below_map;     // the light from below over the downwelling irradiance (rgb): view, sun, depth
uniform float deep_water_depth;  // m: H_deep (ocean_light_maps.glsl), the below map's deepest layer
uniform float sea_level;         // m above the datum: the level drawn, the sea's or the lakes'
uniform int lakes;               // 1: the lakes' level, drawn where the lake mask is at least one half
uniform vec3 seabed_albedo;

// Tests' switches (planet/ocean_internal.hpp): 1 the glint, 2 the sky, 4
// the light from below, 8 the sun's irradiance instead, 16 a uniform sky
// of radiance 1, 64 no displaced waves; 32 (a program of its own,
// OCEAN_DIRECT_LIGHT) the pass's functions instead of the light maps.
uniform int terms;

#if defined(OCEAN_STARS)
uniform int star_count;
uniform vec4 star_directions[16];   // xyz: unit, towards the star (planet axes); kOceanMirroredStars
uniform vec4 star_irradiances[16];  // rgb: irradiance above the atmosphere, the tables' channels
#endif
#if defined(OCEAN_MOONS)
uniform int moon_count;
uniform vec4 moon_spheres[MOON_CAPACITY];
uniform float eclipse_top_radius;  // m: the atmosphere's top, for the reflected sky's eclipse (below)
#endif

// The sea is moved towards the camera, ahead of the terrain's flat sea,
// which lies on the same sphere at its vertices (below it between them):
// by 1e-5 of its distance, more than the tiles' float positions differ
// from the sphere (1e-6 of the distance), and at grazing views by the
// distance along the ray over which the sea rises kHeightTolerance, which
// covers the tiles' float heights (under a millimetre) however flat the
// ray (from 2 m the horizon is seen 0.05 degrees down: a millimetre is
// metres along the ray). The sea covers land less than kHeightTolerance
// above it.
const float kRelativeLead = 1.0e-5;
const float kHeightTolerance = 0.01;  // m

// The sky's radiance seen from the sea point `point` (zenith n) in
// `direction`, lifted to the horizon when it points below it: directions
// mirrored by facets tilted by the resolved waves, and the mean direction
// at grazing views (rounded in float), may dip below the horizon, where
// the tables' ray meets the ground and returns only the air in front of
// it. The sea there would mirror other waves; the horizon's sky stands in.
// From the sky's map: μ, μ_s and the azimuth φ between the view and the
// sun about the zenith, cos φ = (ν − μ μ_s) / (sin θ sin θ_s).
vec3 sky_seen_from_sea(vec3 point, vec3 n, vec3 direction, vec3 sun) {
  float below = dot(direction, n);
  if (below < kOceanLeastSkyCosine) direction = normalize(direction + (kOceanLeastSkyCosine - below) * n);
#if defined(OCEAN_DIRECT_LIGHT)
  return ocean_sky_radiance(point, direction, sun);
#else
  float mu = dot(direction, n), mu_s = dot(sun, n);
  float sines = sqrt(max((1.0 - mu * mu) * (1.0 - mu_s * mu_s), 1e-12));
  float cos_phi = (dot(direction, sun) - mu * mu_s) / sines;
  vec3 uvw = vec3(ocean_azimuth_parameter(cos_phi), ocean_elevation_parameter(mu), ocean_sun_parameter(mu_s));
  uvw = vec3(ocean_map_coordinate(uvw.x, OCEAN_SKY_MAP_SIZE), ocean_map_coordinate(uvw.y, OCEAN_SKY_MAP_SIZE),
             ocean_map_coordinate(uvw.z, OCEAN_SKY_MAP_SIZE));
  return exp(textureLod(sky_map, uvw, 0.0).rgb);
#endif
}

// The rough surface's reflectance of the sky (water_sky_reflectance) and
// the mean reflected direction, from the reflectance map: the slopes'
// variances along and across the view's azimuth, without their covariance
// (ocean_light_maps.glsl).
vec3 sea_sky_reflectance(IN(WaterParams) water, vec3 normal, vec3 upwind, vec3 view, out vec3 mean_direction) {
#if defined(OCEAN_DIRECT_LIGHT)
  return water_sky_reflectance(water, normal, upwind, view, mean_direction);
#else
  float mu_v = dot(view, normal);
  vec3 tangent = view - mu_v * normal;
  float tangent_length = length(tangent);
  vec3 along = tangent_length > 1e-6 ? tangent / tangent_length : upwind;
  vec2 a = vec2(dot(along, upwind), dot(along, cross(normal, upwind)));
  vec2 v = water.slope_variance;
  float v_along = v.x * a.x * a.x + v.y * a.y * a.y, v_across = v.x * a.y * a.y + v.y * a.x * a.x;
  vec3 uvw = vec3(ocean_elevation_parameter(mu_v), ocean_deviation_parameter(sqrt(v_along)),
                  ocean_deviation_parameter(sqrt(v_across)));
  uvw = vec3(ocean_map_coordinate(uvw.x, OCEAN_REFLECTANCE_MAP_SIZE),
             ocean_map_coordinate(uvw.y, OCEAN_REFLECTANCE_MAP_SIZE),
             ocean_map_coordinate(uvw.z, OCEAN_REFLECTANCE_MAP_SIZE));
  vec4 texel = textureLod(reflectance_map, uvw, 0.0);
  float mu = clamp(texel.a, -1.0, 1.0);
  mean_direction = mu * normal - sqrt(1.0 - mu * mu) * along;
  return texel.rgb;
#endif
}

// E_sun (normal to the sun) at each triple of working wavelengths and E_sky
// (on the horizontal, the tables' channels) at sea point `point` of zenith
// n.
void sun_and_sky_at_sea(vec3 point, vec3 n, vec3 sun, out vec3 sun_irradiance[SPECTRAL_SET_CAPACITY],
                        out vec3 sky_irradiance) {
#if defined(OCEAN_DIRECT_LIGHT)
  sky_irradiance = ocean_sky_irradiance(point, sun);
  for (int k = 0; k < SPECTRAL_SET_CAPACITY; ++k) sun_irradiance[k] = ocean_set_sun_irradiance(k, point, sun);
#else
  float u = ocean_map_coordinate(ocean_sun_parameter(dot(sun, n)), OCEAN_LIGHT_MAP_SIZE);
  sky_irradiance = exp(textureLod(light_map, vec2(u, 0.5 / float(OCEAN_LIGHT_MAP_ROWS)), 0.0).rgb);
  for (int k = 0; k < SPECTRAL_SET_CAPACITY; ++k)
    sun_irradiance[k] = exp(textureLod(light_map, vec2(u, (float(k) + 1.5) / float(OCEAN_LIGHT_MAP_ROWS)), 0.0).rgb);
#endif
}

void main() {
  vec2 ndc = 2.0 * gl_FragCoord.xy / viewport_size - 1.0;
  vec4 near_point = offset_from_clip * vec4(ndc, 1.0, 1.0);
  vec3 d = normalize(near_point.xyz / near_point.w);
  float b = camera_radius * dot(camera_up, d);
  float disc = b * b - camera_height_term;
  if (camera_height_term <= 0.0 || b >= 0.0 || disc < 0.0) discard;
  float t = camera_height_term / (-b + sqrt(disc));
  vec3 offset = t * d;
  vec4 clip = clip_from_offset * vec4(offset, 1.0);
  float depth = clip.z / clip.w;
  if (!(clip.w > 0.0) || !(depth <= 1.0)) discard;

  vec3 point = camera_planet + offset;
  vec3 n = normalize(point);
  vec3 ground = textureLod(bathymetry, n, 0.0).rgb;
  if (ground.g > sea_level + 1.0) discard;  // land all around: the terrain is in front
  if (lakes != 0 && ground.b < 0.5) discard;  // no lake here
  float water_depth = max(sea_level - ground.r, 0.0);

  vec3 view = -d;
  vec3 upwind = wind_upwind - dot(wind_upwind, n) * n;
  float upwind_length = length(upwind);
  upwind = upwind_length > 1e-3 ? upwind / upwind_length : normalize(cross(n, abs(n.x) < 0.9 ? vec3(1, 0, 0) : vec3(0, 1, 0)));
  vec3 crosswind = cross(n, upwind);
  float mu_v = max(dot(view, n), 1e-4);
  vec3 along = view - dot(view, n) * n;
  along = length(along) > 1e-6 ? normalize(along) : upwind;
  // The wave vectors' components on the local upwind and crosswind axes
  // are those at the waves' anchor (wave_in_wind, from the CPU): they
  // differ by the square of the arc from it, 1e-4 within its 0.5 degrees,
  // and farther, where the sea is seen from higher, the waves are filtered
  // out. The view's azimuth on the same axes gives the footprint's phase
  // changes.
  vec2 along_wind = vec2(dot(along, upwind), dot(along, crosswind));
  float footprint = t * pixel_angle;

  // The displaced sea (ocean_waves.glsl): the waves resolved by 8 pixels
  // or more per wavelength at the ray's sphere point displace the surface;
  // the pixel is the first crossing of its ray with it. The weights, the
  // frame and the lead below are the sphere point's.
  vec3 surface_offset = offset;
  float surface_depth = depth;
  ocean_wave_count = 0;
  if (waves_can_displace != 0) {
    ocean_select_displacing_waves(footprint, mu_v, along_wind);
    if (ocean_wave_count > 0 && (terms & 64) == 0) {
      float t_surface;
      if (!ocean_displaced_hit(d, b, camera_height_term, sea_radius, t_surface)) discard;
      surface_offset = t_surface * d;
      vec4 surface_clip = clip_from_offset * vec4(surface_offset, 1.0);
      if (!(surface_clip.w > 0.0)) discard;
      surface_depth = surface_clip.z / surface_clip.w;
      point = camera_planet + surface_offset;
    }
  }

  // The resolved waves' slopes and variance, at the surface's point.
  vec2 slope = vec2(0.0);
  vec2 resolved = vec2(0.0);
  for (int i = 0; i < wave_count; ++i) {
    vec4 wave = wave_in_wind[i];
    // The waves come in increasing wavenumber, and the phase change is at
    // least the footprint times |k|: once that filters a wave out, it
    // filters out the shorter ones.
    if (footprint * wave.z >= 0.5 * PI) break;
    float w = 1.0 - smoothstep(0.25 * PI, 0.5 * PI, ocean_footprint_phase(footprint, mu_v, along_wind, wave.xy));
    float a = wave.w;
    slope += (w * a * cos(wave_phase[i] + dot(wave_vector[i].xyz, surface_offset))) * wave.xy;
    resolved += (w * w * 0.5 * a * a) * wave.xy * wave.xy;
  }
  WaterParams water;
  water.refractive_index = sea_refractive_index;
  water.absorption = sea_absorption;
  water.backscattering = sea_backscattering;
  water.diffuse_reflectance = sea_diffuse_reflectance;
  water.slope_variance = max(sea_slope_variance - resolved, vec2(1e-5));
  // The resolved surface's normal, kept facing the camera at no less than
  // half the mean surface's cosine: the back sides of waves seen at grazing
  // angles, and the facets that would mirror the view into the sea (whose
  // light, that of other waves, the BRDF drops), are not drawn black.
  vec3 normal = normalize(n - slope.x * upwind - slope.y * crosswind);
  float facing = dot(view, normal), least_facing = 0.5 * mu_v;
  if (facing < least_facing) normal = normalize(normal + (least_facing - facing) * view);
  vec3 wave_upwind = normalize(upwind - dot(upwind, normal) * normal);

  // The light at the point.
  vec3 sun = sun_direction;
  vec3 sky_irradiance;
  vec3 sun_irradiance[SPECTRAL_SET_CAPACITY];
  sun_and_sky_at_sea(point, n, sun, sun_irradiance, sky_irradiance);
  float sun_factor = 1.0, sky_factor = 1.0;
#if defined(OCEAN_ECLIPSE)
  atmos_eclipse(point, sun, moon_count, moon_spheres, sun_factor, sky_factor);
#endif
  vec3 sun_channels = vec3(0.0);
  for (int k = 0; k < SPECTRAL_SET_CAPACITY; ++k) {
    sun_irradiance[k] *= sun_factor;
    sun_channels += sea_spectrum.to_channels[k] * sun_irradiance[k];
  }
  sky_irradiance *= sky_factor;

  // The sun's glint and the light from below at every working wavelength.
  float view_half_cosine;
  float glint_factor = water_glint_geometry(water.slope_variance, normal, wave_upwind, view, sun, view_half_cosine) *
                       max(dot(sun, normal), 0.0);
  vec3 glint;
  vec3 below;
#if !defined(OCEAN_ECLIPSE) && !defined(OCEAN_DIRECT_LIGHT)
  // From the map (ocean_light_maps.glsl), times the downwelling
  // irradiance. The moons' eclipse, which dims the sun's and the sky's
  // light by different factors, evaluates it.
  float mu_s = dot(sun, n);
  vec3 uvw = vec3(ocean_map_coordinate(ocean_elevation_parameter(dot(view, n)), OCEAN_BELOW_MAP_WIDTH),
                  ocean_map_coordinate(ocean_sun_parameter(mu_s), OCEAN_BELOW_MAP_HEIGHT),
                  ocean_map_coordinate(ocean_depth_parameter(water_depth, deep_water_depth), OCEAN_BELOW_MAP_DEPTH));
  below = textureLod(below_map, uvw, 0.0).rgb * (sun_channels * max(mu_s, 0.0) + sky_irradiance);
  glint = water_spectral_glint(sea_spectrum, sun_irradiance, glint_factor, view_half_cosine);
#else
  below = water_spectral_radiance(sea_spectrum, sun_irradiance, sky_irradiance, glint_factor, view_half_cosine, n,
                                  view, sun, water_depth, seabed_albedo, glint);
#endif
#if defined(OCEAN_MOONS)
  // The moons' light mirrored by the waves (a moon's glade), through the
  // glint's BRDF as the sun's. A moon, a Lambertian sphere of albedo
  // MOON_ALBEDO (eclipse.glsl) lit by the sun, gives at distance d the
  // irradiance E = A E_0 (ρ/d)² (2 / (3π)) (sin α + (π − α) cos α)
  // normal to it (Lambert's sphere; Russell 1916), E_0 the sun's above the
  // atmosphere, ρ the moon's radius, α the phase angle (cos α = −s · l, l
  // towards the moon; 0 at full moon, where E = (2/3) A E_0 (ρ/d)²),
  // attenuated by the atmosphere's transmittance towards the moon.
  for (int i = 0; i < moon_count; ++i) {
    vec3 to_moon = moon_spheres[i].xyz - point;
    float moon_distance = length(to_moon);
    vec3 l = to_moon / moon_distance;
    float alpha = acos(clamp(-dot(sun, l), -1.0, 1.0));
    float size = moon_spheres[i].w / moon_distance;
    float lambert = MOON_ALBEDO * size * size * (2.0 / (3.0 * PI)) * (sin(alpha) + (PI - alpha) * cos(alpha));
    vec3 moon_irradiance = ATMOSPHERE.solar_irradiance * lambert * ocean_transmittance_to_light(point, l);
    glint += water_glint_brdf(water, normal, wave_upwind, view, l) * moon_irradiance * max(dot(l, normal), 0.0);
  }
#endif
#if defined(OCEAN_STARS)
  // The brightest stars' light mirrored by the waves, as the sun's: each a
  // point of irradiance E above the atmosphere (the tables' channels)
  // attenuated towards it.
  for (int i = 0; i < star_count; ++i) {
    vec3 l = star_directions[i].xyz;
    vec3 star_irradiance = star_irradiances[i].rgb * ocean_transmittance_to_light(point, l);
    glint += water_glint_brdf(water, normal, wave_upwind, view, l) * star_irradiance * max(dot(l, normal), 0.0);
  }
#endif
  vec3 sky = vec3(0.0);
#if defined(OCEAN_SKY_MEAN_DIRECTION)
  vec3 mean_direction;
  vec3 reflectance = sea_sky_reflectance(water, normal, wave_upwind, view, mean_direction);
  sky = reflectance * ((terms & 16) != 0 ? vec3(1.0) : sky_seen_from_sea(point, n, mean_direction, sun));
#else
  WaterSkyQuadrature q = water_sky_quadrature(water, normal, wave_upwind, view);
  for (int k = 0; k < WATER_SKY_SAMPLE_COUNT; ++k) {
    vec3 direction;
    vec3 weight = water_sky_sample(q, k, direction);
    if (weight.x + weight.y + weight.z > 0.0)
      sky += weight * ((terms & 16) != 0 ? vec3(1.0) : sky_seen_from_sea(point, n, direction, sun));
  }
#endif
#if defined(OCEAN_ECLIPSE)
  // The reflected sky in an eclipse. The sky's map holds the uneclipsed
  // sky; the sky the sea mirrors is dark where the air it sees lies in the
  // moon's shadow and lit where it lies beyond (the twilight all around the
  // horizon in the umbra). Along the mirror direction r, from the point to
  // where r leaves the atmosphere (distance t_top), the light a segment
  // scatters towards the point is, for a source function J uniform along
  // the ray, J (T_k − T_{k+1}), T the transmittance from the point
  // (T(0, t) = T(0, top) / T(t, top), the pass's transmittance to the top
  // along r); the moon removes the sun's part f_k outside the segment's
  // midpoint (atmos_eclipse's sun factor). The uneclipsed sky is scaled by
  // Σ_k (T_k − T_{k+1}) f_k / (1 − T(0, top)), 8 segments with ends at
  // t_top (k/8)², and by no less than the diffuse light's fraction at the
  // point: single scattering's share of the eclipse, the multiple
  // scattering's as the terrain's.
  {
    vec3 mirror = reflect(-view, normal);
    float mu_r = max(dot(mirror, n), kOceanLeastSkyCosine);
    mirror = normalize(mirror + (mu_r - dot(mirror, n)) * n);
    float radius = length(point), height = eclipse_top_radius - radius;
    float rise = 2.0 * radius * height + height * height;
    float top_distance = rise / (sqrt(radius * radius * mu_r * mu_r + rise) + radius * mu_r);
    vec3 to_top = ocean_transmittance_to_light(point, mirror);
    vec3 previous = vec3(1.0), lit = vec3(0.0);
    for (int k = 1; k <= 8; ++k) {
      float t = top_distance * float(k * k) / 64.0, middle = top_distance * (float(k) - 0.5) * (float(k) - 0.5) / 64.0;
      vec3 transmittance = min(to_top / max(ocean_transmittance_to_light(point + t * mirror, mirror), vec3(1e-30)), previous);
      float air_sun, air_sky;
      atmos_eclipse(point + middle * mirror, sun, moon_count, moon_spheres, air_sun, air_sky);
      lit += (previous - transmittance) * air_sun;
      previous = transmittance;
    }
    sky *= max(lit / max(vec3(1.0) - previous, vec3(1e-6)), vec3(sky_factor));
  }
#else
  sky *= sky_factor;
#endif

  // The channels to colour, as the pass converts its own light.
  vec3 radiance = ((terms & 1) != 0 ? glint : vec3(0.0)) + ((terms & 2) != 0 ? sky : vec3(0.0)) +
                  ((terms & 4) != 0 ? below : vec3(0.0));
  if ((terms & 8) != 0) radiance = sun_channels;
  colour = vec4(max(ATMOS_RADIANCE_TO_SRGB * radiance * light_scale, vec3(0.0)), 1.0);
  // The uniform sky's test: the rough surface's reflectance itself.
  if ((terms & 16) != 0 && (terms & 8) == 0) colour = vec4(max(sky, vec3(0.0)), 1.0);
  // The depth: the surface's, or where a trough lies beyond the sphere,
  // the sphere's with its lead (above), so that the terrain's flat sea on
  // the sphere stays behind the water.
  float lead = clamp(kHeightTolerance / (t * max(dot(view, n), 1e-9)), kRelativeLead, 0.1);
  gl_FragDepth = min(max(surface_depth, depth * (1.0 + lead)), 1.0);
}
