// The engine plugin (AtmospherePass) against its CPU twin (also from orbit,
// where it draws each class of pixels with its own program), and the
// properties an engine needs of it: depth encodings agree, no seam at the
// horizon, no hitch from the ground to 100 planet radii, light shafts, the
// planet's shadow seen from space, the GLSL library, and bad input; and
// eclipses (FrameInput::moons): twin, darkness, bad moons.
//
// The "engine" here is synthetic: its depth and colour buffers are computed
// on the CPU by ray casting spheres in double precision (the planet's ground
// raised by a few metres, a round "mountain"), in an engine world measured in
// kilometres whose origin is not the planet centre — so every test also
// exercises PlanetFrame and the camera-relative reduction.
//
// Like the renderer's GPU tests, these FAIL (never skip) without an OpenGL
// 4.5 context.
#include <gtest/gtest.h>

#include <epoxy/gl.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"
#include "gpu/atmosphere_pass.hpp"
#include "gpu/gl_util.hpp"
#include "physics/parameters.hpp"
#include "figures.hpp"
#include "engine_frame.hpp"
#include "fullscreen_program.hpp"
#include "gpu_fixture.hpp"

namespace {

using atmos::DepthEncoding;
using atmos::FrameInput;
using atmos::PlanetFrame;
using atmos::SurfaceMode;
using atmos_test::engine_frame;
using atmos_test::EngineFrame;
using atmos_test::hit_sphere;
using atmos_test::make_engine_frame;
using atmos_test::Shot;
using atmos_test::to_world;

constexpr double kEarthRadius = 6371e3;

// A local frame at a point of the planet: east, north, up.
struct LocalFrame {
  glm::dvec3 east, north, up;
};
LocalFrame local_frame(const glm::dvec3& position) {
  LocalFrame l;
  l.up = glm::normalize(position);
  l.east = glm::normalize(glm::cross(glm::dvec3(0.0, 0.0, 1.0), l.up));
  l.north = glm::cross(l.up, l.east);
  return l;
}

glm::dvec3 direction(const LocalFrame& l, double azimuth_deg, double elevation_deg) {
  const double a = glm::radians(azimuth_deg), e = glm::radians(elevation_deg);
  return glm::normalize(l.north * (std::cos(e) * std::cos(a)) + l.east * (std::cos(e) * std::sin(a)) +
                        l.up * std::sin(e));
}

GLuint upload_r32f(int w, int h, const std::vector<float>& data) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, GL_R32F, w, h);
  glTextureSubImage2D(t, 0, 0, 0, w, h, GL_RED, GL_FLOAT, data.data());
  return t;
}

GLuint upload_depth32f(int w, int h, const std::vector<float>& data) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, GL_DEPTH_COMPONENT32F, w, h);
  glTextureSubImage2D(t, 0, 0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, data.data());
  return t;
}

GLuint upload_rgb32f(int w, int h, const std::vector<glm::vec3>& data) {
  GLuint t = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &t);
  glTextureStorage2D(t, 1, GL_RGBA32F, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t, 0, 0, 0, w, h, GL_RGB, GL_FLOAT, data.data());
  return t;
}

std::vector<glm::vec3> read_rgb(GLuint texture, int w, int h) {
  std::vector<float> rgba(size_t(w) * size_t(h) * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
  std::vector<glm::vec3> rgb(size_t(w) * size_t(h));
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
  return rgb;
}

// The engine's textures on the GPU for one frame (deleted with it).
struct GpuEngineFrame {
  std::vector<GLuint> textures;
  ~GpuEngineFrame() { glDeleteTextures(GLsizei(textures.size()), textures.data()); }
  GLuint add(GLuint t) {
    textures.push_back(t);
    return t;
  }
};

double luminance(const glm::vec3& c) { return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z; }

bool all_finite(const std::vector<glm::vec3>& v) {
  return std::all_of(v.begin(), v.end(),
                     [](const glm::vec3& c) { return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z); });
}

// The plugin suite: the GPU fixture (gpu_fixture.hpp) and one pass.
class Plugin : public atmos_test::EarthGpuTest {
 protected:
  static void SetUpTestSuite() {
    EarthGpuTest::SetUpTestSuite();
    if (context_ == nullptr) return;
    try {
      pass_ = std::make_unique<atmos::AtmospherePass>(*earth_, *tables_, engine_frame(), atmos::PassPrograms::none);
    } catch (const atmos::Error& e) {
      error_ = e.what();
    }
  }
  static void TearDownTestSuite() {
    pass_.reset();
    EarthGpuTest::TearDownTestSuite();
  }
  void SetUp() override { ASSERT_TRUE(pass_ != nullptr) << error_; }

  // The suite's first comparison shot (10 m up at noon, lit colour) as an
  // engine frame to draw again, the frame the suite's pass draws of it, and
  // its input without textures (link_programs reads none): the programs are
  // those the suite's pass compiled, so the driver's cache keeps this cheap.
  struct ShotToRelink {
    EngineFrame frame;
    std::vector<glm::vec3> expected;
    atmos::FrameInput numbers;
  };
  static ShotToRelink shot_to_relink();  // after comparison_shots

  // Runs the pass (`pass`, else the suite's) on an engine frame; returns
  // the output (rows bottom-up).
  static std::vector<glm::vec3> run(EngineFrame& e, bool depth_component = false,
                                    atmos::AtmospherePass* pass = nullptr) {
    GpuEngineFrame gpu;
    const int w = e.input.width, h = e.input.height;
    e.input.depth = gpu.add(depth_component ? upload_depth32f(w, h, e.buffers.depth) : upload_r32f(w, h, e.buffers.depth));
    if (e.input.surfaces == SurfaceMode::lit_colour) {
      e.input.colour = gpu.add(upload_rgb32f(w, h, e.buffers.colour));
    } else {
      e.input.albedo = gpu.add(upload_rgb32f(w, h, e.buffers.albedo));
      e.input.normal = gpu.add(upload_rgb32f(w, h, e.buffers.normal));
    }
    if (!e.buffers.shadow_depth.empty()) {
      std::vector<float> depth(e.buffers.shadow_depth.size());
      for (size_t i = 0; i < depth.size(); ++i) depth[i] = e.buffers.shadow_depth[i].x;
      e.input.shadow_map = gpu.add(upload_depth32f(e.buffers.shadow_width, e.buffers.shadow_height, depth));
    }
    const GLuint out = (pass ? *pass : *pass_).render(e.input);
    // The texture names stay in e.input (deleted now): the CPU twin reads the
    // buffers, and only whether a shadow map was given.
    return read_rgb(out, w, h);
  }

  static inline std::unique_ptr<atmos::AtmospherePass> pass_;
};

// Cameras of the comparisons: on the ground, in a valley at 1.5 km looking
// at a mountain, at 10 km, from orbit (400 km), at sunset, and lit from a
// G-buffer.
std::vector<std::pair<std::string, Shot>> comparison_shots() {
  std::vector<std::pair<std::string, Shot>> shots;
  const glm::dvec3 site = glm::normalize(glm::dvec3(0.3, 0.2, 0.93));
  const LocalFrame l = local_frame(site);
  auto at = [&](double altitude) { return site * (kEarthRadius + altitude); };
  Shot ground;
  ground.camera = at(10.0);
  ground.forward = direction(l, 20.0, -3.0);
  ground.up_hint = l.up;
  ground.sun = direction(l, 140.0, 35.0);
  ground.mountain_centre = at(-2000.0) + direction(l, 25.0, 0.0) * 30e3;
  ground.mountain_radius_m = 4000.0;
  shots.push_back({"ground_noon", ground});
  Shot high = ground;
  high.camera = at(10e3);
  high.forward = direction(l, 10.0, -20.0);
  shots.push_back({"altitude_10km", high});
  Shot orbit = ground;
  orbit.camera = at(400e3);
  orbit.forward = direction(l, 0.0, -60.0);
  orbit.fov_deg = 90.0;
  shots.push_back({"orbit_400km", orbit});
  Shot sunset = ground;
  sunset.sun = direction(l, 30.0, 2.0);
  shots.push_back({"sunset", sunset});
  Shot gbuffer = ground;
  gbuffer.surfaces = SurfaceMode::gbuffer;
  shots.push_back({"gbuffer", gbuffer});
  // Night, looking up across a mountain: the star field over the sky pixels.
  Shot night = ground;
  night.forward = direction(l, 20.0, 8.0);
  night.fov_deg = 30.0;
  night.sun = direction(l, 200.0, -18.0);
  night.stars = true;
  shots.push_back({"night_stars", night});
  // Totality: a moon 0.28° in radius on the sun seen from the camera (the
  // sun's is 0.2664°), the surfaces lit by the pass (G-buffer) so that they
  // are eclipsed too; and the same moon seen from orbit, whose umbra falls
  // near the ground below the camera (the per-ray path of cameras above the
  // atmosphere, the exact in-scatter of the surfaces, the penumbra).
  Shot eclipse = gbuffer;
  eclipse.moons = {atmos::moon_in_sky(eclipse.camera, glm::normalize(eclipse.sun), glm::radians(0.28))};
  shots.push_back({"eclipse_ground", eclipse});
  Shot eclipse_orbit = orbit;
  eclipse_orbit.moons = {atmos::moon_in_sky(site * kEarthRadius, glm::normalize(orbit.sun), glm::radians(0.28))};
  shots.push_back({"eclipse_orbit", eclipse_orbit});
  return shots;
}

