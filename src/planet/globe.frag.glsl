// The globe's fragment shader (src/planet/globe.cpp): the radiance lit per
// vertex (globe.vert.glsl), interpolated, divided by nits_per_unit.
//
// ATMOS_GLOBE_SHADOWS: the sun's part times the terrain's visibility of the
// sun at this pixel, from the cascaded shadow maps (Dimitrov 2007; the
// cascades in src/planet/globe_shadows.hpp), plus the sky's part, which the
// terrain's shadows leave as it is. ATMOS_GLOBE_ECLIPSE (with or without
// shadows; appended after AtmospherePass::glsl_library()): the sun's part
// and the sky's part times the factors of the moons at the pixel's point
// (atmos_eclipse: the fraction of the limb-darkened sun they leave it, and
// the documented approximation for the diffuse light), the factors the
// pass applies to the G-buffer surfaces it lights; per pixel, as the umbra
// can be narrower than the vertices' spacing seen from afar.
// ATMOS_GLOBE_DEPTH_ONLY: nothing but the depth the rasteriser writes (the
// shadow maps).

#if defined(ATMOS_GLOBE_DEPTH_ONLY)

void main() {}

#elif defined(ATMOS_GLOBE_SHADOWS) || defined(ATMOS_GLOBE_ECLIPSE)

in vec3 v_sun_radiance;
in vec3 v_sky_radiance;
in vec3 v_offset;  // m, from the camera

layout(location = 0) out vec4 colour;

uniform vec3 sun_direction;  // unit, planet axes

#if defined(ATMOS_GLOBE_ECLIPSE)
uniform vec3 camera_planet;                   // m, planet-centred
uniform int moon_count;                       // 1..MOON_CAPACITY (this variant draws eclipses only)
uniform vec4 moon_spheres[MOON_CAPACITY];     // xyz: centre (m, planet-centred), w: radius (m)
#endif

#if defined(ATMOS_GLOBE_SHADOWS)
in vec3 v_normal;

const int kMaxCascades = 4;
// The shadow maps' depth, one layer per cascade, standard depth (0 towards
// the sun); compared with GL_LEQUAL and filtered bilinearly by the sampler.
uniform sampler2DArrayShadow shadow_maps;
uniform int cascade_count;
uniform mat4 light_clip_from_offset[kMaxCascades];  // camera-relative m -> the cascade's clip space
uniform float cascade_far[kMaxCascades];            // view depth where the cascade ends, m
uniform float cascade_blend[kMaxCascades];          // view depth where it starts handing over, m
uniform float cascade_texel[kMaxCascades];          // its texel's side, m
uniform float cascade_depth_per_m[kMaxCascades];    // window depth per metre along the sun
uniform vec3 view_forward;                          // unit, planet axes: view depth = dot(offset, view_forward)

// The lookup's offset from the surface, in texels of the cascade: along the
// normal, kNormalOffset sin(theta) (theta between the normal and the sun),
// and towards the sun, kDepthBias (a slope-scaled bias, Holbert 2011: a
// surface tilted by theta from the sun's direction changes depth by
// w tan(theta) over w texels; moved by d along its normal, a point rises
// d / cos(theta) above it along the sun, which clears the surface over the
// filter's reach w if d >= w sin(theta)). The 4-tap filter below reads
// texels up to 1.5 texels away along each axis (2.1 diagonally).
const float kNormalOffset = 2.5;
const float kDepthBias = 1.0;

// The sun's visibility from cascade i: percentage-closer filtering (Reeves,
// Salesin & Cook 1987) with four bilinear depth comparisons half a texel
// apart, 16 texels weighted as a 3 x 3-texel tent.
float cascade_visibility(int i, vec3 offset, vec3 n, float sin_theta) {
  float texel = cascade_texel[i];
  vec4 p = light_clip_from_offset[i] * vec4(offset + n * (kNormalOffset * texel * sin_theta), 1.0);
  vec3 m = 0.5 * p.xyz + 0.5;
  float reference = m.z - kDepthBias * texel * cascade_depth_per_m[i];
  float half_texel = 0.5 / float(textureSize(shadow_maps, 0).x);
  float layer = float(i);
  float lit = texture(shadow_maps, vec4(m.x - half_texel, m.y - half_texel, layer, reference)) +
              texture(shadow_maps, vec4(m.x + half_texel, m.y - half_texel, layer, reference)) +
              texture(shadow_maps, vec4(m.x - half_texel, m.y + half_texel, layer, reference)) +
              texture(shadow_maps, vec4(m.x + half_texel, m.y + half_texel, layer, reference));
  return 0.25 * lit;
}

// The terrain's visibility of the sun at this pixel.
float terrain_sun_visibility() {
  float visibility = 1.0;
  if (any(greaterThan(v_sun_radiance, vec3(0.0)))) {
    float depth = dot(v_offset, view_forward);
    int i = 0;
    while (i < cascade_count && depth >= cascade_far[i]) ++i;
    if (i < cascade_count) {
      vec3 n = normalize(v_normal);
      float cos_theta = clamp(dot(n, sun_direction), 0.0, 1.0);
      float sin_theta = sqrt(1.0 - cos_theta * cos_theta);
      visibility = cascade_visibility(i, v_offset, n, sin_theta);
      // Over the last part of its range the cascade hands over to the next
      // one, the last to full sunlight at the shadow distance.
      if (depth > cascade_blend[i]) {
        float w = (depth - cascade_blend[i]) / (cascade_far[i] - cascade_blend[i]);
        float next = i + 1 < cascade_count ? cascade_visibility(i + 1, v_offset, n, sin_theta) : 1.0;
        visibility = mix(visibility, next, w);
      }
    }
  }
  return visibility;
}
#endif

void main() {
  vec3 sun = v_sun_radiance;
  vec3 sky = v_sky_radiance;
#if defined(ATMOS_GLOBE_SHADOWS)
  sun *= terrain_sun_visibility();
#endif
#if defined(ATMOS_GLOBE_ECLIPSE)
  float sun_factor, sky_factor;
  atmos_eclipse(camera_planet + v_offset, sun_direction, moon_count, moon_spheres, sun_factor, sky_factor);
  sun *= sun_factor;
  sky *= sky_factor;
#endif
  colour = vec4(max(sun + sky, vec3(0.0)), 1.0);
}

#else

in vec3 v_radiance;

layout(location = 0) out vec4 colour;

void main() { colour = vec4(max(v_radiance, vec3(0.0)), 1.0); }

#endif
