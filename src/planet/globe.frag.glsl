// The globe's fragment shader (src/planet/globe.cpp), appended to
// "#version 450 core" and AtmospherePass::glsl_library(): a Lambertian
// surface lit by the sun's light transmitted to the point's own altitude
// (zero in the planet's shadow) and by the sky's irradiance there, both from
// the atmosphere's tables (Bruneton & Neyret 2008, §4; Collienne 2013,
// §4.3.3). The colour written is radiance / nits_per_unit; the engine plugin
// then adds the aerial perspective in front of it.

in vec3 v_offset;
in vec3 v_normal;
in vec3 v_albedo;

uniform vec3 camera_planet;  // m, planet-centred
uniform vec3 sun_direction;  // unit, planet axes
uniform float light_scale;   // (sun illuminance / the atmosphere's own) / nits_per_unit

layout(location = 0) out vec4 colour;

void main() {
  vec3 point = camera_planet + v_offset;
  vec3 n = normalize(v_normal);
  vec3 sky_irradiance;
  vec3 sun_irradiance = atmos_sun_and_sky_irradiance(point, n, sun_direction, sky_irradiance);
  colour = vec4(v_albedo * (1.0 / 3.14159265358979) * (sun_irradiance + sky_irradiance) * light_scale, 1.0);
}