// Tolerances of the pass against its CPU twin, relative to the pixel's
// luminance. The two evaluate the same code on the same floats; they differ
// by the GPU's own sin/cos/exp/atan (an ulp or two) amplified where the
// tables change fast (see tests/gpu_test.cpp, which measures the same for
// the renderer: up to 1e-2 where the ground is in view). Measured here on
// llvmpipe: printed and recorded by the test.
constexpr double kMaxRelative = 1e-2;
constexpr double kRmsRelative = 3e-3;  // measured up to 2.6e-3 (Earth's continental aerosol)
// With a moon on the sun (eclipse_ground) the GPU comes out 0.1-0.15 %
// darker than the twin in luminance over the whole frame, sky and ground
// alike (measured: max 4.8e-3, RMS 2.6e-3 of the colour difference), as the
// renderer's eclipse does (tests/eclipse_test.cpp: 2.4e-3): the light in
// the umbra comes from the penumbra, where the sun's visible fraction is
// 1 - (overlap / disc), a difference of nearly equal floats that amplifies
// the GPU's own acos / asin / atan.
constexpr double kEclipseRmsRelative = 4e-3;

TEST_F(Plugin, MatchesCpuTwin) {
  for (auto& [name, shot] : comparison_shots()) {
    EngineFrame e = make_engine_frame(shot);
    const std::vector<glm::vec3> gpu = run(e);
    ASSERT_TRUE(all_finite(gpu)) << name;
    std::vector<glm::ivec2> pixels;
    for (int y = 0; y < shot.height; y += 3)
      for (int x = (y / 3) % 3; x < shot.width; x += 3) pixels.push_back({x, y});
    const std::vector<glm::vec3> cpu =
        atmos::gpu::composite_cpu(*earth_, *tables_, engine_frame(), e.input, e.buffers, pixels);
    double max_relative = 0.0, sum_squares = 0.0;
    int surfaces = 0;
    size_t worst = 0;
    for (size_t k = 0; k < pixels.size(); ++k) {
      const size_t i = size_t(pixels[k].y) * size_t(shot.width) + size_t(pixels[k].x);
      const double reference = std::max(luminance(cpu[k]), 1e-3);
      const double difference = glm::length(glm::dvec3(gpu[i]) - glm::dvec3(cpu[k])) / reference;
      if (difference > max_relative) worst = k;
      max_relative = std::max(max_relative, difference);
      sum_squares += difference * difference;
      surfaces += e.buffers.depth[i] < 1.0f ? 1 : 0;
    }
    const double rms = std::sqrt(sum_squares / double(pixels.size()));
    const size_t w = size_t(pixels[worst].y) * size_t(shot.width) + size_t(pixels[worst].x);
    std::printf("%-14s %zu pixels (%d surface)  max %.3e at (%d, %d) %s [cpu %.5g, gpu %.5g]  rms %.3e\n",
                name.c_str(), pixels.size(), surfaces, max_relative, pixels[worst].x, pixels[worst].y,
                e.buffers.depth[w] < 1.0f ? "surface" : "sky", luminance(cpu[worst]), luminance(gpu[w]), rms);
    atmos_test::record_figure(name + ": max relative difference", max_relative, "", "<= 1e-2");
    atmos_test::record_figure(name + ": RMS relative difference", rms, "",
                              shot.moons.empty() ? "<= 3e-3" : "<= 4e-3");
    EXPECT_LE(max_relative, kMaxRelative) << name;
    EXPECT_LE(rms, shot.moons.empty() ? kRmsRelative : kEclipseRmsRelative) << name;
    EXPECT_GT(surfaces, 0) << name << ": the shot shows no surface";
  }
}

// An engine frame's input without its textures: link_programs reads none.
atmos::FrameInput numbers_of(const EngineFrame& e) {
  atmos::FrameInput numbers = e.input;
  numbers.depth = numbers.colour = 0;
  return numbers;
}

Plugin::ShotToRelink Plugin::shot_to_relink() {
  const Shot shot = comparison_shots().front().second;
  EngineFrame first = make_engine_frame(shot);
  ShotToRelink r{make_engine_frame(shot), run(first), {}};
  r.numbers = numbers_of(r.frame);
  return r;
}

// The pixels where two frames of the same size differ at all; every pixel
// if their sizes differ.
size_t differing_pixels(const std::vector<glm::vec3>& a, const std::vector<glm::vec3>& b) {
  if (a.size() != b.size()) return std::max(a.size(), b.size());
  size_t differing = 0;
  for (size_t i = 0; i < a.size(); ++i) differing += a[i] == b[i] ? 0 : 1;
  return differing;
}

// A pass built without programs (PassPrograms::none) links, before any
// draw, exactly the programs a frame draws with (link_programs), and then
// draws it as the suite's pass does, bit for bit (shot_to_relink).
TEST_F(Plugin, LinksAFramesProgramsBeforeItsFirstDraw) {
  ShotToRelink s = shot_to_relink();
  const atmos::FrameInput& numbers = s.numbers;
  atmos::AtmospherePass pass(*earth_, *tables_, engine_frame(), atmos::PassPrograms::none);
  EXPECT_FALSE(pass.programs_linked(numbers));
  pass.link_programs(numbers);
  EXPECT_TRUE(pass.programs_linked(numbers));
  // Another camera (orbit) needs other programs.
  atmos::FrameInput orbit = make_engine_frame(comparison_shots()[2].second).input;
  EXPECT_FALSE(pass.programs_linked(orbit));
  // Bad numbers: the error render() gives.
  atmos::FrameInput bad = numbers;
  bad.width = 0;
  EXPECT_THROW(pass.link_programs(bad), atmos::Error);
  const std::vector<glm::vec3> drawn = run(s.frame, false, &pass);
  EXPECT_EQ(differing_pixels(drawn, s.expected), 0u);
}

// Links the programs of `numbers` (ProgramScope `scope`) into `pass` in a
// context of the suite's share group on another thread while this thread
// draws with the same pass (`draw`); returns what `draw` drew.
std::vector<glm::vec3> draw_while_linking_elsewhere(atmos::GlContext& context, atmos::AtmospherePass& pass,
                                                    const atmos::FrameInput& numbers, atmos::ProgramScope scope,
                                                    const std::function<std::vector<glm::vec3>()>& draw) {
  std::unique_ptr<atmos::GlContext> shared = context.create_shared();
  std::string linker_error;
  std::thread linker([&] {
    try {
      shared->make_current();
      pass.link_programs(numbers, scope);
    } catch (const std::exception& e) {
      linker_error = e.what();
    }
    shared.reset();
  });
  std::vector<glm::vec3> drawn;
  try {
    drawn = draw();
  } catch (...) {
    linker.join();
    throw;
  }
  linker.join();
  EXPECT_TRUE(linker_error.empty()) << linker_error;
  return drawn;
}

// link_programs() in a context of the pass's share group on another thread,
// while this thread draws with the same pass: the frame is the one a pass
// with its own programs draws, bit for bit (render() takes or waits for
// the programs the other thread links, and the other thread draws its new
// programs only into its own scratch targets).
TEST_F(Plugin, LinksOnAnotherThreadWhileDrawing) {
  ShotToRelink s = shot_to_relink();
  const atmos::FrameInput& numbers = s.numbers;
  atmos::AtmospherePass pass(*earth_, *tables_, engine_frame(), atmos::PassPrograms::none);
  const std::vector<glm::vec3> drawn = draw_while_linking_elsewhere(
      *context_, pass, numbers, atmos::ProgramScope::view, [&] { return run(s.frame, false, &pass); });
  EXPECT_TRUE(pass.programs_linked(numbers));
  EXPECT_EQ(differing_pixels(drawn, s.expected), 0u);
}

