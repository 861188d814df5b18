// Fills the sea's light maps (ocean_light_maps.glsl; src/planet/ocean.cpp),
// appended after "#version 450 core", AtmospherePass::glsl_library(),
// physics/water.glsl and ocean_light_maps.glsl. One draw per layer of the sky's map, one for the
// irradiances; each pixel evaluates the pass's own functions at a point of
// the sea-level sphere (the z axis here) for its texel's parameters, in
// the tables' channels.

layout(location = 0) out vec4 colour;

uniform int map;    // 0: the sky's radiance, 1: the irradiances, 2: the reflectance, 3: the light from below
uniform int layer;  // the sun's texel (the sky's map), the across deviation's (the reflectance's), the depth's (below)
uniform float sea_radius;  // R, m
uniform vec3 sea_refractive_index;
uniform WaterSpectrum sea_spectrum;  // the below map's water (ocean.frag.glsl)
uniform vec3 seabed_albedo;
uniform float deep_water_depth;  // m: H_deep

void main() {
  ivec2 texel = ivec2(gl_FragCoord.xy);
  vec3 point = vec3(0.0, 0.0, sea_radius);
  if (map == 0) {
    float phi = ocean_azimuth(ocean_map_parameter(texel.x, OCEAN_SKY_MAP_SIZE));
    float mu = max(ocean_elevation_cosine(ocean_map_parameter(texel.y, OCEAN_SKY_MAP_SIZE)), kOceanLeastSkyCosine);
    float mu_s = ocean_sun_cosine(ocean_map_parameter(layer, OCEAN_SKY_MAP_SIZE));
    float sin_v = sqrt(max(1.0 - mu * mu, 0.0));
    vec3 view = vec3(sin_v * cos(phi), sin_v * sin(phi), mu);
    vec3 sun = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    colour = vec4(log(max(ocean_sky_radiance(point, view, sun), vec3(kOceanLeastRadiance))), 1.0);
  } else if (map == 2) {
    float mu_v = ocean_elevation_cosine(ocean_map_parameter(texel.x, OCEAN_REFLECTANCE_MAP_SIZE));
    float sigma_along = ocean_deviation(ocean_map_parameter(texel.y, OCEAN_REFLECTANCE_MAP_SIZE));
    float sigma_across = ocean_deviation(ocean_map_parameter(layer, OCEAN_REFLECTANCE_MAP_SIZE));
    WaterParams water;
    water.refractive_index = sea_refractive_index;
    water.absorption = vec3(0.0);
    water.backscattering = vec3(0.0);
    water.diffuse_reflectance = vec3(0.0);
    water.slope_variance = vec2(sigma_along * sigma_along, sigma_across * sigma_across);
    vec3 mean_direction;
    vec3 reflectance = water_sky_reflectance(water, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0),
                                             vec3(sqrt(max(1.0 - mu_v * mu_v, 0.0)), 0.0, mu_v), mean_direction);
    colour = vec4(reflectance, mean_direction.z);
  } else if (map == 3) {
    float mu_v = ocean_elevation_cosine(ocean_map_parameter(texel.x, OCEAN_BELOW_MAP_WIDTH));
    float mu_s = ocean_sun_cosine(ocean_map_parameter(texel.y, OCEAN_BELOW_MAP_HEIGHT));
    vec3 view = vec3(sqrt(max(1.0 - mu_v * mu_v, 0.0)), 0.0, mu_v);
    vec3 sun = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    vec3 sun_irradiance[SPECTRAL_SET_CAPACITY];
    vec3 sun_channels = vec3(0.0);
    for (int k = 0; k < SPECTRAL_SET_CAPACITY; ++k) {
      sun_irradiance[k] = ocean_set_sun_irradiance(k, point, sun);
      sun_channels += sea_spectrum.to_channels[k] * sun_irradiance[k];
    }
    vec3 sky_irradiance = ocean_sky_irradiance(point, sun);
    vec3 glint;
    vec3 below = water_spectral_radiance(sea_spectrum, sun_irradiance, sky_irradiance, 0.0, 1.0, vec3(0.0, 0.0, 1.0),
                                         view, sun,
                                         ocean_depth(ocean_map_parameter(layer, OCEAN_BELOW_MAP_DEPTH), deep_water_depth),
                                         seabed_albedo, glint);
    vec3 downwelling = sun_channels * max(mu_s, 0.0) + sky_irradiance;
    colour = vec4(below / max(downwelling, vec3(kOceanLeastRadiance)), 1.0);
  } else {
    float mu_s = ocean_sun_cosine(ocean_map_parameter(texel.x, OCEAN_LIGHT_MAP_SIZE));
    vec3 sun = vec3(sqrt(max(1.0 - mu_s * mu_s, 0.0)), 0.0, mu_s);
    vec3 irradiance = texel.y == 0 ? ocean_sky_irradiance(point, sun) : ocean_set_sun_irradiance(texel.y - 1, point, sun);
    colour = vec4(log(max(irradiance, vec3(kOceanLeastRadiance))), 1.0);
  }
}
