// The sea on the globe (include/atmos/ocean.hpp): the water's parameters at
// the channels' wavelengths, the wave spectrum, the bathymetry cube map and
// the drawing.
#include "atmos/ocean.hpp"

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat4x4.hpp>
#include <numbers>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <atomic>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "planet/gl_program.hpp"
#include "planet/ocean_internal.hpp"
#include "planet/raster_source.hpp"
#include "planet/surface.hpp"

namespace atmos {

namespace {

constexpr double kGravity = 9.81;  // m s^-2, the waves' dispersion ω² = g k (deep water)
constexpr int kMaxWaves = 32;      // OCEAN_MAX_WAVES of ocean_waves.glsl
constexpr int kSkyMapSize = 64;    // OCEAN_SKY_MAP_SIZE of ocean_light_maps.glsl
constexpr int kLightMapSize = 512; // OCEAN_LIGHT_MAP_SIZE
constexpr int kReflectanceMapSize = 32;  // OCEAN_REFLECTANCE_MAP_SIZE
constexpr int kBelowMapWidth = 64, kBelowMapHeight = 257, kBelowMapDepth = 32;  // OCEAN_BELOW_MAP_WIDTH, ...

// The sea's shaders loop over the working wavelengths' triples to the
// pass's count, a constant of its GLSL library (water.glsl, WATER_SET_COUNT).
constexpr const char* kConstantSetCount = "#define WATER_SET_COUNT(w) SPECTRAL_SET_CAPACITY\n";

// set_ocean_terms (ocean_internal.hpp).
std::atomic<unsigned> terms_drawn{planet::kOceanAllTerms};

// The waves of a wind of speed U (m/s) whose slope variance along and
// across the wind stays within `budget` (Cox & Munk's; the waves take at
// most 80 % of each, the rest is the BRDF's at every distance).
//
// Heights: the Pierson & Moskowitz 1964 spectrum of a fully developed sea,
// S(ω) = α g² ω⁻⁵ exp(−β (ω₀ / ω)⁴), α = 8.1e-3, β = 0.74, ω₀ = g / U
// (U taken at 12.5 m rather than their 19.5 m: 3 % apart in a neutral
// log profile), peaking at ω_p = (4β/5)^¼ ω₀ = 0.877 g / U. kMaxWaves
// bands spaced evenly in log ω from 0.75 ω_p to the frequency of 0.1 m
// waves, each a sine of amplitude a = √(2 S(ω) Δω) (its height variance
// a²/2 is the band's) at the band's geometric centre, k = ω² / g. The slope
// variance of a wave is ½ a² k²; the slope spectrum k² S(ω) =
// α ω⁻¹ e^{−β (ω₀/ω)⁴} falls off slowly, so the waves down to 0.1 m carry
// about α ln(ω_max / ω_p): 0.023 at 7 m/s, of Cox & Munk's 0.038; the
// capillary waves below 0.1 m are the BRDF's.
// The waves are in increasing frequency, hence wavenumber (the shader stops
// at the first one a pixel filters out). Directions: the cos² spreading about the wind (Longuet-Higgins et al.
// 1963's cos^2s with s = 1), each band's angle from the spreading's
// inverse distribution at a golden-ratio sequence, on alternate sides.
std::vector<planet::OceanWave> make_waves(double wind_speed, glm::dvec2 budget) {
  std::vector<planet::OceanWave> waves;
  if (!(wind_speed > 0.5)) return waves;  // calm: the slopes are all the BRDF's
  const double omega_0 = kGravity / wind_speed;
  const double omega_p = std::pow(0.8 * 0.74, 0.25) * omega_0;
  const double omega_lo = 0.75 * omega_p, omega_hi = std::sqrt(kGravity * 2.0 * std::numbers::pi / 0.1);
  const double step = std::log(omega_hi / omega_lo) / kMaxWaves;
  glm::dvec2 variance(0.0);
  for (int i = 0; i < kMaxWaves; ++i) {
    const double lo = omega_lo * std::exp(step * i), hi = omega_lo * std::exp(step * (i + 1));
    const double omega = std::sqrt(lo * hi);
    const double s = 8.1e-3 * kGravity * kGravity * std::pow(omega, -5.0) * std::exp(-0.74 * std::pow(omega_0 / omega, 4.0));
    planet::OceanWave w;
    w.omega = omega;
    w.k = omega * omega / kGravity;
    w.amplitude = std::sqrt(2.0 * s * (hi - lo));
    // cos² spreading on [-π/2, π/2]: F(θ) = (θ + π/2 + sin(2θ)/2) / π, inverted by bisection.
    const double u = std::fmod(0.5 + 0.6180339887498949 * i, 1.0);
    double a = -0.5 * std::numbers::pi, b = 0.5 * std::numbers::pi;
    for (int it = 0; it < 50; ++it) {
      const double m = 0.5 * (a + b);
      ((m + 0.5 * std::numbers::pi + 0.5 * std::sin(2.0 * m)) / std::numbers::pi < u ? a : b) = m;
    }
    w.angle = 0.5 * (a + b) * (i % 2 == 0 ? 1.0 : -1.0);
    w.phase = 2.0 * std::numbers::pi * std::fmod(0.3 + 0.7548776662466927 * i, 1.0);
    const double slope = 0.5 * w.amplitude * w.amplitude * w.k * w.k;
    variance += slope * glm::dvec2(std::cos(w.angle) * std::cos(w.angle), std::sin(w.angle) * std::sin(w.angle));
    waves.push_back(w);
  }
  const double scale = std::min({1.0, 0.8 * budget.x / variance.x, 0.8 * budget.y / variance.y});
  for (planet::OceanWave& w : waves) w.amplitude *= std::sqrt(scale);
  return waves;
}

// The unit direction of texel (i, j) of cube-map face `face` (OpenGL's
// cube-map layout: the face's major axis and its s, t axes).
glm::dvec3 cube_direction(int face, int i, int j, int n) {
  const double s = 2.0 * (i + 0.5) / n - 1.0, t = 2.0 * (j + 0.5) / n - 1.0;
  glm::dvec3 d;
  switch (face) {
    case 0: d = {1.0, -t, -s}; break;
    case 1: d = {-1.0, -t, s}; break;
    case 2: d = {s, 1.0, t}; break;
    case 3: d = {s, -1.0, -t}; break;
    case 4: d = {s, -t, 1.0}; break;
    default: d = {-s, -t, -1.0}; break;
  }
  return glm::normalize(d);
}

struct OceanProgram {
  GLuint id = 0;
  GLint clip = -1, inverse = -1, viewport = -1, camera = -1, up = -1, radius = -1, height_term = -1,
        pixel_angle = -1, sun = -1, light = -1, refractive = -1, absorption = -1, backscattering = -1,
        diffuse = -1, slope_variance = -1, upwind = -1, wave_count = -1, wave_vector = -1, wave_in_wind = -1,
        wave_phase = -1, sea_radius = -1, waves_can_displace = -1,
        bathymetry = -1, sky_map = -1, light_map = -1, reflectance_map = -1, below_map = -1, deep = -1, sea_level = -1, seabed = -1, moon_count = -1,
        moon_spheres = -1, terms = -1, lakes = -1, eclipse_top_radius = -1, star_count = -1, star_directions = -1,
        star_irradiances = -1;
  void locate() {
    const auto at = [&](const char* name) { return glGetUniformLocation(id, name); };
    clip = at("clip_from_offset");
    inverse = at("offset_from_clip");
    viewport = at("viewport_size");
    camera = at("camera_planet");
    up = at("camera_up");
    radius = at("camera_radius");
    height_term = at("camera_height_term");
    pixel_angle = at("pixel_angle");
    sun = at("sun_direction");
    light = at("light_scale");
    refractive = at("sea_refractive_index");
    absorption = at("sea_absorption");
    backscattering = at("sea_backscattering");
    diffuse = at("sea_diffuse_reflectance");
    slope_variance = at("sea_slope_variance");
    upwind = at("wind_upwind");
    wave_count = at("wave_count");
    wave_vector = at("wave_vector");
    wave_in_wind = at("wave_in_wind");
    wave_phase = at("wave_phase");
    sea_radius = at("sea_radius");
    waves_can_displace = at("waves_can_displace");
    bathymetry = at("bathymetry");
    sky_map = at("sky_map");
    light_map = at("light_map");
    reflectance_map = at("reflectance_map");
    below_map = at("below_map");
    deep = at("deep_water_depth");
    sea_level = at("sea_level");
    seabed = at("seabed_albedo");
    moon_count = at("moon_count");
    moon_spheres = at("moon_spheres");
    terms = at("terms");
    lakes = at("lakes");
    eclipse_top_radius = at("eclipse_top_radius");
    star_count = at("star_count");
    star_directions = at("star_directions");
    star_irradiances = at("star_irradiances");
  }
};

// The water at every working wavelength (water.glsl, WaterSpectrum) into
// `program`'s uniform sea_spectrum.
void set_water_spectrum(GLuint program, const WaterTriples& spectrum) {
  const auto at = [&](const std::string& name) { return glGetUniformLocation(program, ("sea_spectrum." + name).c_str()); };
  const auto vector = [&](const std::string& name, const glm::dvec3& v) {
    glProgramUniform3f(program, at(name), float(v.x), float(v.y), float(v.z));
  };
  const int count = int(spectrum.optics.size());
  glProgramUniform1i(program, at("count"), count);
  for (int k = 0; k < count; ++k) {
    const std::string i = "[" + std::to_string(k) + "]";
    const WaterOptics& w = spectrum.optics[size_t(k)];
    vector("set" + i + ".refractive_index", w.refractive_index);
    vector("set" + i + ".absorption", w.absorption_per_m);
    vector("set" + i + ".backscattering", w.backscattering_per_m);
    vector("set" + i + ".diffuse_reflectance", w.diffuse_reflectance);
    glProgramUniform2f(program, at("set" + i + ".slope_variance"), float(w.slope_variance.x),
                       float(w.slope_variance.y));
    vector("solar_irradiance" + i, spectrum.solar_irradiance[size_t(k)]);
    const glm::mat3 to(spectrum.to_channels[size_t(k)]), from(spectrum.from_channels[size_t(k)]);
    glProgramUniformMatrix3fv(program, at("to_channels" + i), 1, GL_FALSE, glm::value_ptr(to));
    glProgramUniformMatrix3fv(program, at("from_channels" + i), 1, GL_FALSE, glm::value_ptr(from));
  }
}

// H_deep (ocean_light_maps.glsl): the depth beyond which e^{−2 κ H} < 1e-5
// at every working wavelength, κ = a + b_b.
double deep_water_depth(const WaterTriples& spectrum) {
  double kappa = std::numeric_limits<double>::infinity();
  for (const WaterOptics& w : spectrum.optics)
    for (int c = 0; c < 3; ++c) kappa = std::min(kappa, w.absorption_per_m[c] + w.backscattering_per_m[c]);
  return std::log(1e5) / (2.0 * kappa);
}

void require_range(double value, double lo, double hi, const char* name) {
  if (!(value >= lo && value <= hi))
    throw Error(std::string("ocean settings: ") + name + " must be in [" + std::to_string(lo) + ", " +
                std::to_string(hi) + "], not " + std::to_string(value));
}

}  // namespace

namespace planet {
void set_ocean_terms(unsigned mask) { terms_drawn.store(mask, std::memory_order_relaxed); }

std::vector<OceanWave> make_ocean_waves(double wind_speed_m_s, glm::dvec2 slope_variance) {
  return make_waves(wind_speed_m_s, slope_variance);
}

void ocean_wind_axes(const glm::dvec3& nadir, double wind_azimuth_deg, glm::dvec3& upwind, glm::dvec3& crosswind) {
  glm::dvec3 east = glm::cross(glm::dvec3(0.0, 0.0, 1.0), nadir);
  if (glm::length(east) < 1e-6) east = glm::cross(glm::dvec3(0.0, 1.0, 0.0), nadir);
  east = glm::normalize(east);
  const glm::dvec3 north = glm::cross(nadir, east);
  const double azimuth = wind_azimuth_deg * std::numbers::pi / 180.0;
  upwind = std::cos(azimuth) * north + std::sin(azimuth) * east;
  crosswind = glm::cross(nadir, upwind);
}

void set_ocean_wave_uniforms(const std::vector<OceanWave>& waves, const glm::dvec3& upwind,
                             const glm::dvec3& crosswind, const glm::dvec3& camera_m, double time_s,
                             OceanWaveField& field) {
  field.wave_count = int(std::min(waves.size(), size_t(OceanWaveField::kMaxWaves)));
  for (size_t i = 0; i < size_t(field.wave_count); ++i) {
    const OceanWave& w = waves[i];
    const glm::dvec3 k = w.k * (std::cos(w.angle) * upwind + std::sin(w.angle) * crosswind);
    field.wave_vector[i] = glm::dvec4(k, w.amplitude);
    field.wave_in_wind[i] = glm::dvec4(w.k * std::cos(w.angle), w.k * std::sin(w.angle), w.k, w.amplitude);
    const double phase = glm::dot(k, camera_m) + w.phase - w.omega * time_s;
    field.wave_phase[i] = phase - 2.0 * std::numbers::pi * std::floor(phase / (2.0 * std::numbers::pi));
  }
}
}  // namespace planet

// The water levels an ocean draws: the sea, and the lakes of the surface's
// lake mask.
enum Level { kSea = 0, kLakes = 1, kLevels = 2 };

struct Ocean::Impl {
  const AtmospherePass* pass = nullptr;
  OceanSettings settings;
  bool has_sea = false, has_lakes = false;
  double sea_level_m = std::numeric_limits<double>::quiet_NaN();
  double lake_level_m = std::numeric_limits<double>::quiet_NaN();
  double sea_radius_m = 0.0, top_radius_m = 0.0, sun_angular_radius_rad = 0.0;
  // Per level: the water's height above the datum (m) and its sphere's radius (m).
  std::array<double, kLevels> level_height_m{}, level_radius_m{};
  std::unique_ptr<planet::Surface> surface;
  std::unique_ptr<planet::RasterSource> lake_mask;
  WaterOptics water;
  // The water at every working wavelength, in the atmosphere's triples.
  WaterTriples spectrum;
  std::vector<planet::OceanWave> waves;
  // The waves' anchor: the unit direction of the sea below the camera where
  // the wind's frame was last set, and that frame (upwind, crosswind).
  bool anchored = false;
  glm::dvec3 anchor{0.0}, upwind{0.0}, crosswind{0.0};
  // The programs (the sky quadrature or the mean direction, as the
  // settings say), by variant: + 1 with moons (their light on the water),
  // + 2 with moons that eclipse, + 4 the tests' program without the light
  // maps (kOceanDirectLight), + 8 with stars (set_stars). The first linked
  // at construction, the others at their first draw.
  std::array<OceanProgram, 16> programs{};
  // The tables' working wavelengths (the stars' channel irradiances), and
  // the mirrored stars: unit directions in the world's axes and their
  // irradiance in the tables' channels above the atmosphere.
  std::vector<double> wavelengths_nm;
  std::vector<glm::vec4> star_directions, star_irradiances;
  GLuint vertex_array = 0, bathymetry = 0;
  // The light maps (ocean_light_maps.glsl; the sky's and the irradiances'
  // per level, at its radius), the program that fills them and the pass's
  // ground albedo they were filled with (the tables follow it).
  std::array<GLuint, kLevels> sky_map{}, light_map{}, below_map{};
  GLuint reflectance_map = 0, map_program = 0, map_framebuffer = 0;
  glm::dvec3 maps_albedo{-1.0};