// A stop already asked for: link_programs() links nothing (a thread that
// prepares programs is told so when its pass is about to go).
TEST_F(Plugin, LinksNothingOnceStopped) {
  const Shot shot = comparison_shots().front().second;
  const atmos::FrameInput numbers = numbers_of(make_engine_frame(shot));
  atmos::AtmospherePass pass(*earth_, *tables_, engine_frame(), atmos::PassPrograms::none);
  const std::atomic<bool> stop{true};
  pass.link_programs(numbers, atmos::ProgramScope::flight, &stop);
  EXPECT_FALSE(pass.programs_linked(numbers));
  pass.link_programs(numbers);
  EXPECT_TRUE(pass.programs_linked(numbers));
}

// The same view moved along its camera's vertical to `altitude` (m).
FrameInput at_altitude(const FrameInput& input, double altitude) {
  const PlanetFrame f = engine_frame();
  const glm::dvec3 eye = glm::dvec3(glm::inverse(input.view)[3]);
  const glm::dvec3 offset = (eye - f.centre) / f.units_per_metre;
  const double radius = glm::length(offset);
  const glm::dvec3 delta = offset / radius * ((kEarthRadius + altitude - radius) * f.units_per_metre);
  FrameInput moved = input;
  moved.view = input.view * glm::translate(glm::dmat4(1.0), -delta);
  return moved;
}

// The full tier's (tests/CMakeLists.txt): a flight's programs take about 20
// s to link and compile on llvmpipe.
class PluginFlight : public Plugin {};

// With ProgramScope::flight, link_programs() links the programs of the same
// view from the blend band of the volume (20 km), from higher in the
// atmosphere (60 km) and from above it (150 km, 2.5 radii) too, on another
// thread while this one draws, the frame bit for bit as above; bad numbers
// are the error render() gives.
TEST_F(PluginFlight, LinksAFlightsPrograms) {
  ShotToRelink s = shot_to_relink();
  const atmos::FrameInput& numbers = s.numbers;
  atmos::AtmospherePass pass(*earth_, *tables_, engine_frame(), atmos::PassPrograms::none);
  for (const double altitude : {20e3, 60e3, 150e3, 2.5 * kEarthRadius})
    EXPECT_FALSE(pass.programs_linked(at_altitude(numbers, altitude))) << altitude << " m";
  const std::vector<glm::vec3> drawn = draw_while_linking_elsewhere(
      *context_, pass, numbers, atmos::ProgramScope::flight, [&] { return run(s.frame, false, &pass); });
  EXPECT_EQ(differing_pixels(drawn, s.expected), 0u);
  for (const double altitude : {20e3, 60e3, 150e3, 2.5 * kEarthRadius})
    EXPECT_TRUE(pass.programs_linked(at_altitude(numbers, altitude))) << altitude << " m";
  atmos::FrameInput bad = numbers;
  bad.projection[0][0] = std::nan("");
  EXPECT_THROW(pass.link_programs(bad, atmos::ProgramScope::flight), atmos::Error);
}

// A pass of an atmosphere that differs from the suite's in values only (a
// longer Rayleigh scale height, another ground albedo, sun and top radius)
// draws with the programs of the suite's pass (gpu::shared_program): it
// links none, and draws the image a pass of that atmosphere draws with
// programs of its own (linked in a context that shares nothing with the
// suite's), not the suite's image.
TEST_F(Plugin, AtmosphereOfTheSameStructureLinksNoProgram) {
  const Shot shot = comparison_shots().front().second;
  EngineFrame first = make_engine_frame(shot), second = make_engine_frame(shot), third = make_engine_frame(shot);
  const std::vector<glm::vec3> earth = run(first);
  const atmos::Atmosphere other = atmos_test::other_earth_values(*earth_);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(other, options);
  const long linked = atmos::gpu::linked_program_count();
  std::vector<glm::vec3> shared;
  {
    atmos::AtmospherePass pass(other, tables, engine_frame(), atmos::PassPrograms::none);
    shared = run(second, false, &pass);
  }
  EXPECT_EQ(atmos::gpu::linked_program_count(), linked);
  std::vector<glm::vec3> own;
  {
    const std::unique_ptr<atmos::GlContext> unshared = atmos::GlContext::create_headless();
    unshared->make_current();
    {
      atmos::AtmospherePass pass(other, tables, engine_frame(), atmos::PassPrograms::none);
      own = run(third, false, &pass);
    }
    EXPECT_GT(atmos::gpu::linked_program_count(), linked);
  }
  context_->make_current();
  ASSERT_TRUE(all_finite(shared));
  ASSERT_EQ(shared.size(), own.size());
  double max_relative = 0.0, sum_squares = 0.0;
  for (size_t i = 0; i < own.size(); ++i) {
    const double reference = std::max(luminance(own[i]), 1e-3);
    max_relative = std::max(max_relative, glm::length(glm::dvec3(shared[i]) - glm::dvec3(own[i])) / reference);
    const double from_earth = glm::length(glm::dvec3(earth[i]) - glm::dvec3(own[i])) / reference;
    sum_squares += from_earth * from_earth;
  }
  const double earth_rms = std::sqrt(sum_squares / double(own.size()));
  std::printf("other values: shared programs against their own: max %.3e; the suite's image %.3e RMS from theirs\n",
              max_relative, earth_rms);
  EXPECT_LE(max_relative, 1e-6);
  EXPECT_GT(earth_rms, 0.05);
}

// From orbit the pass sorts the pixels into classes and draws each with its
// own program (atmosphere_pass.frag.glsl): the space beside the planet, the
// sky and the surfaces with the low-sun integration where their light needs
// it (pixel_needs_low_sun_path) and without it elsewhere. The CPU twin
// evaluates every pixel with the frame's variant (composite_pixel, all
// pixels with the integration), so the two agree within the twin's
// tolerances only if no pixel is drawn by the wrong program. The view: 400
// km up, looking north past the horizon, the sun 6° up in the north-west:
// the sun is below 10° on the nearer ground and limb (the low-sun band) and
// above it towards the sun, and space fills the top, so that every class
// has pixels.
TEST_F(Plugin, ClassifiedPixelsMatchTheCpuTwinFromOrbit) {
  const glm::dvec3 site = glm::normalize(glm::dvec3(0.3, 0.2, 0.93));
  const LocalFrame l = local_frame(site);
  Shot shot;
  shot.camera = site * (kEarthRadius + 400e3);
  shot.forward = direction(l, 0.0, -17.0);
  shot.up_hint = l.up;
  shot.fov_deg = 40.0;
  shot.width = 160;
  shot.height = 120;
  shot.encoding = DepthEncoding::reversed_z;
  shot.sun = direction(l, -60.0, 6.0);
  EngineFrame e = make_engine_frame(shot);
  const std::vector<glm::vec3> gpu = run(e);
  ASSERT_TRUE(all_finite(gpu));

  // The classes, from the pass's own tests on the CPU.
  const atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(*earth_, tables_->sizes);
  const glm::mat3 matrix = atmos::physics::channels_to_srgb_matrix(tables_->wavelengths_nm);
  const atmos::physics::PassFrame frame = atmos::gpu::make_pass_frame(
      e.input, engine_frame(), params, matrix, atmos::gpu::own_sun_illuminance(params, matrix));
  ASSERT_TRUE(frame.low_sun);
  int space = 0, sky = 0, sky_low_sun = 0, surface = 0, surface_low_sun = 0;
  std::vector<glm::ivec2> pixels;
  for (int y = 0; y < shot.height; ++y)
    for (int x = 0; x < shot.width; ++x) {
      pixels.push_back({x, y});
      const glm::vec2 ndc = (glm::vec2(float(x), float(y)) + 0.5f) /
                                glm::vec2(float(shot.width), float(shot.height)) * 2.0f -
                            1.0f;
      const atmos::physics::PixelRay ray =
          atmos::physics::pixel_ray(frame.inverse_projection, frame.view_to_world, ndc);
      const float depth = e.buffers.depth[size_t(y) * size_t(shot.width) + size_t(x)];
      const bool low_sun = atmos::physics::pixel_needs_low_sun_path(params, frame, ray, depth);
      if (!atmos::physics::depth_is_sky(depth, frame.depth_encoding)) {
        (low_sun ? surface_low_sun : surface) += 1;
      } else if (atmos::physics::sky_ray_misses_atmosphere(params, frame, ray)) {
        space += 1;
      } else {
        (low_sun ? sky_low_sun : sky) += 1;
      }
    }
  std::printf("classes: space %d, sky %d + %d with the low sun, surfaces %d + %d with the low sun\n", space, sky,
              sky_low_sun, surface, surface_low_sun);
  EXPECT_GT(space, 0);
  EXPECT_GT(sky, 0);
  EXPECT_GT(sky_low_sun, 0);
  EXPECT_GT(surface, 0);
  EXPECT_GT(surface_low_sun, 0);

  const std::vector<glm::vec3> cpu =
      atmos::gpu::composite_cpu(*earth_, *tables_, engine_frame(), e.input, e.buffers, pixels);
  double max_relative = 0.0, sum_squares = 0.0;
  size_t worst = 0;
  for (size_t k = 0; k < pixels.size(); ++k) {
    const double reference = std::max(luminance(cpu[k]), 1e-3);
    const double difference = glm::length(glm::dvec3(gpu[k]) - glm::dvec3(cpu[k])) / reference;
    if (difference > max_relative) worst = k;
    max_relative = std::max(max_relative, difference);
    sum_squares += difference * difference;
  }
  const double rms = std::sqrt(sum_squares / double(pixels.size()));
  std::printf("classified pass against the twin: max %.3e at (%d, %d) [cpu %.5g, gpu %.5g], rms %.3e\n",
              max_relative, pixels[worst].x, pixels[worst].y, luminance(cpu[worst]), luminance(gpu[worst]), rms);
  atmos_test::record_figure("orbit classes: max relative difference", max_relative, "", "<= 1e-2");
  atmos_test::record_figure("orbit classes: RMS relative difference", rms, "", "<= 3e-3");
  EXPECT_LE(max_relative, kMaxRelative);
  EXPECT_LE(rms, kRmsRelative);
}

