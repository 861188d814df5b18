// The instant approximate mode (InstantTables, AtmospherePass from them;
// physics/instant_atmosphere.glsl): its tables for every preset and in the
// spectral mode, bad input, and the pass against its CPU twin on the GPU
// (its error against the reference: tests/instant_accuracy.cpp).
//
// The GPU tests FAIL (never skip) without an OpenGL 4.5 context.
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "engine_frame.hpp"
#include "figures.hpp"
#include "fullscreen_program.hpp"
#include "gpu/instant.hpp"
#include "physics/parameters.hpp"
#include "table_sizes.hpp"

namespace {

bool finite_and_non_negative(const std::vector<glm::vec3>& texels) {
  return std::all_of(texels.begin(), texels.end(), [](const glm::vec3& c) {
    return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z) && c.x >= 0.0f && c.y >= 0.0f &&
           c.z >= 0.0f;
  });
}

double seconds(const atmos::InstantTables& tables) {
  double sum = 0.0;
  for (const atmos::StepTiming& t : tables.timings) sum += t.seconds;
  return sum;
}

// Every preset's instant tables: finite, non-negative, the multiple
// scattering positive where the sun is up (Ψ_ms > 0 at mu_s = 1 at every
// altitude), the sky irradiance positive at the ground under a high sun. The
// time is printed (atmos bench measures it).
TEST(InstantTables, EveryPresetGivesFiniteNonNegativeTables) {
  for (const char* name : {"earth", "mars", "mars-thesis", "venus", "titan"}) {
    const atmos::Atmosphere atmosphere = atmos::load_atmosphere(name);
    const atmos::InstantTables tables = atmos::compute_instant_tables(atmosphere);
    ASSERT_NO_THROW(atmos::check_tables_match(atmosphere, tables)) << name;
    EXPECT_TRUE(finite_and_non_negative(tables.multiple_scattering)) << name;
    EXPECT_TRUE(finite_and_non_negative(tables.indirect_irradiance)) << name;
    const int width = tables.multiple_scattering_mu_s * tables.spectral_sets();
    for (int y = 0; y < tables.multiple_scattering_r; ++y) {
      const glm::vec3 overhead = tables.multiple_scattering[size_t(y) * size_t(width) + size_t(width - 1)];
      EXPECT_GT(std::min({overhead.x, overhead.y, overhead.z}), 0.0f) << name << " row " << y;
    }
    // Irradiance texel at the ground (row 0) with the sun overhead (last column).
    const glm::vec3 sky = tables.indirect_irradiance[size_t(tables.sizes.irradiance_mu_s - 1)];
    EXPECT_GT(std::min({sky.x, sky.y, sky.z}), 0.0f) << name;
    std::printf("%-12s %2zu wavelengths: instant tables in %.3f s (", name, atmosphere.wavelengths_nm.size(),
                seconds(tables));
    for (const atmos::StepTiming& t : tables.timings) std::printf(" %s %.3f", t.name.c_str(), t.seconds);
    std::printf(" )\n");
  }
}

TEST(InstantTables, BadInputIsAnError) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  atmos::TableSizes odd;
  odd.scattering_mu = 31;
  EXPECT_THROW(atmos::compute_instant_tables(earth, odd), atmos::Error);
  atmos::InstantTables tables = atmos::compute_instant_tables(earth, atmos_test::small_gpu_sizes());
  atmos::Atmosphere other = earth;
  other.wavelengths_nm = {700.0, 550.0, 450.0};
  EXPECT_THROW(atmos::check_tables_match(other, tables), atmos::Error);
  tables.multiple_scattering.pop_back();
  EXPECT_THROW(atmos::check_tables_match(earth, tables), atmos::Error);
}