  ~Impl() {
    for (const OceanProgram& q : programs)
      if (q.id != 0) glDeleteProgram(q.id);
    if (map_program != 0) glDeleteProgram(map_program);
    if (map_framebuffer != 0) glDeleteFramebuffers(1, &map_framebuffer);
    if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
    const GLuint textures[] = {bathymetry, sky_map[kSea], light_map[kSea], below_map[kSea], sky_map[kLakes],
                               light_map[kLakes], below_map[kLakes],
                               reflectance_map};
    for (GLuint t : textures)
      if (t != 0) glDeleteTextures(1, &t);
  }

  OceanProgram link(bool moons, bool eclipse, bool direct_light, bool stars) const {
    std::string head = "#version 450 core\n";
    if (stars) head += "#define OCEAN_STARS 1\n";
    if (moons || eclipse) head += "#define OCEAN_MOONS 1\n";
    if (eclipse) head += "#define OCEAN_ECLIPSE 1\n";
    if (direct_light) head += "#define OCEAN_DIRECT_LIGHT 1\n";
    if (!settings.sky_quadrature) head += "#define OCEAN_SKY_MEAN_DIRECTION 1\n";
    head += kConstantSetCount;
    OceanProgram p;
    p.id = planet::link_program(
        "ocean", std::string("#version 450 core\n") + planet::shader_text("ocean", "src/planet/ocean.vert.glsl"),
        head + pass->glsl_library(settings.first_unit) + "\n" + planet::shader_text("ocean", "src/physics/water.glsl") +
            "\n" + planet::shader_text("ocean", "src/planet/ocean_light_maps.glsl") + "\n" +
            planet::shader_text("ocean", "src/planet/ocean_waves.glsl") + "\n" +
            planet::shader_text("ocean", "src/planet/ocean.frag.glsl"));
    p.locate();
    glProgramUniform1i(p.id, p.bathymetry, settings.first_unit + 5);
    glProgramUniform1i(p.id, p.sky_map, settings.first_unit + 6);
    glProgramUniform1i(p.id, p.light_map, settings.first_unit + 7);
    glProgramUniform1i(p.id, p.reflectance_map, settings.first_unit + 8);
    glProgramUniform1i(p.id, p.below_map, settings.first_unit + 9);
    // The water at every working wavelength: constant for the ocean.
    set_water_spectrum(p.id, spectrum);
    glProgramUniform1f(p.id, p.deep, float(deep_water_depth(spectrum)));
    return p;
  }