// Where the driver exports a fragment's stencil value (llvmpipe does), the
// pass sorts the pixels with one classifying draw that writes all their
// bits, and draws the low-sun surfaces in the planet's shadow without the
// integration, which gives them no single scattering (VARIANT_NIGHT);
// drivers without it classify with a draw per class and integrate them.
// The two give the same image: from 400 km with the low-sun band and the
// space beside the planet in view (ClassifiedPixelsMatchTheCpuTwinFromOrbit's
// view), and from 2.5 planet radii with the terminator and the night side
// across the disc (the space volume's view), relative to the pixel's
// luminance; measured 0 for every pixel but the night surfaces, whose light
// a different program evaluates (the same functions on the same floats).
constexpr double kClassifyingDrawsMaxRelative = 1e-5;

TEST_F(Plugin, OneClassifyingDrawGivesTheImageOfADrawPerClass) {
  if (!epoxy_has_gl_extension("GL_ARB_shader_stencil_export"))
    GTEST_SKIP() << "the driver does not export the stencil: the pass draws per class only";
  const glm::dvec3 site = glm::normalize(glm::dvec3(0.3, 0.2, 0.93));
  const LocalFrame l = local_frame(site);
  Shot orbit;
  orbit.camera = site * (kEarthRadius + 400e3);
  orbit.forward = direction(l, 0.0, -17.0);
  orbit.up_hint = l.up;
  orbit.fov_deg = 40.0;
  orbit.width = 160;
  orbit.height = 120;
  orbit.encoding = DepthEncoding::reversed_z;
  orbit.sun = direction(l, -60.0, 6.0);
  Shot disc = orbit;
  disc.camera = site * (kEarthRadius * 3.5);
  disc.forward = -site;
  disc.up_hint = l.north;
  disc.sun = direction(l, 0.0, 25.0);
  disc.fov_deg = 34.0;
  disc.width = 192;
  disc.height = 108;
  for (const auto& [name, shot] : {std::pair<std::string, Shot>{"400 km", orbit}, {"2.5 radii", disc}}) {
    EngineFrame e = make_engine_frame(shot);
    const std::vector<glm::vec3> one = run(e);
    atmos::gpu::set_stencil_export(false);
    const std::vector<glm::vec3> per_class = run(e);
    atmos::gpu::set_stencil_export(true);
    ASSERT_TRUE(all_finite(one)) << name;
    // The night surfaces, from the pass's own test on the CPU.
    const atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(*earth_, tables_->sizes);
    const glm::mat3 matrix = atmos::physics::channels_to_srgb_matrix(tables_->wavelengths_nm);
    const atmos::physics::PassFrame frame = atmos::gpu::make_pass_frame(
        e.input, engine_frame(), params, matrix, atmos::gpu::own_sun_illuminance(params, matrix));
    int night = 0, low_sun = 0;
    double max_relative = 0.0;
    for (int y = 0; y < shot.height; ++y)
      for (int x = 0; x < shot.width; ++x) {
        const size_t i = size_t(y) * size_t(shot.width) + size_t(x);
        const glm::vec2 ndc = (glm::vec2(float(x), float(y)) + 0.5f) /
                                  glm::vec2(float(shot.width), float(shot.height)) * 2.0f -
                              1.0f;
        bool in_shadow = false;
        const bool needs = atmos::physics::pixel_low_sun_classes(
            params, frame, atmos::physics::pixel_ray(frame.inverse_projection, frame.view_to_world, ndc),
            e.buffers.depth[i], in_shadow);
        const bool surface = !atmos::physics::depth_is_sky(e.buffers.depth[i], frame.depth_encoding);
        low_sun += needs && surface ? 1 : 0;
        night += needs && surface && in_shadow ? 1 : 0;
        const double reference = std::max(luminance(per_class[i]), 1e-3);
        max_relative =
            std::max(max_relative, double(glm::length(glm::dvec3(one[i]) - glm::dvec3(per_class[i]))) / reference);
      }
    std::printf("%s: %d low-sun surface pixels, %d of them in the planet's shadow; one classifying draw against "
                "one per class: max %.3e\n",
                name.c_str(), low_sun, night, max_relative);
    atmos_test::record_figure("classifying draws, " + name + ": max relative difference", max_relative, "",
                              "<= 1e-5");
    EXPECT_GT(low_sun, 0) << name;
    EXPECT_LE(max_relative, kClassifyingDrawsMaxRelative) << name;
    if (name == "2.5 radii") {
      EXPECT_GT(night, 0);
    }
  }
}

// From above the atmosphere the surfaces the space volume covers
// (composite.glsl: space_volume_covers; 72 % and 50 % of them here) read
// it, whose texels are the exact per-pixel evaluation at their directions
// and distances: the volume's error is its interpolation. Against the exact
// evaluation of every pixel (the CPU twin both ways), surfaces only,
// relative to the pixel's luminance:
// from 400 km looking towards the limb with the sun 12° up (grazing rays
// near the limb, a 6 km mountain), and from 2.5 planet radii looking down at
// the disc with the terminator across it (the low-sun band). The
// volume's directions are the image's (128 x 72 texels whatever the image
// size), so a small image with the field of view of a full-size one tests
// the same angular texel spacing.
constexpr double kSpaceVolumeMaxRelative = 0.03;  // measured 1.2e-2 (400 km), 1.6e-2 (2.5 radii)
constexpr double kSpaceVolumeRmsRelative = 0.01;  // measured 4.2e-3, 5.5e-3