// The spectral mode (15 wavelengths, three wavelength triples) gives the
// same sky as three wavelengths within the difference of the two modes'
// colour (a few per cent in luminance), and both are finite.
TEST(InstantTables, SpectralModeMatchesThreeWavelengths) {
  atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::InstantTables three = atmos::compute_instant_tables(earth);
  atmos::Atmosphere spectral = earth;
  spectral.wavelengths_nm = atmos::spectral_wavelengths(15);
  const atmos::InstantTables fifteen = atmos::compute_instant_tables(spectral);
  EXPECT_TRUE(finite_and_non_negative(fifteen.multiple_scattering));
  const glm::dvec3 camera = atmos::observer_position(earth, 2.0);
  const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(200.0, 30.0);
  std::vector<glm::dvec3> views;
  for (double elevation : {5.0, 30.0, 80.0})
    for (double azimuth : {0.0, 90.0, 180.0}) views.push_back(atmos::direction_from_azimuth_elevation(azimuth, elevation));
  const std::vector<glm::dvec3> a = atmos::gpu::instant_sky_radiance_cpu(earth, three, camera, sun, views);
  const std::vector<glm::dvec3> b = atmos::gpu::instant_sky_radiance_cpu(spectral, fifteen, camera, sun, views);
  const glm::dmat3 to_srgb_three(atmos::physics::channels_to_srgb_matrix(earth.wavelengths_nm));
  const glm::dmat3 to_srgb_fifteen(atmos::physics::channels_to_srgb_matrix(spectral.wavelengths_nm));
  for (size_t i = 0; i < views.size(); ++i) {
    const double la = atmos::srgb_luminance(to_srgb_three * a[i]);
    const double lb = atmos::srgb_luminance(to_srgb_fifteen * b[i]);
    ASSERT_TRUE(std::isfinite(lb));
    EXPECT_NEAR(lb / la, 1.0, 0.08) << "view " << i;
  }
}

// --- The pass on the GPU ------------------------------------------------------

constexpr double kEarthRadius = 6371e3;

using atmos_test::engine_frame;
using atmos_test::EngineFrame;
using atmos_test::make_engine_frame;
using atmos_test::Shot;

GLuint upload(GLenum format, int w, int h, GLenum pixel_format, const void* data) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, format, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t, 0, 0, 0, w, h, pixel_format, GL_FLOAT, data);
  return t;
}

std::vector<glm::vec3> run(atmos::AtmospherePass& pass, EngineFrame& e) {
  const int w = e.input.width, h = e.input.height;
  std::vector<GLuint> textures;
  e.input.depth = upload(GL_R32F, w, h, GL_RED, e.buffers.depth.data());
  textures.push_back(e.input.depth);
  if (e.input.surfaces == atmos::SurfaceMode::lit_colour) {
    e.input.colour = upload(GL_RGBA32F, w, h, GL_RGB, e.buffers.colour.data());
    textures.push_back(e.input.colour);
  } else {
    e.input.albedo = upload(GL_RGBA32F, w, h, GL_RGB, e.buffers.albedo.data());
    e.input.normal = upload(GL_RGBA32F, w, h, GL_RGB, e.buffers.normal.data());
    textures.push_back(e.input.albedo);
    textures.push_back(e.input.normal);
  }
  const GLuint out = pass.render(e.input);
  std::vector<float> rgba(size_t(w) * size_t(h) * 4);
  glGetTextureImage(out, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
  glDeleteTextures(GLsizei(textures.size()), textures.data());
  std::vector<glm::vec3> rgb(size_t(w) * size_t(h));
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
  return rgb;
}

double luminance(const glm::vec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

// Every preset through the pass's CPU twin (the functions the GPU runs), on
// the ground looking at the horizon with the sun 20° and 3° up, and from
// orbit: every pixel finite and non-negative, the sky brighter than nothing.
TEST(InstantTables, EveryPresetRendersFiniteNonNegative) {
  for (const char* name : {"earth", "mars", "venus", "titan"}) {
    const atmos::Atmosphere atmosphere = atmos::load_atmosphere(name);
    const atmos::InstantTables tables = atmos::compute_instant_tables(atmosphere, atmos_test::small_gpu_sizes());
    const glm::dvec3 up(0.0, 0.0, 1.0), north(0.0, 1.0, 0.0);
    for (const auto& [altitude, sun_elevation] : {std::pair{2.0, 20.0}, std::pair{2.0, 3.0}, std::pair{400e3, 20.0}}) {
      Shot shot;
      shot.planet_radius_m = atmosphere.bottom_radius_m;
      shot.camera = up * (atmosphere.bottom_radius_m + altitude);
      shot.forward = glm::normalize(north + up * (altitude > 1e3 ? -1.0 : 0.05));
      shot.width = 16;
      shot.height = 12;
      const double e = glm::radians(sun_elevation);
      shot.sun = glm::normalize(north * std::cos(e) + up * std::sin(e) + glm::dvec3(0.3, 0.0, 0.0));
      EngineFrame frame = make_engine_frame(shot);
      std::vector<glm::ivec2> pixels;
      for (int y = 0; y < shot.height; ++y)
        for (int x = 0; x < shot.width; ++x) pixels.push_back({x, y});
      const std::vector<glm::vec3> rgb =
          atmos::gpu::composite_instant_cpu(atmosphere, tables, engine_frame(), frame.input, frame.buffers, pixels);
      EXPECT_TRUE(finite_and_non_negative(rgb)) << name << " " << altitude << " m, sun " << sun_elevation;
      double brightest = 0.0;
      for (const glm::vec3& c : rgb) brightest = std::max(brightest, double(c.y));
      EXPECT_GT(brightest, 0.0) << name << " " << altitude << " m, sun " << sun_elevation;
    }
  }
}

class InstantGpu : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    earth_ = std::make_unique<atmos::Atmosphere>(atmos::load_atmosphere("earth"));
    tables_ = std::make_unique<atmos::InstantTables>(
        atmos::compute_instant_tables(*earth_, atmos_test::small_gpu_sizes()));
    try {
      context_ = atmos::GlContext::create_headless();
      pass_ = std::make_unique<atmos::AtmospherePass>(*earth_, *tables_, engine_frame(), atmos::PassPrograms::none);
    } catch (const atmos::Error& e) {
      error_ = e.what();
    }
  }
  static void TearDownTestSuite() {
    pass_.reset();
    context_.reset();
    tables_.reset();
    earth_.reset();
  }
  void SetUp() override { ASSERT_TRUE(pass_ != nullptr) << error_; }

  static inline std::unique_ptr<atmos::Atmosphere> earth_;
  static inline std::unique_ptr<atmos::InstantTables> tables_;
  static inline std::unique_ptr<atmos::GlContext> context_;
  static inline std::unique_ptr<atmos::AtmospherePass> pass_;
  static inline std::string error_;
};