  // Draws map `map` of the filling program (bound) into `texture`, `layers`
  // layers of width x height (0: a 2D texture).
  void fill_map(int map, GLuint texture, int width, int height, int layers) const {
    glUniform1i(glGetUniformLocation(map_program, "map"), map);
    const GLint layer = glGetUniformLocation(map_program, "layer");
    glViewport(0, 0, width, height);
    for (int z = 0; z < std::max(layers, 1); ++z) {
      if (layers > 0)
        glNamedFramebufferTextureLayer(map_framebuffer, GL_COLOR_ATTACHMENT0, texture, 0, z);
      else
        glNamedFramebufferTexture(map_framebuffer, GL_COLOR_ATTACHMENT0, texture, 0);
      glUniform1i(layer, z);
      glDrawArrays(GL_TRIANGLES, 0, 3);
    }
  }

  bool present(int level) const { return level == kSea ? has_sea : has_lakes; }

  // Fills the light maps from the pass's tables (ocean_light_maps.frag.glsl):
  // per level drawn, 64 layers of 64 x 64 of the sky's radiance and 512 x
  // (1 + triples) irradiances (the sky's, the sun's per triple of working
  // wavelengths) and 64 x 257 x 32 of the light from below, 0.8 million
  // evaluations of the pass's functions, once (and
  // again when the pass's ground albedo, hence its tables, changes).
  // Restores the draw framebuffer binding and the viewport.
  void fill_light_maps() {
    maps_albedo = pass->ground_albedo();
    const bool first = map_program == 0;
    if (first) {
      map_program = planet::link_program(
          "ocean", std::string("#version 450 core\n") + planet::shader_text("ocean", "src/planet/ocean.vert.glsl"),
          std::string("#version 450 core\n") + kConstantSetCount + pass->glsl_library(settings.first_unit) + "\n" +
              planet::shader_text("ocean", "src/physics/water.glsl") + "\n" +
              planet::shader_text("ocean", "src/planet/ocean_light_maps.glsl") + "\n" +
              planet::shader_text("ocean", "src/planet/ocean_light_maps.frag.glsl"));
      std::vector<GLuint> maps;
      for (int level = 0; level < kLevels; ++level) {
        if (!present(level)) continue;
        glCreateTextures(GL_TEXTURE_3D, 1, &sky_map[size_t(level)]);
        glTextureStorage3D(sky_map[size_t(level)], 1, GL_RGBA32F, kSkyMapSize, kSkyMapSize, kSkyMapSize);
        glCreateTextures(GL_TEXTURE_2D, 1, &light_map[size_t(level)]);
        glTextureStorage2D(light_map[size_t(level)], 1, GL_RGBA32F, kLightMapSize, 1 + int(spectrum.optics.size()));
        glCreateTextures(GL_TEXTURE_3D, 1, &below_map[size_t(level)]);
        glTextureStorage3D(below_map[size_t(level)], 1, GL_RGBA32F, kBelowMapWidth, kBelowMapHeight, kBelowMapDepth);
        maps.insert(maps.end(), {sky_map[size_t(level)], light_map[size_t(level)], below_map[size_t(level)]});
      }
      glCreateTextures(GL_TEXTURE_3D, 1, &reflectance_map);
      glTextureStorage3D(reflectance_map, 1, GL_RGBA32F, kReflectanceMapSize, kReflectanceMapSize,
                         kReflectanceMapSize);
      maps.push_back(reflectance_map);
      for (GLuint t : maps) {
        glTextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
        glTextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
        glTextureParameteri(t, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
        glTextureParameteri(t, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
        glTextureParameteri(t, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
      }
      glCreateFramebuffers(1, &map_framebuffer);
      set_water_spectrum(map_program, spectrum);
      glProgramUniform3f(map_program, glGetUniformLocation(map_program, "seabed_albedo"),
                         float(settings.seabed_albedo.x), float(settings.seabed_albedo.y),
                         float(settings.seabed_albedo.z));
      glProgramUniform1f(map_program, glGetUniformLocation(map_program, "deep_water_depth"),
                         float(deep_water_depth(spectrum)));
    }
    GLint framebuffer = 0, viewport[4] = {0, 0, 0, 0};
    glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &framebuffer);
    glGetIntegerv(GL_VIEWPORT, viewport);
    glUseProgram(map_program);
    glBindVertexArray(vertex_array);
    pass->bind_textures(settings.first_unit);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, map_framebuffer);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_BLEND);
    glDisable(GL_SCISSOR_TEST);
    const glm::vec3 n(water.refractive_index);
    glUniform3f(glGetUniformLocation(map_program, "sea_refractive_index"), n.x, n.y, n.z);
    // The reflectance depends on the water alone: filled once.
    if (first) fill_map(2, reflectance_map, kReflectanceMapSize, kReflectanceMapSize, kReflectanceMapSize);
    for (int level = 0; level < kLevels; ++level) {
      if (!present(level)) continue;
      glUniform1f(glGetUniformLocation(map_program, "sea_radius"), float(level_radius_m[size_t(level)]));
      fill_map(0, sky_map[size_t(level)], kSkyMapSize, kSkyMapSize, kSkyMapSize);
      fill_map(1, light_map[size_t(level)], kLightMapSize, 1 + int(spectrum.optics.size()), 0);
      fill_map(3, below_map[size_t(level)], kBelowMapWidth, kBelowMapHeight, kBelowMapDepth);
    }
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(framebuffer));
    glViewport(viewport[0], viewport[1], viewport[2], viewport[3]);
    glBindVertexArray(0);
  }