TEST_F(Plugin, SpaceVolumeMatchesTheExactEvaluation) {
  const glm::dvec3 site = glm::normalize(glm::dvec3(0.3, 0.2, 0.93));
  const LocalFrame l = local_frame(site);
  std::vector<std::pair<std::string, Shot>> shots;
  Shot limb;
  limb.camera = site * (kEarthRadius + 400e3);
  limb.forward = direction(l, 0.0, -17.0);
  limb.up_hint = l.up;
  limb.fov_deg = 60.0;
  limb.width = 192;
  limb.height = 108;
  limb.encoding = DepthEncoding::reversed_z;
  limb.sun = direction(l, -60.0, 12.0);
  limb.mountain_centre = glm::normalize(site * kEarthRadius + l.north * 900e3) * (kEarthRadius - 14e3);
  limb.mountain_radius_m = 20e3;
  shots.push_back({"400 km, limb", limb});
  Shot disc = limb;
  disc.camera = site * (kEarthRadius * 3.5);
  disc.forward = -site;
  disc.up_hint = l.north;
  disc.sun = direction(l, 0.0, 25.0);
  disc.fov_deg = 34.0;  // the disc fills the image's height
  disc.mountain_radius_m = 0.0;
  shots.push_back({"2.5 radii, terminator", disc});
  for (auto& [name, shot] : shots) {
    EngineFrame e = make_engine_frame(shot);
    std::vector<glm::ivec2> pixels;
    for (int y = 0; y < shot.height; ++y)
      for (int x = 0; x < shot.width; ++x)
        if (e.buffers.depth[size_t(y) * size_t(shot.width) + size_t(x)] > 0.0f) pixels.push_back({x, y});
    ASSERT_GT(pixels.size(), 1000u) << name;
    const std::vector<glm::vec3> volume =
        atmos::gpu::composite_cpu(*earth_, *tables_, engine_frame(), e.input, e.buffers, pixels, true);
    const std::vector<glm::vec3> exact =
        atmos::gpu::composite_cpu(*earth_, *tables_, engine_frame(), e.input, e.buffers, pixels, false);
    double max_relative = 0.0, sum_squares = 0.0, changed = 0.0;
    size_t worst = 0;
    // The surfaces the volume covers (the others are evaluated exactly).
    const atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(*earth_, tables_->sizes);
    const glm::mat3 matrix = atmos::physics::channels_to_srgb_matrix(tables_->wavelengths_nm);
    const atmos::physics::PassFrame frame = atmos::gpu::make_pass_frame(
        e.input, engine_frame(), params, matrix, atmos::gpu::own_sun_illuminance(params, matrix));
    const atmos::gpu::SpaceVolumeColumns columns = atmos::gpu::space_volume_columns(params, frame);
    std::printf("%s: %zu regular columns of %d\n", name.c_str(), columns.order.size(),
                SPACE_VOLUME_WIDTH * SPACE_VOLUME_HEIGHT);
    ASSERT_TRUE(frame.space_volume) << name;
    const atmos::physics::sampler2D regular{SPACE_VOLUME_WIDTH, SPACE_VOLUME_HEIGHT, columns.regular.data()};
    size_t covered = 0;
    for (const glm::ivec2& pixel : pixels) {
      const glm::vec2 ndc = (glm::vec2(pixel) + 0.5f) / glm::vec2(float(shot.width), float(shot.height)) * 2.0f - 1.0f;
      covered += atmos::physics::space_volume_covers(
                     frame, regular, atmos::physics::pixel_ray(frame.inverse_projection, frame.view_to_world, ndc))
                     ? 1
                     : 0;
    }
    for (size_t k = 0; k < pixels.size(); ++k) {
      const double reference = std::max(luminance(exact[k]), 1e-3);
      const double difference = glm::length(glm::dvec3(volume[k]) - glm::dvec3(exact[k])) / reference;
      if (difference > max_relative) worst = k;
      max_relative = std::max(max_relative, difference);
      sum_squares += difference * difference;
      changed = std::max(changed, double(glm::length(volume[k] - exact[k])));
    }
    const double rms = std::sqrt(sum_squares / double(pixels.size()));
    std::printf("%s: %zu surface pixels, %zu from the volume; against exact: max %.3e at (%d, %d) [exact %.5g, "
                "volume %.5g], rms %.3e\n",
                name.c_str(), pixels.size(), covered, max_relative, pixels[worst].x, pixels[worst].y,
                luminance(exact[worst]), luminance(volume[worst]), rms);
    atmos_test::record_figure("space volume, " + name + ": max relative difference", max_relative, "", "<= 3e-2");
    atmos_test::record_figure("space volume, " + name + ": RMS relative difference", rms, "", "<= 1e-2");
    EXPECT_GT(changed, 0.0) << name << ": the volume was not used";
    EXPECT_GT(double(covered), 0.1 * double(pixels.size())) << name;
    EXPECT_LE(max_relative, kSpaceVolumeMaxRelative) << name;
    EXPECT_LE(rms, kSpaceVolumeRmsRelative) << name;
  }
}

// The same view with standard depth (finite and infinite far plane, as a
// depth texture), reversed-Z and logarithmic depth: the images agree. The
// encodings quantise the surfaces' distances differently (float depth), so
// they agree to the radiance change of a slightly different distance; with
// a 1 m near plane, standard depth resolves the 30 km mountain to 0.1 %.
// (With a 10 cm near plane it is 2 %: the engine's precision, not the
// pass's — which is why engines use reversed-Z or logarithmic depth.)
constexpr double kEncodingMaxRelative = 5e-3;

TEST_F(Plugin, DepthEncodingsAgree) {
  Shot shot = comparison_shots()[0].second;
  shot.width = 96;
  shot.height = 64;
  shot.near_km = 1e-3;
  EngineFrame standard_frame = make_engine_frame(shot);
  const std::vector<glm::vec3> standard = run(standard_frame, true);
  ASSERT_TRUE(all_finite(standard));
  struct Variant {
    const char* name;
    DepthEncoding encoding;
    bool infinite_far;
  };
  for (const Variant& v : {Variant{"standard, infinite far", DepthEncoding::standard, true},
                           Variant{"reversed-Z (infinite)", DepthEncoding::reversed_z, false},
                           Variant{"logarithmic", DepthEncoding::logarithmic, false}}) {
    Shot other = shot;
    other.encoding = v.encoding;
    other.infinite_far = v.infinite_far;
    EngineFrame e = make_engine_frame(other);
    const std::vector<glm::vec3> image = run(e);
    ASSERT_TRUE(all_finite(image)) << v.name;
    double max_relative = 0.0;
    int surfaces = 0;
    for (size_t i = 0; i < image.size(); ++i) {
      max_relative = std::max(max_relative, glm::length(glm::dvec3(image[i]) - glm::dvec3(standard[i])) /
                                                std::max(luminance(standard[i]), 1e-3));
      surfaces += standard_frame.buffers.depth[i] < 1.0f ? 1 : 0;
    }
    std::printf("%-24s vs standard: max relative difference %.2e (%d surface pixels)\n", v.name, max_relative,
                surfaces);
    EXPECT_LE(max_relative, kEncodingMaxRelative) << v.name;
    EXPECT_GT(surfaces, 0);
  }
}

// The horizon seam of the two-lookup difference (Schafhitzel, Falk & Ertl
// 2007, §4.2): at high
// exposure, a thin band just below the horizon where aerial perspective
// jumps, bright or dark. A narrow vertical field of view (2°, 64 rows: 0.03°
// per row) straddles the horizon of a camera 300 m above an engine ground of
// black surfaces (so the image IS the aerial perspective). Approaching the
// horizon the ground's distance, and its in-scatter, grow steeply but
// smoothly; a seam is a kink on top of that. So the test bounds the second
// difference down the centre column, |L(y-1) - 2 L(y) + L(y+1)| / L(y), by
// kSeamMaxCurvature, for a sweep of sun elevations, in the ground rows and
// in the sky rows (not across the ground's edge, a real edge). Measured:
// 2.6-2.9 % by day, 4.1 % with the sun 2° below the horizon (the volume's
// interpolation between directions); the artefact this guards against is a
// band tens of percent off.
constexpr double kSeamMaxCurvature = 0.05;

TEST_F(Plugin, NoSeamAtTheHorizon) {
  const glm::dvec3 site = glm::normalize(glm::dvec3(-0.4, 0.5, 0.76));
  const LocalFrame l = local_frame(site);
  for (double sun_elevation : {60.0, 20.0, 8.0, 3.0, 0.5, -2.0}) {
    Shot shot;
    shot.camera = site * (kEarthRadius + 300.0);
    shot.up_hint = l.up;
    // The horizon's dip at 300 m is 0.56°.
    shot.forward = direction(l, 0.0, -0.56);
    shot.fov_deg = 2.0;
    shot.width = 8;
    shot.height = 64;
    shot.ground_offset_m = 0.0;
    // Reversed-Z: standard depth with a 10 cm near plane quantises the
    // distance of these far ground points by ~2 % per float step (the test
    // would see the engine's depth precision, not the pass).
    shot.encoding = DepthEncoding::reversed_z;
    shot.sun = direction(l, 120.0, sun_elevation);
    EngineFrame e = make_engine_frame(shot);
    for (auto& c : e.buffers.colour) c = glm::vec3(0.0f);
    const std::vector<glm::vec3> image = run(e);
    ASSERT_TRUE(all_finite(image));
    double worst = 0.0;
    int worst_row = -1;
    const int x = shot.width / 2;
    for (int y = 1; y + 1 < shot.height; ++y) {
      const size_t a = size_t(y - 1) * size_t(shot.width) + size_t(x), b = a + size_t(shot.width),
                   c = b + size_t(shot.width);
      const bool surface = e.buffers.depth[b] > 0.0f;
      if ((e.buffers.depth[a] > 0.0f) != surface || (e.buffers.depth[c] > 0.0f) != surface) continue;
      const double la = luminance(image[a]), lb = luminance(image[b]), lc = luminance(image[c]);
      const double curvature = std::abs(la - 2.0 * lb + lc) / std::max(lb, 1e-6);
      if (curvature > worst) {
        worst = curvature;
        worst_row = y;
      }
    }
    std::printf("sun %5.1f deg: largest second difference %.2e (row %d)\n", sun_elevation, worst, worst_row);
    if (worst > kSeamMaxCurvature)
      for (int y = std::max(worst_row - 4, 0); y < std::min(worst_row + 5, shot.height); ++y) {
        const size_t i = size_t(y) * size_t(shot.width) + size_t(x);
        std::printf("  row %2d depth %.9f luminance %.5g\n", y, double(e.buffers.depth[i]), luminance(image[i]));
      }
    EXPECT_LE(worst, kSeamMaxCurvature) << "sun elevation " << sun_elevation;
  }
}