// The pass against its CPU twin (gpu/instant.cpp: the same sky-view table,
// volume and composite, or the per-pixel integration from orbit): on the
// ground at noon and at sunset, at 10 km, from orbit (400 km) and lit from a
// G-buffer. Tolerances of the exact mode's twin test (tests/plugin_test.cpp:
// the GPU's own transcendental functions), measured here and recorded.
TEST_F(InstantGpu, MatchesCpuTwin) {
  EXPECT_TRUE(pass_->instant());
  const glm::dvec3 site = glm::normalize(glm::dvec3(0.3, 0.2, 0.93));
  const glm::dvec3 up = site;
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0.0, 0.0, 1.0), up));
  const glm::dvec3 north = glm::cross(up, east);
  const auto direction = [&](double azimuth, double elevation) {
    const double a = glm::radians(azimuth), e = glm::radians(elevation);
    return glm::normalize(north * (std::cos(e) * std::cos(a)) + east * (std::cos(e) * std::sin(a)) +
                          up * std::sin(e));
  };
  const auto at = [&](double altitude) { return site * (kEarthRadius + altitude); };
  std::vector<std::pair<std::string, Shot>> shots;
  Shot ground;
  ground.camera = at(10.0);
  ground.forward = direction(20.0, -3.0);
  ground.up_hint = up;
  ground.width = 48;
  ground.height = 32;
  ground.sun = direction(140.0, 35.0);
  ground.mountain_centre = at(-2000.0) + direction(25.0, 0.0) * 30e3;
  ground.mountain_radius_m = 4000.0;
  shots.push_back({"ground_noon", ground});
  Shot sunset = ground;
  sunset.sun = direction(30.0, 2.0);
  shots.push_back({"sunset", sunset});
  Shot high = ground;
  high.camera = at(10e3);
  high.forward = direction(10.0, -20.0);
  shots.push_back({"altitude_10km", high});
  Shot orbit = ground;
  orbit.camera = at(400e3);
  orbit.forward = direction(0.0, -60.0);
  orbit.fov_deg = 90.0;
  shots.push_back({"orbit_400km", orbit});
  Shot gbuffer = ground;
  gbuffer.surfaces = atmos::SurfaceMode::gbuffer;
  shots.push_back({"gbuffer", gbuffer});
  for (auto& [name, shot] : shots) {
    EngineFrame e = make_engine_frame(shot);
    const std::vector<glm::vec3> gpu = run(*pass_, e);
    std::vector<glm::ivec2> pixels;
    for (int y = 0; y < shot.height; y += 2)
      for (int x = (y / 2) % 2; x < shot.width; x += 2) pixels.push_back({x, y});
    const std::vector<glm::vec3> cpu =
        atmos::gpu::composite_instant_cpu(*earth_, *tables_, engine_frame(), e.input, e.buffers, pixels);
    double max_relative = 0.0, sum_squares = 0.0;
    int surfaces = 0;
    for (size_t k = 0; k < pixels.size(); ++k) {
      const size_t i = size_t(pixels[k].y) * size_t(shot.width) + size_t(pixels[k].x);
      ASSERT_TRUE(std::isfinite(luminance(gpu[i])) && std::isfinite(luminance(cpu[k]))) << name;
      EXPECT_GE(std::min({gpu[i].x, gpu[i].y, gpu[i].z}), 0.0f) << name;
      const double reference = std::max(luminance(cpu[k]), 1e-3);
      const double difference = glm::length(glm::dvec3(gpu[i]) - glm::dvec3(cpu[k])) / reference;
      max_relative = std::max(max_relative, difference);
      sum_squares += difference * difference;
      surfaces += e.buffers.depth[i] < 1.0f ? 1 : 0;
    }
    const double rms = std::sqrt(sum_squares / double(pixels.size()));
    std::printf("%-14s %zu pixels (%d surface): max %.3e, RMS %.3e\n", name.c_str(), pixels.size(), surfaces,
                max_relative, rms);
    atmos_test::record_figure("instant " + name + ": max relative difference", max_relative, "", "<= 1e-2");
    atmos_test::record_figure("instant " + name + ": RMS relative difference", rms, "", "<= 3e-3");
    EXPECT_LE(max_relative, 1e-2) << name;
    EXPECT_LE(rms, 3e-3) << name;
    EXPECT_GT(surfaces, 0) << name;
  }
}