  // The ground's height (r), its least over the texel and its 8
  // neighbours on the face (g) and the lake mask (b: 1 lake, 0 not; the
  // mask's fraction of lake pixels around the texel's centre), for every
  // texel of the six faces.
  void bake_bathymetry() {
    const int n = settings.bathymetry_texels;
    std::vector<float> height(size_t(6) * size_t(n) * size_t(n)), lake(height.size(), 0.0f);
    tbb::parallel_for(0, 6 * n, [&](int row) {
      const int face = row / n, j = row % n;
      for (int i = 0; i < n; ++i)
        height[(size_t(face) * n + size_t(j)) * n + size_t(i)] =
            float(surface->ground_height_m(cube_direction(face, i, j, n)));
    });
    if (lake_mask) {
      // The texels' spacing on the lakes' sphere: a face spans 90 degrees.
      const double spacing = 0.5 * std::numbers::pi / n * level_radius_m[kLakes];
      std::vector<glm::dvec3> directions(static_cast<size_t>(n));
      std::vector<std::uint8_t> valid(static_cast<size_t>(n));
      for (int row = 0; row < 6 * n; ++row) {
        const int face = row / n, j = row % n;
        for (int i = 0; i < n; ++i) directions[size_t(i)] = cube_direction(face, i, j, n);
        float* out = &lake[(size_t(face) * n + size_t(j)) * n];
        lake_mask->sample(directions.data(), size_t(n), spacing, level_radius_m[kLakes], out, valid.data());
      }
    }
    glCreateTextures(GL_TEXTURE_CUBE_MAP, 1, &bathymetry);
    // Without lakes the mask's channel is left out (RG32F: half the bytes
    // the sea's one fetch per pixel reads; its b then reads 0, no lake).
    const size_t channels = lake_mask ? 3 : 2;
    glTextureStorage2D(bathymetry, 1, lake_mask ? GL_RGB32F : GL_RG32F, n, n);
    std::vector<float> texels(channels * n * n);
    for (int face = 0; face < 6; ++face) {
      const float* h = &height[size_t(face) * n * n];
      for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
          float least = h[size_t(j) * n + size_t(i)];
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              const int a = std::clamp(i + di, 0, n - 1), b = std::clamp(j + dj, 0, n - 1);
              least = std::min(least, h[size_t(b) * n + size_t(a)]);
            }
          float* t = &texels[channels * (size_t(j) * n + size_t(i))];
          t[0] = h[size_t(j) * n + size_t(i)];
          t[1] = least;
          if (lake_mask) t[2] = lake[(size_t(face) * n + size_t(j)) * n + size_t(i)];
        }
      glTextureSubImage3D(bathymetry, 0, 0, 0, face, n, n, 1, lake_mask ? GL_RGB : GL_RG, GL_FLOAT, texels.data());
    }
    glTextureParameteri(bathymetry, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(bathymetry, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(bathymetry, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(bathymetry, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }

  // Sets the wind's frame at `nadir` when the sea below the camera has
  // moved more than 0.5 degrees (55 km on Earth) from the anchor: the waves
  // stay fixed in the world while the camera moves less than that, and
  // change by one step when it moves farther (where the waves are smaller
  // than the pixels but for cameras near the sea flying that far).
  void anchor_at(const glm::dvec3& nadir) {
    if (anchored && glm::dot(nadir, anchor) > std::cos(0.5 * std::numbers::pi / 180.0)) return;
    anchored = true;
    anchor = nadir;
    planet::ocean_wind_axes(nadir, settings.wind_azimuth_deg, upwind, crosswind);
  }
};

Ocean::Ocean(const Atmosphere& atmosphere, const PlanetSurface& surface, const AtmospherePass& pass,
             const OceanSettings& settings) {
  if (epoxy_gl_version() < 45) throw Error("ocean: needs a current OpenGL 4.5 core context");
  WaterOptics optics;
  try {
    optics = water_optics(settings.water, atmosphere);
  } catch (const Error& e) {
    throw Error(std::string("ocean settings: ") + e.what());
  }
  for (int c = 0; c < 3; ++c)
    if (!(settings.seabed_albedo[c] >= 0.0 && settings.seabed_albedo[c] <= 1.0))
      throw Error("ocean settings: seabed_albedo must be in [0, 1] in every channel");
  require_range(settings.wind_azimuth_deg, -360.0, 360.0, "wind_azimuth_deg");
  if (settings.bathymetry_texels < 16 || settings.bathymetry_texels > 2048)
    throw Error("ocean settings: bathymetry_texels must be in 16..2048, not " +
                std::to_string(settings.bathymetry_texels));
  if (settings.first_unit < 0) throw Error("ocean settings: first_unit must be a texture unit (>= 0)");
  planet::validate_sea_level(surface, atmosphere, "ocean");
  const double sea = planet::sea_level_of(surface);
  const bool lakes = !surface.lake_mask.source.empty() || surface.lake_level_m.has_value();
  if (lakes) {
    if (surface.lake_mask.source.empty() || !surface.lake_level_m)
      throw Error("ocean: the surface's lakes need both a lake mask and a lake level");
    const double level = *surface.lake_level_m;
    if (!(std::isfinite(level) && level > -atmosphere.bottom_radius_m &&
          level < atmosphere.top_radius_m - atmosphere.bottom_radius_m))
      throw Error("ocean: the lake level " + std::to_string(level) +
                  " m must lie between the planet's centre and the top of the atmosphere");
    if (std::isfinite(sea) && !(level > sea))
      throw Error("ocean: the lake level " + std::to_string(level) + " m is not above the sea level " +
                  std::to_string(sea) + " m, which covers all ground below it");
  }

  impl_ = std::make_unique<Impl>();
  Impl& p = *impl_;
  p.pass = &pass;
  p.settings = settings;
  p.top_radius_m = atmosphere.top_radius_m;
  p.wavelengths_nm = atmosphere.wavelengths_nm;
  p.sun_angular_radius_rad = atmosphere.sun_angular_radius_rad;
  if (!std::isfinite(sea) && !lakes) return;
  GLint units = 0;
  glGetIntegerv(GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, &units);
  if (settings.first_unit + 10 > units)
    throw Error("ocean settings: first_unit + 9 (the sea's light maps) is beyond the context's " +
                std::to_string(units) + " texture units");
  p.has_sea = std::isfinite(sea);
  p.sea_level_m = sea;
  p.sea_radius_m = atmosphere.bottom_radius_m + sea;
  p.level_height_m[kSea] = sea;
  p.level_radius_m[kSea] = p.sea_radius_m;
  if (lakes) {
    p.has_lakes = true;
    p.lake_level_m = *surface.lake_level_m;
    p.level_height_m[kLakes] = p.lake_level_m;
    p.level_radius_m[kLakes] = atmosphere.bottom_radius_m + p.lake_level_m;
    planet::RasterSettings mask;
    mask.source = surface.lake_mask.source;
    mask.kind = planet::RasterKind::mask;
    mask.crs = surface.lake_mask.crs;
    mask.bounds_deg = surface.lake_mask.bounds_deg;
    mask.role = "lake mask";
    try {
      p.lake_mask = std::make_unique<planet::RasterSource>(mask);
    } catch (const Error& e) {
      throw Error(std::string("ocean: ") + e.what());
    }
  }
  // The channels' wavelengths (water_optics): the working ones, or in the
  // spectral mode representative wavelengths of the sRGB primaries.
  p.water = optics;
  p.spectrum = water_triples(settings.water, atmosphere);
  p.waves = make_waves(settings.water.wind_speed_m_s, optics.slope_variance);
  p.surface = std::make_unique<planet::Surface>(surface, atmosphere.bottom_radius_m);
  p.bake_bathymetry();
  glCreateVertexArrays(1, &p.vertex_array);
  p.programs[0] = p.link(false, false, false, false);
  // The maps at construction, but for the tests' program that reads the
  // pass's functions instead (kOceanDirectLight): then at the first draw
  // that reads them.
  if ((terms_drawn.load(std::memory_order_relaxed) & planet::kOceanDirectLight) == 0) p.fill_light_maps();
}

Ocean::~Ocean() = default;

bool Ocean::has_sea() const { return impl_->has_sea; }
double Ocean::sea_level_m() const { return impl_->sea_level_m; }
bool Ocean::has_lakes() const { return impl_->has_lakes; }

void Ocean::set_stars(bool on, const glm::dmat3& world_from_star_catalogue) {
  validate_star_orientation(world_from_star_catalogue, "ocean: set_stars");
  Impl& p = *impl_;
  p.star_directions.clear();
  p.star_irradiances.clear();
  if (!on) return;
  const std::vector<Star>& catalogue = p.pass->star_catalogue();
  std::vector<std::pair<glm::vec3, size_t>> light;
  light.reserve(catalogue.size());
  for (size_t i = 0; i < catalogue.size(); ++i)
    light.emplace_back(star_channel_irradiance(catalogue[i], p.wavelengths_nm), i);
  const size_t count = std::min(light.size(), size_t(kOceanMirroredStars));
  std::partial_sort(light.begin(), light.begin() + std::ptrdiff_t(count), light.end(),
                    [](const auto& a, const auto& b) { return a.first.y > b.first.y; });
  for (size_t k = 0; k < count; ++k) {
    const glm::dvec3 d = glm::normalize(world_from_star_catalogue * catalogue[light[k].second].direction);
    p.star_directions.emplace_back(glm::vec3(d), 0.0f);
    p.star_irradiances.emplace_back(light[k].first, 0.0f);
  }
}
double Ocean::lake_level_m() const { return impl_->lake_level_m; }

double Ocean::depth_m(const glm::dvec3& direction) const {
  const Impl& p = *impl_;
  const double length = glm::length(direction);
  if (!(length > 0.0) || !std::isfinite(length)) throw Error("ocean: depth_m of a zero or non-finite direction");
  if (!p.has_sea) return 0.0;
  return std::max(p.sea_level_m - p.surface->ground_height_m(direction / length), 0.0);
}

void Ocean::draw(const GlobeView& view, double time_s) {
  Impl& p = *impl_;
  planet::check_view_matrices("ocean", view);
  const double sun_length = glm::length(view.sun_direction);
  if (!(sun_length > 0.0) || !std::isfinite(sun_length)) throw Error("ocean view: zero or non-finite sun direction");
  if (!(view.nits_per_unit > 0.0) || !std::isfinite(view.nits_per_unit))
    throw Error("ocean view: nits_per_unit must be positive");
  if (!(view.sun_illuminance_lux >= 0.0) || !std::isfinite(view.sun_illuminance_lux))
    throw Error("ocean view: sun_illuminance_lux must be >= 0");
  if (!std::isfinite(time_s)) throw Error("ocean view: the time must be finite");
  bool eclipse = false;
  try {
    eclipse = moons_may_eclipse(view.moons, view.sun_direction, p.top_radius_m, p.sun_angular_radius_rad);
  } catch (const Error& e) {
    throw Error(std::string("ocean view: GlobeView::moons: ") + e.what());
  }
  if (!p.has_sea && !p.has_lakes) return;

  const PlanetFrame& frame = p.pass->frame();
  const glm::dmat4 world_from_view = glm::inverse(view.view);
  const glm::dvec3 eye_world(world_from_view[3]);
  const glm::dvec3 camera = (eye_world - frame.centre) / frame.units_per_metre;
  const double r_c = glm::length(camera);
  // Below a level's water (or at the centre) that level is not drawn: no
  // underwater view.
  const auto above = [&](int level) { return p.present(level) && r_c > p.level_radius_m[size_t(level)]; };
  if (!above(kSea) && !above(kLakes)) return;
  glm::dmat4 rotation = view.view;
  rotation[3] = glm::dvec4(0.0, 0.0, 0.0, 1.0);
  glm::dmat4 scale(1.0);
  scale[0][0] = scale[1][1] = scale[2][2] = frame.units_per_metre;
  const glm::dmat4 clip_from_offset = view.projection * rotation * scale;
  const glm::dmat4 offset_from_clip = glm::inverse(clip_from_offset);
  if (!planet::finite(offset_from_clip)) throw Error("ocean view: singular projection");
  const glm::dvec3 up = camera / r_c;
  const glm::dvec3 sun = view.sun_direction / sun_length;

  // The waves: world wave vectors in the anchor's wind frame, and their
  // phases at the camera, k · camera + φ − ω t, reduced in double.
  p.anchor_at(up);
  planet::OceanWaveField field;
  planet::set_ocean_wave_uniforms(p.waves, p.upwind, p.crosswind, camera, time_s, field);
  std::array<glm::vec4, kMaxWaves> vectors{}, in_wind{};
  std::array<float, kMaxWaves> phases{};
  for (size_t i = 0; i < size_t(field.wave_count); ++i) {
    vectors[i] = glm::vec4(field.wave_vector[i]);
    in_wind[i] = glm::vec4(field.wave_in_wind[i]);
    phases[i] = float(field.wave_phase[i]);
  }

  const unsigned terms = terms_drawn.load(std::memory_order_relaxed);
  const bool direct_light = (terms & planet::kOceanDirectLight) != 0;
  const bool moons = !view.moons.empty();
  const bool stars = !p.star_directions.empty();
  OceanProgram* program =
      &p.programs[size_t((moons ? 1 : 0) + (eclipse ? 2 : 0) + (direct_light ? 4 : 0) + (stars ? 8 : 0))];
  if (program->id == 0) *program = p.link(moons, eclipse, direct_light, stars);
  if (!direct_light && p.pass->ground_albedo() != p.maps_albedo) p.fill_light_maps();
  const OceanProgram& g = *program;
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glEnable(GL_TEXTURE_CUBE_MAP_SEAMLESS);
  glViewport(0, 0, view.width, view.height);
  glUseProgram(g.id);
  glBindVertexArray(p.vertex_array);
  p.pass->bind_textures(p.settings.first_unit);
  glBindTextureUnit(GLuint(p.settings.first_unit + 5), p.bathymetry);
  glBindTextureUnit(GLuint(p.settings.first_unit + 8), p.reflectance_map);
  for (int unit = 5; unit < 10; ++unit) glBindSampler(GLuint(p.settings.first_unit + unit), 0);

  const glm::mat4 clip_f(clip_from_offset), inverse_f(offset_from_clip);
  glUniformMatrix4fv(g.clip, 1, GL_FALSE, glm::value_ptr(clip_f));
  glUniformMatrix4fv(g.inverse, 1, GL_FALSE, glm::value_ptr(inverse_f));
  glUniform2f(g.viewport, float(view.width), float(view.height));
  glUniform3f(g.camera, float(camera.x), float(camera.y), float(camera.z));
  glUniform3f(g.up, float(up.x), float(up.y), float(up.z));
  glUniform1f(g.radius, float(r_c));
  const double pixel_angle = 2.0 / (std::abs(view.projection[1][1]) * view.height);  // rad
  glUniform1f(g.pixel_angle, float(pixel_angle));
  glUniform3f(g.sun, float(sun.x), float(sun.y), float(sun.z));
  const double lux_scale =
      view.sun_illuminance_lux > 0.0 ? view.sun_illuminance_lux / p.pass->sun_illuminance_lux() : 1.0;
  glUniform1f(g.light, float(lux_scale / view.nits_per_unit));
  const WaterOptics& w = p.water;
  const glm::vec3 n(w.refractive_index), a(w.absorption_per_m), b(w.backscattering_per_m), r(w.diffuse_reflectance);
  glUniform3f(g.refractive, n.x, n.y, n.z);
  glUniform3f(g.absorption, a.x, a.y, a.z);
  glUniform3f(g.backscattering, b.x, b.y, b.z);
  glUniform3f(g.diffuse, r.x, r.y, r.z);
  glUniform2f(g.slope_variance, float(w.slope_variance.x), float(w.slope_variance.y));
  glUniform3f(g.upwind, float(p.upwind.x), float(p.upwind.y), float(p.upwind.z));
  glUniform1i(g.wave_count, int(p.waves.size()));
  glUniform4fv(g.wave_vector, kMaxWaves, glm::value_ptr(vectors[0]));
  glUniform4fv(g.wave_in_wind, kMaxWaves, glm::value_ptr(in_wind[0]));
  glUniform1fv(g.wave_phase, kMaxWaves, phases.data());
  glUniform3f(g.seabed, float(p.settings.seabed_albedo.x), float(p.settings.seabed_albedo.y),
              float(p.settings.seabed_albedo.z));
  if (moons) {
    std::array<glm::vec4, kMaxMoons> spheres{};
    for (size_t i = 0; i < view.moons.size(); ++i)
      spheres[i] = glm::vec4(glm::vec3(view.moons[i].centre_m), float(view.moons[i].radius_m));
    glUniform1i(g.moon_count, int(view.moons.size()));
    glUniform4fv(g.moon_spheres, kMaxMoons, glm::value_ptr(spheres[0]));
    glUniform1f(g.eclipse_top_radius, float(p.top_radius_m));
  }
  if (stars) {
    glUniform1i(g.star_count, int(p.star_directions.size()));
    glUniform4fv(g.star_directions, GLsizei(p.star_directions.size()), glm::value_ptr(p.star_directions[0]));
    glUniform4fv(g.star_irradiances, GLsizei(p.star_irradiances.size()), glm::value_ptr(p.star_irradiances[0]));
  }
  glUniform1i(g.terms, int(terms));
  // The sea, then the lakes: each its own sphere, light maps and water
  // level; the lakes only where the mask says so. The depth test keeps
  // the nearer water, and the terrain in front of both.
  double largest_amplitude = 0.0;  // m, of the waves (waves_can_displace below)
  for (const planet::OceanWave& wave : p.waves) largest_amplitude = std::max(largest_amplitude, wave.amplitude);
  for (int level = 0; level < kLevels; ++level) {
    if (!above(level)) continue;
    const double radius = p.level_radius_m[size_t(level)];
    glUniform1f(g.height_term, float((r_c - radius) * (r_c + radius)));
    glUniform1f(g.sea_radius, float(radius));
    // ocean.frag.glsl: a wave of amplitude a displaces the surface only
    // where a spans more than a pixel, a sin θ_v / (t α) > 1, and t is at
    // least the camera's height above this level.
    glUniform1i(g.waves_can_displace, largest_amplitude > (r_c - radius) * pixel_angle ? 1 : 0);
    glUniform1f(g.sea_level, float(p.level_height_m[size_t(level)]));
    glUniform1i(g.lakes, level == kLakes ? 1 : 0);
    glBindTextureUnit(GLuint(p.settings.first_unit + 6), p.sky_map[size_t(level)]);
    glBindTextureUnit(GLuint(p.settings.first_unit + 7), p.light_map[size_t(level)]);
    glBindTextureUnit(GLuint(p.settings.first_unit + 9), p.below_map[size_t(level)]);
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  glBindVertexArray(0);
}

}  // namespace atmos