// From 1 m above the ground to 100 planet radii, looking down at the same
// ground point (straight down, and 45° off the vertical): no NaN anywhere in
// the image, and no jump — the "hitch" users report when a camera leaves
// the atmosphere (here the pass switches from the sky-view table to
// evaluating every ray from the top of the atmosphere) or, lower, when the
// surfaces switch from the aerial-perspective volume to the exact
// evaluation (mixed between 15 and 25 km: kVolumeBlendAltitude,
// kVolumeMaxAltitude). The
// probe's radiance grows steeply but smoothly with altitude (the air
// column in front of the ground), so the test bounds its second difference
// over altitudes stepping by a factor 1.25, |P(k-1) - 2 P(k) + P(k+1)| /
// P(k) <= kAltitudeMaxCurvature (the largest measured, 6.6 % at 15 km,
// is the curvature of the radiance itself: no switch happens there), and
// the change across each switch (0.5 % below to 0.5 % above it) by
// kSwitchMaxStep.
constexpr double kAltitudeMaxCurvature = 0.08;
constexpr double kSwitchMaxStep = 0.03;

TEST_F(Plugin, AltitudeSweepHasNoHitch) {
  const glm::dvec3 site = glm::normalize(glm::dvec3(0.6, -0.2, 0.77));
  const LocalFrame l = local_frame(site);
  const double top = earth_->top_radius_m - earth_->bottom_radius_m;
  std::vector<double> altitudes;
  for (double h = 1.0; h < 100.0 * kEarthRadius; h *= 1.25) altitudes.push_back(h);
  const double volume_top = atmos::gpu::kVolumeMaxAltitude;
  for (double switch_altitude : {top, volume_top, atmos::gpu::kVolumeBlendAltitude}) {
    altitudes.push_back(switch_altitude * 0.995);
    altitudes.push_back(switch_altitude * 1.005);
  }
  std::sort(altitudes.begin(), altitudes.end());
  for (double zenith_angle : {0.0, 45.0}) {
    std::vector<double> probes;
    for (double h : altitudes) {
      // The camera above the point `site` seen at `zenith_angle` from its
      // vertical; it looks at that point.
      const glm::dvec3 target = site * kEarthRadius;
      const glm::dvec3 towards_camera = direction(l, 180.0, 90.0 - zenith_angle);
      // Distance along towards_camera to altitude h (law of cosines).
      const double b = glm::dot(target, towards_camera);
      const double R = kEarthRadius + h;
      const double distance = -b + std::sqrt(b * b - glm::dot(target, target) + R * R);
      Shot shot;
      shot.camera = target + towards_camera * distance;
      shot.forward = -towards_camera;
      shot.up_hint = std::abs(zenith_angle) < 1.0 ? l.north : l.up;
      shot.fov_deg = 10.0;
      shot.width = 15;
      shot.height = 15;
      shot.ground_offset_m = 0.0;
      shot.encoding = DepthEncoding::reversed_z;
      shot.sun = direction(l, 60.0, 30.0);
      EngineFrame e = make_engine_frame(shot);
      const std::vector<glm::vec3> image = run(e);
      ASSERT_TRUE(all_finite(image)) << "altitude " << h;
      probes.push_back(luminance(image[size_t(7) * 15 + 7]));
      ASSERT_GT(probes.back(), 0.0) << "altitude " << h;
    }
    double worst = 0.0, worst_altitude = 0.0, top_step = 0.0, volume_step = 0.0;
    for (size_t k = 0; k < altitudes.size(); ++k) {
      const double step = k > 0 ? std::abs(probes[k] - probes[k - 1]) / std::max(probes[k], probes[k - 1]) : 0.0;
      if (altitudes[k] == top * 1.005) top_step = step;
      if (altitudes[k] == volume_top * 1.005) volume_step = step;
      // The second difference over the geometric steps (skipping the two
      // extra points at the top, tested by the step across it).
      if (k == 0 || k + 1 == altitudes.size()) continue;
      if (std::abs(altitudes[k] / altitudes[k - 1] - 1.25) > 1e-9 || std::abs(altitudes[k + 1] / altitudes[k] - 1.25) > 1e-9)
        continue;
      const double curvature = std::abs(probes[k - 1] - 2.0 * probes[k] + probes[k + 1]) / probes[k];
      if (curvature > worst) {
        worst = curvature;
        worst_altitude = altitudes[k];
      }
      EXPECT_LE(curvature, kAltitudeMaxCurvature) << zenith_angle << "° at " << altitudes[k] << " m";
    }
    std::printf("%2.0f deg off the vertical, 1 m to 100 planet radii: largest second difference %.3f (at %.4g m), "
                "step across the top of the atmosphere %.4f, across the volume's top %.4f; %.5g cd/m2 at 1 m, "
                "%.5g cd/m2 from 100 radii\n",
                zenith_angle, worst, worst_altitude, top_step, volume_step, probes.front(), probes.back());
    EXPECT_LE(top_step, kSwitchMaxStep) << zenith_angle << "°";
    EXPECT_LE(volume_step, kSwitchMaxStep) << zenith_angle << "°";
  }
}

// Seen from space, the atmosphere over the night side is dark: the limb on
// the side away from the sun is at least 1000 times darker than the lit limb
// (Jošth n.d.: the planet's shadow in the atmosphere).
TEST_F(Plugin, PlanetShadowDarkensTheNightSideSeenFromSpace) {
  Shot shot;
  shot.camera = glm::dvec3(0.0, -4.0 * kEarthRadius, 0.0);
  shot.forward = glm::dvec3(0.0, 1.0, 0.0);
  shot.up_hint = glm::dvec3(0.0, 0.0, 1.0);
  shot.fov_deg = 36.0;
  shot.width = 96;
  shot.height = 96;
  shot.ground_offset_m = -2e6;  // the engine draws nothing: the pass's sphere
  shot.sun = glm::dvec3(1.0, 0.0, 0.0);  // the terminator splits the disc in two, lit on the right (+x)
  EngineFrame e = make_engine_frame(shot);
  const std::vector<glm::vec3> image = run(e);
  ASSERT_TRUE(all_finite(image));
  // The limb is ~14.5° from the centre at 4 radii; look for the brightest
  // pixel in the left and right thirds of the middle row.
  double lit = 0.0, dark = 0.0;
  const int y = shot.height / 2;
  for (int x = 0; x < shot.width; ++x) {
    const double value = luminance(image[size_t(y) * size_t(shot.width) + size_t(x)]);
    if (x < shot.width / 3) dark = std::max(dark, value);
    if (x >= 2 * shot.width / 3) lit = std::max(lit, value);
  }
  std::printf("limb from 4 planet radii: lit side %.4g cd/m2, night side %.4g cd/m2\n", lit, dark);
  EXPECT_GT(lit, 100.0);
  EXPECT_LT(dark, 1e-3 * lit);
}

// Light shafts: a wall of the engine's geometry between the sun and part of
// the view (in the shadow map only) removes single scattering from the view
// rays behind it. With black surfaces the image is the in-scatter: a point
// seen through the shadowed air gets less than the same point without the
// wall, and the sky far from the shadowed region does not change.
constexpr double kDarkSurfaceNits = 10.0;  // a dark rock in daylight, cd/m²