// The GLSL library of an instant pass (engine_library.glsl with
// ATMOS_INSTANT) gives what the pass gives: from 400 km, where the pass
// integrates each pixel's ray (instant_space_pixel) with the march the
// library calls (instant_radiance_to_distance), a one-pixel frame looking
// 60 and 25 degrees down at the ground (surface colour x transmittance +
// atmos_radiance_to_point; reversed-Z depth) and 19 degrees down past the limb
// (atmos_sky_radiance) against the pass's pixel, to 1e-3; the irradiance
// and the transmittance to the sun are positive in daylight.
TEST_F(InstantGpu, GlslLibraryMatchesThePass) {
  const std::string library = pass_->glsl_library(20);
  EXPECT_NE(library.find("#define ATMOS_INSTANT 1"), std::string::npos);
  const std::string fragment = "#version 450 core\n" + library + R"(
layout(location = 0) uniform vec3 camera_position;
layout(location = 1) uniform vec3 sun;
layout(location = 2) uniform vec3 offset;
layout(location = 3) uniform bool sky;
layout(location = 0) out vec4 result;
void main() {
  vec3 transmittance;
  vec3 light;
  if (sky) {
    light = atmos_sky_radiance(camera_position, normalize(offset), sun, transmittance);
  } else {
    vec3 in_scatter = atmos_radiance_to_point(camera_position, offset, sun, transmittance);
    light = vec3(300.0) * transmittance + in_scatter;
  }
  vec3 point = camera_position + offset;
  vec3 sky_irradiance;
  vec3 direct = atmos_sun_and_sky_irradiance(point, normalize(point), sun, sky_irradiance);
  vec3 to_sun = atmos_transmittance_to_sun(point, sun);
  bool ok = (sky || (all(greaterThan(direct, vec3(0.0))) && all(greaterThan(sky_irradiance, vec3(0.0))) &&
                     all(greaterThan(to_sun, vec3(0.0))))) &&
            all(greaterThan(light, vec3(0.0)));
  result = vec4(light, ok ? 1.0 : 0.0);
}
)";
  const GLuint program = atmos_test::fullscreen_program(fragment);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  ASSERT_TRUE(linked);

  const glm::dvec3 up = glm::normalize(glm::dvec3(0.3, 0.2, 0.93));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0.0, 0.0, 1.0), up));
  const glm::dvec3 north = glm::cross(up, east);
  double worst = 0.0;
  for (const double down_deg : {60.0, 25.0, 19.0}) {
    Shot shot;
    shot.camera = up * (kEarthRadius + 400e3);
    const double a = glm::radians(down_deg);
    shot.forward = glm::normalize(north * std::cos(a) - up * std::sin(a));
    shot.up_hint = up;
    shot.width = shot.height = 1;
    shot.fov_deg = 0.5;
    shot.ground_offset_m = 0.0;
    // Reversed-Z: the pass finds the point 450-1900 km away to float precision.
    shot.encoding = atmos::DepthEncoding::reversed_z;
    shot.sun = glm::normalize(up + north * 0.4 + east * 0.3);
    EngineFrame e = make_engine_frame(shot);
    for (auto& c : e.buffers.colour) c = glm::vec3(300.0f);
    const std::vector<glm::vec3> from_pass = run(*pass_, e);
    const double t = atmos_test::hit_sphere(shot.camera, shot.forward, glm::dvec3(0.0), kEarthRadius);
    const bool sky = t < 0.0;
    EXPECT_EQ(sky, down_deg < 19.5) << down_deg;
    const glm::vec3 offset(shot.forward * (sky ? 1.0 : t));
    glProgramUniform3f(program, 0, float(shot.camera.x), float(shot.camera.y), float(shot.camera.z));
    const glm::vec3 sun(shot.sun);
    glProgramUniform3f(program, 1, sun.x, sun.y, sun.z);
    glProgramUniform3f(program, 2, offset.x, offset.y, offset.z);
    glProgramUniform1i(program, 3, sky ? 1 : 0);
    pass_->bind_textures(20);
    const std::vector<float> pixel = atmos_test::draw_fullscreen(program, 1, 1);
    const glm::vec3 from_library(pixel[0], pixel[1], pixel[2]);
    const double difference =
        glm::length(glm::dvec3(from_library) - glm::dvec3(from_pass[0])) / luminance(from_pass[0]);
    std::printf("400 km, %2.0f deg down (%s): pass %.5g cd/m2, engine library %.5g cd/m2 (relative difference %.2e)\n",
                down_deg, sky ? "sky" : "ground", luminance(from_pass[0]), luminance(from_library), difference);
    EXPECT_EQ(pixel[3], 1.0f) << down_deg << ": an irradiance, transmittance or radiance was not positive";
    worst = std::max(worst, difference);
  }
  glDeleteProgram(program);
  atmos_test::record_figure("instant GLSL library against the pass from 400 km: relative difference", worst, "",
                            "<= 1e-3");
  EXPECT_LE(worst, 1e-3);
}

// What the instant mode does not do is refused with a clear error, not
// drawn wrongly: eclipses and the ground albedo response.
TEST_F(InstantGpu, UnsupportedFeaturesAreErrors) {
  EXPECT_THROW(pass_->set_ground_albedo(glm::dvec3(0.2)), atmos::Error);
  Shot shot;
  const glm::dvec3 site(0.0, 0.0, 1.0);
  shot.camera = site * (kEarthRadius + 10.0);
  shot.forward = glm::dvec3(0.0, 1.0, 0.0);
  shot.sun = glm::normalize(glm::dvec3(0.0, 1.0, 1.0));
  EngineFrame e = make_engine_frame(shot);
  e.input.moons = {atmos::moon_in_sky(shot.camera, shot.sun, glm::radians(0.28))};
  EXPECT_THROW(run(*pass_, e), atmos::Error);
}

}  // namespace
