// The engine's fragment shader (main pass). The engine prepends
// "#version 450 core", "#define LOG_DEPTH 0|1", "#define ECLIPSE 0|1" and atmos's GLSL library
// (AtmospherePass::glsl_library), which declares the atmosphere's textures
// and the atmos_* functions used below.
//
// Output: lit colour in cd/m² divided by the buffer's nits-per-unit
// (SurfaceMode::lit_colour), and albedo + world normal for
// SurfaceMode::gbuffer (written in both modes; unused targets are dropped).

in VertexOut {
  vec3 patch_position;
  vec3 normal;
  vec3 albedo;
  float view_depth;
} fs_in;

// Sun shadow map (depth from the sun, orthographic), with depth comparison.
layout(binding = 0) uniform sampler2DShadow u_shadow_map;
uniform bool u_shadows;
uniform mat4 u_shadow_from_patch;     // patch-relative world -> the sun's clip space
uniform float u_shadow_normal_offset; // engine units

uniform vec3 u_sun_direction;         // world frame, unit, towards the sun
uniform vec3 u_patch_centre_planet_m; // patch centre minus planet centre, metres
uniform float u_metres_per_unit;
uniform float u_units_per_nit;        // 1 / FrameInput::nits_per_unit
uniform float u_log_depth_far;        // FrameInput::log_depth_far, engine units (LOG_DEPTH)

layout(location = 0) out vec4 out_colour;
layout(location = 1) out vec4 out_albedo;
layout(location = 2) out vec4 out_normal;

uniform float u_detail;               // strength of the albedo detail (terrain 1, objects 0)

#if ECLIPSE
// The moons (FrameInput::moons): xyz the centre in planet-centred metres, w
// the radius.
uniform int u_moon_count;
uniform vec4 u_moon_spheres[4];

// An eclipse dims the sun and the sky light at `point` exactly as the
// plugin dims the light of the surfaces it lights itself (G-buffer mode):
// atmos_eclipse of the GLSL library.
void eclipse(vec3 point, inout vec3 sun_irradiance, inout vec3 sky_irradiance) {
  float sun_factor;
  float sky_factor;
  atmos_eclipse(point, u_sun_direction, u_moon_count, u_moon_spheres, sun_factor, sky_factor);
  sun_irradiance *= sun_factor;
  sky_irradiance *= sky_factor;
}
#endif

const float ENGINE_PI = 3.14159265;

// --- Albedo detail ----------------------------------------------------------
// The terrain's albedo comes per vertex, every 156 m: near the camera that is
// a smear. Two octaves of value noise (60 m and 11 m) break it up, each faded
// out where a pixel spans more than about one noise cell, so that distant
// terrain neither aliases nor shimmers.

uint detail_hash(uvec2 v) {
  v = v * 1664525u + 1013904223u;
  v.x += v.y * 1664525u;
  v.y += v.x * 1664525u;
  v ^= v >> 16u;
  v.x += v.y * 1664525u;
  v.y += v.x * 1664525u;
  v ^= v >> 16u;
  return v.x;
}

float cell_value(ivec2 cell) { return float(detail_hash(uvec2(cell)) & 0xffffu) / 65535.0; }

// Smooth noise in [0, 1] with one value per unit cell.
float value_noise(vec2 p) {
  vec2 cell = floor(p);
  vec2 f = p - cell;
  vec2 u = f * f * (3.0 - 2.0 * f);
  ivec2 c = ivec2(cell);
  return mix(mix(cell_value(c), cell_value(c + ivec2(1, 0)), u.x),
             mix(cell_value(c + ivec2(0, 1)), cell_value(c + ivec2(1, 1)), u.x), u.y);
}

vec3 detailed_albedo(vec3 albedo, vec2 ground_m) {
  float detail = 0.0;
  for (int octave = 0; octave < 2; ++octave) {
    vec2 p = ground_m / (octave == 0 ? 60.0 : 11.0);
    float footprint = max(length(dFdx(p)), length(dFdy(p)));  // noise cells per pixel
    detail += (1.0 - smoothstep(0.3, 1.0, footprint)) * (value_noise(p) - 0.5);
  }
  return albedo * clamp(1.0 + 0.7 * u_detail * detail, 0.5, 1.5);
}

// Fraction of the sun visible from the surface point (0 in a mountain's
// shadow): 3x3 taps of 2x2 hardware-filtered comparisons, looked up a little
// off the surface along its normal to avoid self-shadowing ("acne").
float sun_visibility(vec3 patch_position, vec3 normal) {
  if (!u_shadows) return 1.0;
  vec4 clip = u_shadow_from_patch * vec4(patch_position + normal * u_shadow_normal_offset, 1.0);
  vec3 coord = clip.xyz / clip.w * 0.5 + 0.5;
  if (any(lessThan(coord, vec3(0.0))) || any(greaterThan(coord, vec3(1.0)))) return 1.0;  // outside: lit
  vec2 texel = 1.0 / vec2(textureSize(u_shadow_map, 0));
  float lit = 0.0;
  for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) lit += texture(u_shadow_map, vec3(coord.xy + vec2(x, y) * texel, coord.z));
  return lit / 9.0;
}

void main() {
  vec3 normal = normalize(fs_in.normal);
  if (!gl_FrontFacing) normal = -normal;  // the terrain seen from below its edge

  // atmos's functions take planet-centred metres in the planet's axes; the
  // engine's world axes are the planet's axes (PlanetFrame has no rotation),
  // so this is a translation and a change of unit. Float precision here is
  // ~0.5 m at Earth's radius: plenty for irradiance, which varies over km.
  vec3 point = u_patch_centre_planet_m + fs_in.patch_position * u_metres_per_unit;
  // (x, z): east and south of the patch centre, which the noise needs only
  // locally consistent; metres.
  vec3 albedo = detailed_albedo(fs_in.albedo, fs_in.patch_position.xz * u_metres_per_unit);

  // Lambert: albedo / pi x (direct sun x shadow + sky light), with the
  // irradiance of the atmosphere's own sun through the atmosphere above
  // this point (lux-scaled sRGB), so the result is in cd/m².
  vec3 sky_irradiance;
  vec3 sun_irradiance = atmos_sun_and_sky_irradiance(point, normal, u_sun_direction, sky_irradiance);
#if ECLIPSE
  eclipse(point, sun_irradiance, sky_irradiance);
#endif
  float visibility = sun_visibility(fs_in.patch_position, normal);
  vec3 radiance = albedo / ENGINE_PI * (sun_irradiance * visibility + sky_irradiance);

  out_colour = vec4(radiance * u_units_per_nit, 1.0);
  out_albedo = vec4(albedo, 1.0);
  out_normal = vec4(normal, 0.0);
#if LOG_DEPTH
  // Logarithmic depth: log2(1 + w) / log2(1 + F), w the distance along the
  // view axis, as DepthEncoding::logarithmic expects. (Writing gl_FragDepth
  // disables early depth testing: the price of log depth, so only then.)
  gl_FragDepth = log2(1.0 + fs_in.view_depth) / log2(1.0 + u_log_depth_far);
#endif
}