TEST_F(Plugin, ShadowedAirScattersLess) {
  Shot shot = comparison_shots()[0].second;
  shot.sun = direction(local_frame(glm::normalize(shot.camera)), 20.0, 10.0);
  shot.width = 64;
  shot.height = 48;
  const glm::dvec3 up = glm::normalize(shot.camera);
  EngineFrame lit_frame = make_engine_frame(shot);
  for (auto& c : lit_frame.buffers.colour) c = glm::vec3(0.0f);
  EngineFrame shadowed_frame = lit_frame;
  // An orthographic shadow map looking along -sun, centred on the camera,
  // 40 km wide and 40 km deep (engine units: km).
  const PlanetFrame f = engine_frame();
  const glm::dvec3 centre = to_world(f, shot.camera);
  const glm::dvec3 sun = glm::normalize(shot.sun);
  const glm::dmat4 light_view = glm::lookAt(centre + sun * 20.0, centre, up);
  const glm::dmat4 light_projection = glm::ortho(-20.0, 20.0, -20.0, 20.0, 0.0, 40.0);
  const glm::dmat4 shadow_matrix = light_projection * light_view;
  const int size = 128;
  auto make_map = [&](bool wall) {
    atmos::gpu::CpuEngineBuffers b = lit_frame.buffers;
    b.shadow_width = b.shadow_height = size;
    b.shadow_depth.assign(size_t(size) * size, glm::vec3(1.0f));
    if (wall) {
      // Occluders 15 km towards the sun over the left half of the map.
      for (int y = 0; y < size; ++y)
        for (int x = 0; x < size / 2; ++x) b.shadow_depth[size_t(y) * size + size_t(x)] = glm::vec3(0.25f);
    }
    return b;
  };
  lit_frame.buffers = make_map(false);
  shadowed_frame.buffers = make_map(true);
  lit_frame.input.shadow_matrix = shadowed_frame.input.shadow_matrix = shadow_matrix;
  const std::vector<glm::vec3> lit = run(lit_frame);
  const std::vector<glm::vec3> shadowed = run(shadowed_frame);
  ASSERT_TRUE(all_finite(lit));
  ASSERT_TRUE(all_finite(shadowed));
  double lit_sum = 0.0, shadowed_sum = 0.0;
  int darker = 0, brighter = 0;
  for (size_t i = 0; i < lit.size(); ++i) {
    if (lit_frame.buffers.depth[i] >= 1.0f) continue;
    lit_sum += luminance(lit[i]);
    shadowed_sum += luminance(shadowed[i]);
    if (luminance(shadowed[i]) < 0.98 * luminance(lit[i])) ++darker;
    if (luminance(shadowed[i]) > luminance(lit[i]) * (1.0 + 1e-4)) ++brighter;
  }
  std::printf("in-scatter over the surfaces: %.4g without the wall, %.4g with it; %d pixels darker, %d brighter\n",
              lit_sum, shadowed_sum, darker, brighter);
  EXPECT_LT(shadowed_sum, 0.95 * lit_sum);
  EXPECT_GT(darker, 0);
  EXPECT_EQ(brighter, 0);
  // The CPU twin agrees on the shadowed frame (same shadow map, sampled the
  // same way).
  std::vector<glm::ivec2> pixels;
  for (int y = 0; y < shot.height; y += 5)
    for (int x = 0; x < shot.width; x += 5) pixels.push_back({x, y});
  const std::vector<glm::vec3> cpu = atmos::gpu::composite_cpu(*earth_, *tables_, engine_frame(),
                                                               shadowed_frame.input, shadowed_frame.buffers, pixels);
  // The surfaces here are black, so a pixel's value is its in-scatter alone,
  // a few cd/m² for the ground near the camera. Measured: the GPU is lower
  // by ~0.05 cd/m² everywhere there (also without the wall: not the
  // shadows), and by up to ~1 cd/m² where the wall's shadow boundary, which
  // runs through the camera, crosses the march's samples. Relative to a
  // dark real surface (kDarkSurfaceNits) behind: RMS 1.8 %, max 11 %.
  // The cause of the uniform offset is not known; the bounds are the
  // measured values plus margin.
  double max_relative = 0.0, sum_squares = 0.0;
  for (size_t k = 0; k < pixels.size(); ++k) {
    const size_t i = size_t(pixels[k].y) * size_t(shot.width) + size_t(pixels[k].x);
    const double d =
        glm::length(glm::dvec3(shadowed[i]) - glm::dvec3(cpu[k])) / std::max(luminance(cpu[k]), kDarkSurfaceNits);
    max_relative = std::max(max_relative, d);
    sum_squares += d * d;
  }
  const double rms = std::sqrt(sum_squares / double(pixels.size()));
  std::printf("shadowed frame, GPU vs CPU: max relative %.2e, rms %.2e\n", max_relative, rms);
  atmos_test::record_figure("shadowed frame: max relative difference", max_relative, "", "<= 0.15");
  atmos_test::record_figure("shadowed frame: RMS relative difference", rms, "", "<= 0.03");
  EXPECT_LE(max_relative, 0.15);
  EXPECT_LE(rms, 0.03);
}

// Bad input: a clear error and nothing drawn, never a crash or NaN.
TEST_F(Plugin, RejectsBadInput) {
  Shot shot = comparison_shots()[0].second;
  EngineFrame e = make_engine_frame(shot);
  GpuEngineFrame gpu;
  const int w = shot.width, h = shot.height;
  e.input.depth = gpu.add(upload_r32f(w, h, e.buffers.depth));
  e.input.colour = gpu.add(upload_rgb32f(w, h, e.buffers.colour));
  auto expect_error = [&](const FrameInput& input, const char* what, const char* fragment) {
    try {
      pass_->render(input);
      ADD_FAILURE() << what << ": no error";
    } catch (const atmos::Error& error) {
      EXPECT_NE(std::string(error.what()).find(fragment), std::string::npos) << what << ": " << error.what();
    }
  };
  FrameInput in = e.input;
  in.depth = 0;
  expect_error(in, "missing depth", "no depth texture");
  in = e.input;
  in.depth = 987654;
  expect_error(in, "not a texture", "not a texture");
  in = e.input;
  in.colour = gpu.add(upload_rgb32f(w + 1, h, std::vector<glm::vec3>(size_t(w + 1) * size_t(h))));
  expect_error(in, "mismatched sizes", "the frame is");
  in = e.input;
  in.depth = e.input.colour;
  expect_error(in, "colour as depth", "not a depth format");
  in = e.input;
  in.projection = glm::dmat4(0.0);
  expect_error(in, "degenerate projection", "degenerate projection");
  in = e.input;
  in.projection = glm::ortho(-1.0, 1.0, -1.0, 1.0, 0.1, 100.0);
  expect_error(in, "orthographic projection", "not a perspective");
  in = e.input;
  in.view[0][0] = 2.0;
  expect_error(in, "scaled view", "rotation + translation");
  in = e.input;
  in.view[3][0] = std::nan("");
  expect_error(in, "NaN view", "not finite");
  in = e.input;
  in.sun_direction = glm::dvec3(0.0);
  expect_error(in, "zero sun", "sun direction");
  in = e.input;
  in.output = in.colour;
  expect_error(in, "output = input", "feedback loop");
  in = e.input;
  in.nits_per_unit = 0.0;
  expect_error(in, "zero nits per unit", "nits_per_unit");
  in = e.input;
  in.depth_encoding = DepthEncoding::logarithmic;
  in.log_depth_far = -1.0;
  expect_error(in, "bad log far", "log_depth_far");
  in = e.input;
  in.shadow_map = in.depth;
  in.shadow_matrix = glm::perspective(1.0, 1.0, 1.0, 10.0);
  expect_error(in, "perspective shadow matrix", "not affine");
  in = e.input;
  in.width = 0;
  expect_error(in, "empty frame", "frame size");
  in = e.input;
  in.view = glm::translate(glm::dmat4(1.0), glm::dvec3(-1e13));
  expect_error(in, "absurd camera", "absurdly far");
  // Bad moons (atmos::validate_moons' messages).
  const atmos::Moon good{{0.0, 0.0, 4e8}, 1.7e6};
  in = e.input;
  in.moons.assign(atmos::kMaxMoons + 1, good);
  expect_error(in, "too many moons", "at most");
  in.moons = {atmos::Moon{{std::nan(""), 0.0, 4e8}, 1.7e6}};
  expect_error(in, "NaN moon", "moon 1: its centre is not finite");
  in.moons = {good, atmos::Moon{{0.0, 0.0, 4e8}, 0.0}};
  expect_error(in, "moon of radius 0", "moon 2: its radius");
  in.moons = {atmos::Moon{{0.0, 0.0, kEarthRadius + 50e3}, 1000.0}};
  expect_error(in, "moon in the atmosphere", "into the atmosphere");

  // A camera inside the planet is moved up to its surface: an image, finite.
  Shot inside = shot;
  inside.camera = glm::normalize(shot.camera) * (kEarthRadius - 500.0);
  inside.ground_offset_m = -1e7;
  EngineFrame below = make_engine_frame(inside);
  const std::vector<glm::vec3> image = run(below);
  EXPECT_TRUE(all_finite(image));
  // Nothing was left broken: the next valid frame renders.
  EXPECT_NO_THROW(pass_->render(e.input));

  // Bad planet frames.
  EXPECT_THROW(atmos::AtmospherePass(*earth_, *tables_, PlanetFrame{glm::dvec3(0.0), 0.0}), atmos::Error);
  EXPECT_THROW(atmos::AtmospherePass(*earth_, *tables_, PlanetFrame{glm::dvec3(std::nan("")), 1.0}), atmos::Error);
}

// Totality in the pass (FrameInput::moons): a moon 0.28° in radius on the
// sun seen from a camera on the ground, the surfaces lit by the pass
// (G-buffer). Against the same frame without the moon, every sky pixel and
// every surface pixel is much darker (measured: printed), yet the sky stays
// finite and > 0 (the light scattered in from the sunlit air beyond the
// umbra); looking at the sun, the moon hides its disc (the corona, ~4e-6 of
// the disc's radiance, remains around it). A frame without moons after
// the eclipse is the same as before it (the eclipse leaves no state).
TEST_F(Plugin, TotalEclipseDarkensSkyAndGround) {
  Shot day_shot;
  for (auto& [name, shot] : comparison_shots())
    if (name == "eclipse_ground") day_shot = shot;
  ASSERT_FALSE(day_shot.moons.empty());
  Shot eclipse_shot = day_shot;
  day_shot.moons.clear();
  EngineFrame day_frame = make_engine_frame(day_shot);
  EngineFrame eclipse_frame = make_engine_frame(eclipse_shot);
  const std::vector<glm::vec3> day = run(day_frame);
  const std::vector<glm::vec3> eclipse = run(eclipse_frame);
  ASSERT_TRUE(all_finite(eclipse));
  double sky_max = 0.0, ground_max = 0.0, sky_min = 1.0, ground_min = 1.0;
  int sky = 0, ground = 0;
  for (size_t i = 0; i < day.size(); ++i) {
    const double ratio = luminance(eclipse[i]) / luminance(day[i]);
    if (day_frame.buffers.depth[i] >= 1.0f) {
      ++sky;
      EXPECT_GT(luminance(eclipse[i]), 0.0) << "sky pixel " << i;
      sky_max = std::max(sky_max, ratio);
      sky_min = std::min(sky_min, ratio);
    } else {
      ++ground;
      EXPECT_GE(luminance(eclipse[i]), 0.0) << "surface pixel " << i;
      ground_max = std::max(ground_max, ratio);
      ground_min = std::min(ground_min, ratio);
    }
  }
  std::printf("totality / day: sky %.2e..%.2e (%d pixels), surfaces %.2e..%.2e (%d pixels)\n", sky_min, sky_max, sky,
              ground_min, ground_max, ground);
  ASSERT_GT(sky, 0);
  ASSERT_GT(ground, 0);
  EXPECT_LT(sky_max, 1e-2);
  EXPECT_LT(ground_max, 1e-2);

  // The sun: 2° wide, 32 x 32 pixels.
  Shot sun_shot = eclipse_shot;
  sun_shot.forward = glm::normalize(sun_shot.sun);
  sun_shot.up_hint = glm::normalize(sun_shot.camera);
  sun_shot.fov_deg = 2.0;
  sun_shot.width = sun_shot.height = 32;
  EngineFrame sun_eclipse_frame = make_engine_frame(sun_shot);
  const std::vector<glm::vec3> sun_eclipse = run(sun_eclipse_frame);
  sun_shot.moons.clear();
  EngineFrame sun_day_frame = make_engine_frame(sun_shot);
  const std::vector<glm::vec3> sun_day = run(sun_day_frame);
  ASSERT_TRUE(all_finite(sun_eclipse));
  double day_peak = 0.0, eclipse_peak = 0.0;
  for (size_t i = 0; i < sun_day.size(); ++i) {
    day_peak = std::max(day_peak, luminance(sun_day[i]));
    eclipse_peak = std::max(eclipse_peak, luminance(sun_eclipse[i]));
  }
  std::printf("looking at the sun: peak %.3g cd/m2 by day, %.3g in totality\n", day_peak, eclipse_peak);
  EXPECT_GT(day_peak, 1e8);
  EXPECT_LT(eclipse_peak, 1e-4 * day_peak);

  // No state left behind: the day frame again, bit for bit.
  EngineFrame again_frame = make_engine_frame(day_shot);
  const std::vector<glm::vec3> again = run(again_frame);
  EXPECT_TRUE(again == day);
}

// The GLSL library for engines compiles in an engine's own shader and gives
// what the pass gives: a full-screen shader that computes, for each pixel,
// surface colour x transmittance + radiance to the point with
// atmos_radiance_to_point (the exact two-lookup evaluation), compared with
// the pass's output for the same frame at a 10 km camera (the pass reads its
// aerial-perspective volume there: the two methods differ by 3.8 % at this
// point with these small tables, the volume being the nearer to the
// reference — tests/aerial_perspective_accuracy.cpp), and the irradiance and
// transmittance functions are finite and positive in daylight.
TEST_F(Plugin, GlslLibraryForEnginesMatchesThePass) {
  // The parameter block at a binding other than the default.
  const std::string library = pass_->glsl_library(20, 5);
  EXPECT_NE(library.find("atmos_radiance_to_point"), std::string::npos);
  const std::string fragment = "#version 450 core\n" + library + R"(
layout(location = 0) uniform vec3 camera_position;
layout(location = 1) uniform vec3 sun;
layout(location = 2) uniform vec3 offset;
layout(location = 0) out vec4 result;
void main() {
  vec3 transmittance;
  vec3 in_scatter = atmos_radiance_to_point(camera_position, offset, sun, transmittance);
  vec3 sky;
  vec3 point = camera_position + offset;
  vec3 direct = atmos_sun_and_sky_irradiance(point, normalize(point), sun, sky);
  vec3 to_sun = atmos_transmittance_to_sun(point, sun);
  vec3 sky_transmittance;
  vec3 sky_radiance = atmos_sky_radiance(camera_position, normalize(offset), sun, sky_transmittance);
  bool ok = all(greaterThan(direct, vec3(0.0))) && all(greaterThan(sky, vec3(0.0))) &&
            all(greaterThan(to_sun, vec3(0.0))) && all(greaterThan(sky_radiance, vec3(0.0)));
  result = vec4(vec3(300.0) * transmittance + in_scatter, ok ? 1.0 : 0.0);
}
)";
  const GLuint program = atmos_test::fullscreen_program(fragment);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  ASSERT_TRUE(linked);

  // A camera at 10 km looking 20° down at the ground sphere; one pixel.
  Shot shot = comparison_shots()[1].second;
  shot.width = 1;
  shot.height = 1;
  shot.fov_deg = 1.0;
  shot.ground_offset_m = 0.0;
  EngineFrame e = make_engine_frame(shot);
  for (auto& c : e.buffers.colour) c = glm::vec3(300.0f);
  const std::vector<glm::vec3> from_pass = run(e);
  // The same point: the ground along the view direction.
  const double t = hit_sphere(shot.camera, shot.forward, glm::dvec3(0.0), kEarthRadius);
  ASSERT_GT(t, 0.0);
  const glm::vec3 offset(shot.forward * t);
  glProgramUniform3f(program, 0, float(shot.camera.x), float(shot.camera.y), float(shot.camera.z));
  const glm::vec3 sun(glm::normalize(shot.sun));
  glProgramUniform3f(program, 1, sun.x, sun.y, sun.z);
  glProgramUniform3f(program, 2, offset.x, offset.y, offset.z);
  pass_->bind_textures(20, 5);
  const std::vector<float> pixel = atmos_test::draw_fullscreen(program, 1, 1);
  glDeleteProgram(program);
  const glm::vec3 from_library(pixel[0], pixel[1], pixel[2]);
  const double difference = glm::length(glm::dvec3(from_library) - glm::dvec3(from_pass[0])) / luminance(from_pass[0]);
  std::printf("10 km, 20 deg down: pass %.5g cd/m2, engine library %.5g cd/m2 (relative difference %.2e)\n",
              luminance(from_pass[0]), luminance(from_library), difference);
  EXPECT_EQ(pixel[3], 1.0f) << "an irradiance, transmittance or sky radiance was not positive";
  EXPECT_LE(difference, 0.05);
}

}  // namespace
