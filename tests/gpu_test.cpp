// The OpenGL renderer against its CPU twin and the headless context. Its
// host code that needs no context (camera model and validation, programs'
// source, half texels, image files) is tested in gpu_host_test.cpp.
//
// The GPU tests FAIL (never skip) when no OpenGL 4.5 context can be created:
// CI runs them on Mesa llvmpipe, and the GL path must be exercised there.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/colour.hpp"
#include "atmos/image.hpp"
#include "atmos/plugin.hpp"
#include "atmos/post.hpp"
#include "atmos/renderer.hpp"
#include "atmos/sky.hpp"
#include "atmos/tables.hpp"
#include "data/embedded_files.hpp"
#include "data/glsl_prune.hpp"
#include "gpu/gl_util.hpp"
#include "gpu/shader_source.hpp"
#include "physics/parameters.hpp"
#include "physics/stars_cpp.hpp"
#include "figures.hpp"
#include "fullscreen_program.hpp"
#include "gpu_fixture.hpp"

namespace {

using atmos::Camera;
using atmos::Image;
using atmos::Projection;
using atmos::TexturePrecision;

constexpr double kEarthRadius = 6371e3;

glm::dvec3 sun_at(double elevation_deg, double azimuth_deg) {
  // Azimuth from +y (the cameras' forward) towards +x (their right).
  const double e = glm::radians(elevation_deg);
  const double a = glm::radians(azimuth_deg);
  return {std::cos(e) * std::sin(a), std::cos(e) * std::cos(a), std::sin(e)};
}

struct Scene {
  const char* name;
  Camera camera;
  glm::dvec3 sun;
  bool sees_ground = true;  // see the tolerances below
};

std::vector<Scene> scenes() {
  std::vector<Scene> out;
  Camera ground;
  ground.position = {0.0, 0.0, kEarthRadius + 2.0};
  ground.forward = {0.0, 1.0, 0.0};
  ground.up = {0.0, 0.0, 1.0};
  ground.fov_deg = 60.0;
  ground.width = 64;
  ground.height = 48;
  // Sun 20° up, just outside the horizontal field (±37.6°): its aerosol halo
  // is in the picture, its disc (a fraction of a pixel) is not.
  out.push_back({"ground_horizon", ground, sun_at(20.0, 45.0)});

  Camera high = ground;
  high.position = {0.0, 0.0, kEarthRadius + 10e3};
  high.forward = {0.0, 1.0, -0.15};  // the horizon and the ground below it
  out.push_back({"altitude_10km", high, sun_at(20.0, 45.0)});

  Camera orbit = ground;
  orbit.position = {0.0, -2.0 * kEarthRadius, 0.0};  // two planet radii from the centre
  orbit.forward = {0.0, 1.0, 0.0};                    // towards the planet, whose disc spans ±30°
  orbit.fov_deg = 70.0;
  out.push_back({"orbit", orbit, glm::normalize(glm::dvec3(1.0, -0.4, 0.5))});

  Camera fisheye = ground;
  fisheye.forward = {0.0, 0.0, 1.0};  // the zenith
  fisheye.up = {0.0, 1.0, 0.0};
  fisheye.projection = Projection::fisheye;
  fisheye.fov_deg = 180.0;
  out.push_back({"fisheye_sky", fisheye, sun_at(20.0, 45.0), false});

  Camera panorama = high;
  panorama.forward = {0.0, 1.0, 0.0};
  panorama.projection = Projection::equirect;
  out.push_back({"equirect_10km", panorama, sun_at(20.0, 45.0)});

  // Twilight: the low-sun path (the sky-view table's integrated single
  // scattering in the atmosphere, each ray's own integration in space).
  out.push_back({"twilight", ground, sun_at(-3.0, 10.0)});
  Camera terminator = orbit;
  terminator.position = {0.0, -1.2 * kEarthRadius, 0.0};
  terminator.fov_deg = 120.0;
  out.push_back({"orbit_terminator", terminator, glm::dvec3(1.0, 0.0, 0.0)});
  return out;
}

// The tables rounded to half floats as the renderer rounds them for RGB16F
// textures (the transmittance stays float, as in the renderer).
atmos::Tables round_to_half(atmos::Tables tables) {
  const bool srgb = atmos::physics::srgb_channels(tables.wavelengths_nm);
  auto round = [srgb](std::vector<glm::vec3>& texels) {
    for (glm::vec3& t : texels) t = atmos::gpu::half_texel(t, srgb);
  };
  round(tables.set.scattering);
  round(tables.set.single_aerosol);
  round(tables.set.indirect_irradiance);
  round(tables.set.multiple_scattering);
  return tables;
}

struct Difference {
  double max_relative = 0.0;  // max over pixels of |gpu - cpu| / scale
  double rms_relative = 0.0;
  int worst_x = -1;
  int worst_y = -1;
  double worst_cpu = 0.0;
  double worst_gpu = 0.0;
};

// Per pixel, the largest channel difference relative to the pixel's CPU
// luminance. A floor of 1e-4 of the image's mean luminance keeps black pixels
// (outside the fisheye circle, space) from dividing by zero: there an
// absolute difference of 1e-4 of the mean level is invisible.
Difference compare(const Image& gpu, const Image& cpu) {
  Difference d;
  double mean = 0.0;
  const size_t n = size_t(cpu.width) * size_t(cpu.height);
  for (size_t i = 0; i < n; ++i)
    mean += std::abs(atmos::srgb_luminance({cpu.rgb[3 * i], cpu.rgb[3 * i + 1], cpu.rgb[3 * i + 2]}));
  mean /= double(n);
  double sum_squares = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const glm::dvec3 c(cpu.rgb[3 * i], cpu.rgb[3 * i + 1], cpu.rgb[3 * i + 2]);
    const glm::dvec3 g(gpu.rgb[3 * i], gpu.rgb[3 * i + 1], gpu.rgb[3 * i + 2]);
    const double scale = std::max(std::abs(atmos::srgb_luminance(c)), 1e-4 * mean);
    const glm::dvec3 delta = glm::abs(g - c);
    const double relative = std::max({delta.x, delta.y, delta.z}) / scale;
    sum_squares += relative * relative;
    if (!(relative <= d.max_relative)) {  // also catches NaN
      d.max_relative = relative;
      d.worst_x = int(i % size_t(cpu.width));
      d.worst_y = int(i / size_t(cpu.width));
      d.worst_cpu = atmos::srgb_luminance(c);
      d.worst_gpu = atmos::srgb_luminance(g);
    }
  }
  d.rms_relative = std::sqrt(sum_squares / double(n));
  return d;
}

bool all_finite(const Image& image) {
  return std::all_of(image.rgb.begin(), image.rgb.end(), [](float v) { return std::isfinite(v); });
}

// The GPU suite: one context and the small Earth tables (gpu_fixture.hpp).
class Gpu : public atmos_test::EarthGpuTest {};

TEST_F(Gpu, HeadlessContextReportsRenderer) {
  const std::string renderer = context_->renderer_string();
  std::printf("OpenGL renderer: %s\n", renderer.c_str());
  EXPECT_NE(renderer.find("OpenGL 4."), std::string::npos) << renderer;
}

// Tolerances of the GPU image against the CPU twin, relative to the pixel
// luminance. On llvmpipe (Mesa 22.3, LLVM 15) with the small tables above the
// largest difference of these scenes is below 2e-3 per pixel and 6e-4 RMS over
// an image (the test prints and records them per scene).
// Where the difference comes from (checked stage by stage):
//  - not the texture filtering: llvmpipe filters float textures with float
//    weights (a lookup at weight 0.302656 between texels 0 and 1 returns
//    0.302656, not an 8-bit 77/256);
//  - cameras in the atmosphere read this frame's sky-view table (see
//    sky_radiance). Its texels, computed by the GPU pass and by the CPU, agree
//    to 1e-4 wherever the radiance is not negligible (checked by reading the
//    texture back); the 1e-3 differences come from the lookup, whose texture
//    coordinates come from acos and atan of the view direction: llvmpipe
//    approximates them differently from glibc, and a coordinate difference of
//    1e-3 texel near the horizon, where the table changes fastest, is a 1e-3
//    change of the radiance. Cameras in space evaluate each ray and agree to
//    7e-4;
//  - the view rays differ by 1-2 ulp (~1.5e-7): llvmpipe's sin/cos/tan/sqrt
//    are not glibc's;
//  - float32 planet-centred coordinates amplify that where a ray reaches the
//    ground: the ground point's radius is quantised to 0.5 m (the float ulp
//    at 6.4e6 m) and the tables' radius coordinate rho = sqrt(r² - R²) turns
//    r = R + 0.5 m into rho = 2.5 km, 0.2 % of the table's range. A 2-ulp ray
//    change that moves the ground point across such a step changes the sun's
//    transmittance by 6e-4 (measured at the equirect_10km worst pixel). The
//    closer the camera is to the ground, the larger the effect: over 300
//    random cameras and suns (32x24 pixels) the worst
//    pixel differed by 1.0e-2 in daylight (camera 1 m above the ground,
//    looking 4° down at a point 15 m away) and 1.8e-2 at night (1e-3 cd/m²).
// Bounds: 1e-2 per pixel where the ground is in view (what float32 geometry
// allows in daylight, on any GPU whose sin/cos differ from glibc's by an ulp;
// not just what llvmpipe happens to reach on these scenes), 3e-3 for the
// sky-only fisheye (the sky-view lookup); and an RMS of 1e-3 over the image,
// which a systematic error of 0.3 % over a third of the image would already
// exceed.
// Half-precision textures are compared first with the CPU reading the same
// tables rounded to half (the renderer rounds on the CPU with
// glm::packHalf1x16, as this test does; the transmittance stays float in
// both): same bounds. Then with the float tables, which adds the rounding of
// 11-bit significands (2^-11 = 5e-4 per texel, several lookups per pixel):
// RMS 1e-3, max 1e-2 as above.
constexpr double kGroundMaxRelative = 1e-2;
constexpr double kSkyMaxRelative = 3e-3;
constexpr double kRmsRelative = 1e-3;
constexpr double kHalfVsFloatMaxRelative = 1e-2;
constexpr double kHalfVsFloatRmsRelative = 1e-3;

void report(const char* scene, const char* what, const Difference& d) {
  std::printf("%-15s %-22s max %.3e at (%d, %d) [cpu %.6g, gpu %.6g cd/m2]  rms %.3e\n", scene, what,
              d.max_relative, d.worst_x, d.worst_y, d.worst_cpu, d.worst_gpu, d.rms_relative);
  atmos_test::record_figure(std::string(what) + ", " + scene + ": max relative difference", d.max_relative, "", "");
  atmos_test::record_figure(std::string(what) + ", " + scene + ": RMS relative difference", d.rms_relative, "", "");
}

// Renders every scene on the GPU and on the CPU and checks the bounds above.
void expect_gpu_matches_cpu(atmos::Renderer& renderer, const atmos::Atmosphere& atmosphere,
                            const atmos::Tables& tables, const char* label, double rms_bound = kRmsRelative,
                            double sky_max_bound = kSkyMaxRelative) {
  for (const Scene& scene : scenes()) {
    const Image gpu = renderer.render(scene.camera, scene.sun);
    const Image cpu = atmos::render_cpu(atmosphere, tables, scene.camera, scene.sun);
    ASSERT_EQ(gpu.width, cpu.width);
    ASSERT_EQ(gpu.height, cpu.height);
    ASSERT_TRUE(all_finite(gpu)) << scene.name;
    ASSERT_TRUE(all_finite(cpu)) << scene.name;
    const Difference d = compare(gpu, cpu);
    report(scene.name, label, d);
    EXPECT_LE(d.max_relative, scene.sees_ground ? kGroundMaxRelative : sky_max_bound) << scene.name;
    EXPECT_LE(d.rms_relative, rms_bound) << scene.name;
    EXPECT_GE(renderer.last_frame_ms(), 0.0);
  }
}

// The OpenGL context rule of Renderer, AtmospherePass and PostProcess: each
// needs a current 4.5 context on the calling thread and says so when there is
// none (a new thread has no current context), and none of them makes the
// fixture's context current by itself.
TEST_F(Gpu, EveryGlClassNeedsACurrentContext) {
  std::string renderer_error, pass_error, post_error;
  std::thread other([&] {
    try {
      atmos::Renderer renderer(*earth_, *tables_);
    } catch (const atmos::Error& e) {
      renderer_error = e.what();
    }
    try {
      atmos::AtmospherePass pass(*earth_, *tables_, atmos::PlanetFrame{}, atmos::PassPrograms::none);
    } catch (const atmos::Error& e) {
      pass_error = e.what();
    }
    try {
      atmos::PostProcess post;
    } catch (const atmos::Error& e) {
      post_error = e.what();
    }
  });
  other.join();
  EXPECT_NE(renderer_error.find("atmos::Renderer needs a current OpenGL 4.5 core context"), std::string::npos)
      << renderer_error;
  EXPECT_NE(pass_error.find("needs a current OpenGL 4.5 core context"), std::string::npos) << pass_error;
  EXPECT_NE(post_error.find("atmos::PostProcess needs a current OpenGL 4.5 core context"), std::string::npos)
      << post_error;
  // On the fixture's thread, where its context is current, all three work.
  atmos::Renderer renderer(*earth_, *tables_);
  atmos::AtmospherePass pass(*earth_, *tables_, atmos::PlanetFrame{}, atmos::PassPrograms::none);
  atmos::PostProcess post;
}

TEST_F(Gpu, FullPrecisionMatchesCpu) {
  atmos::Renderer renderer(*earth_, *tables_, TexturePrecision::full);
  expect_gpu_matches_cpu(renderer, *earth_, *tables_, "full vs cpu");
}

// Spectral tables (7 wavelengths: three triples with the last one
// padded): the shader loops over the wavelength triples for the low-sun
// single scattering and the transmittance, as the CPU does; same tolerances.
TEST_F(Gpu, SpectralTablesMatchCpu) {
  atmos::Atmosphere spectral = *earth_;
  spectral.wavelengths_nm = atmos::spectral_wavelengths(7);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(spectral, options);
  atmos::Renderer renderer(spectral, tables, TexturePrecision::full);
  expect_gpu_matches_cpu(renderer, spectral, tables, "spectral full vs cpu");
}

// A double Henyey-Greenstein aerosol whose lobes change with wavelength, in
// spectral mode: the per-channel phase parameters of the parameter block and
// the phase ratio of the low-sun integration (spectral_single_scattering);
// same tolerances.
TEST_F(Gpu, WavelengthDependentAerosolPhaseMatchesCpu) {
  atmos::Atmosphere spectral = *earth_;
  spectral.wavelengths_nm = atmos::spectral_wavelengths(7);
  const atmos::PhaseFunction dhg(atmos::PhaseFunction::Kind::double_henyey_greenstein,
                                 atmos::Spectrum({400.0, 700.0}, {0.93, 0.87}),
                                 atmos::Spectrum({400.0, 700.0}, {-0.25, -0.35}),
                                 atmos::Spectrum({400.0, 700.0}, {0.85, 0.74}));
  for (atmos::Constituent& c : spectral.constituents)
    if (c.phase.kind != atmos::PhaseFunction::Kind::rayleigh) c.phase = dhg;
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(spectral, options);
  atmos::Renderer renderer(spectral, tables, TexturePrecision::full);
  expect_gpu_matches_cpu(renderer, spectral, tables, "DHG spectral vs cpu");
}

// An optically thick atmosphere (100x Earth, vertical optical depth 27 at
// 550 nm) has its mu axis warped towards log-spaced distances
// (scattering_mu_log_weight, table_coordinates.glsl scattering_u_mu) and its r axis
// following the optical depth (scattering_r_optical_depth_weight and the
// knots of scattering_r_axis, scattering_x_r_from_rho_fraction): both come
// from the parameter block, and the GPU must read the tables exactly where the
// CPU does. The RMS bound is 2e-3: measured 1.0e-3 (ground_horizon) and
// 1.1e-3 (twilight) with the mu warp alone, and the same tables without any
// warp give the same (1.02e-3, 1.12e-3), so that excess over the Earth
// scenes comes with the density (a dim sky seen from the ground), not the
// warp; with the r axis too, 1.3e-3 and 1.46e-3. The sky-only fisheye's
// worst pixel is bounded by 4e-3 instead of 3e-3: measured 3.1e-3 (a sky of
// 1.4e-3 cd/m², 1.07e-3 RMS over the image). Shaders that ignore the mu warp
// (a weight of 0) differ by factors of 2-4; shaders that ignore the r axis
// (weight 0 likewise) by 1.4-2.8 % RMS from the ground and by a factor of 50
// at 10 km: the bounds catch either.
TEST_F(Gpu, WarpedMuAxisMatchesCpu) {
  atmos::Atmosphere dense = *earth_;
  atmos::scale_density(dense, 100.0);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(dense, options);
  const atmos::physics::AtmosphereParams params = atmos::physics::make_atmosphere_params(dense, options.sizes, 0);
  ASSERT_GT(params.scattering_mu_log_weight, 0.9f);
  ASSERT_GT(params.scattering_r_optical_depth_weight, 0.4f);
  atmos::Renderer renderer(dense, tables, TexturePrecision::full);
  expect_gpu_matches_cpu(renderer, dense, tables, "warped axes vs cpu", 2e-3, 4e-3);
}

// A renderer of an atmosphere that differs from Earth in values only
// draws with the programs of Earth's renderer (gpu::shared_program): it
// links none, and its image matches its own CPU twin within the bounds of
// FullPrecisionMatchesCpu (the first scene's), not Earth's image.
TEST_F(Gpu, RendererOfTheSameStructureLinksNoProgram) {
  const Scene scene = scenes().front();
  atmos::Renderer earth(*earth_, *tables_, TexturePrecision::full);
  const Image earth_image = earth.render(scene.camera, scene.sun);
  const atmos::Atmosphere other = atmos_test::other_earth_values(*earth_);
  atmos::PrecomputeOptions options;
  options.sizes = atmos_test::small_gpu_sizes();
  const atmos::Tables tables = atmos::precompute_tables(other, options);
  const long linked = atmos::gpu::linked_program_count();
  atmos::Renderer renderer(other, tables, TexturePrecision::full);
  const Image gpu = renderer.render(scene.camera, scene.sun);
  EXPECT_EQ(atmos::gpu::linked_program_count(), linked);
  ASSERT_TRUE(all_finite(gpu));
  const Difference twin = compare(gpu, atmos::render_cpu(other, tables, scene.camera, scene.sun));
  report(scene.name, "other values vs cpu", twin);
  EXPECT_LE(twin.max_relative, kGroundMaxRelative);
  EXPECT_LE(twin.rms_relative, kRmsRelative);
  EXPECT_GT(compare(earth_image, gpu).rms_relative, 10.0 * kRmsRelative);
}

TEST_F(Gpu, HalfPrecisionMatchesCpu) {
  atmos::Renderer renderer(*earth_, *tables_, TexturePrecision::half);
  const atmos::Tables half_tables = round_to_half(*tables_);
  for (const Scene& scene : scenes()) {
    const Image gpu = renderer.render(scene.camera, scene.sun);
    const Image cpu_half = atmos::render_cpu(*earth_, half_tables, scene.camera, scene.sun);
    const Image cpu = atmos::render_cpu(*earth_, *tables_, scene.camera, scene.sun);
    ASSERT_TRUE(all_finite(gpu)) << scene.name;
    const Difference twin = compare(gpu, cpu_half);
    const Difference exact = compare(gpu, cpu);
    report(scene.name, "half vs cpu(half)", twin);
    report(scene.name, "half vs cpu(float)", exact);
    EXPECT_LE(twin.max_relative, scene.sees_ground ? kGroundMaxRelative : kSkyMaxRelative) << scene.name;
    EXPECT_LE(twin.rms_relative, kRmsRelative) << scene.name;
    EXPECT_LE(exact.max_relative, kHalfVsFloatMaxRelative) << scene.name;
    EXPECT_LE(exact.rms_relative, kHalfVsFloatRmsRelative) << scene.name;
  }
}

TEST_F(Gpu, ImageOrientationAndProjections) {
  atmos::Renderer renderer(*earth_, *tables_);
  // Pixel (0, 0) is the top-left: put the sun's disc (0.27° in radius, a
  // billion cd/m²) on the centre of pixel (16, 12), up and to the left of
  // the image centre; its pixels of 1.25° leave the disc in that pixel alone.
  Camera camera = scenes()[0].camera;  // forward +y, up +z, right +x, 60° over 48 rows
  const double scale = std::tan(glm::radians(30.0)) / 24.0;
  const glm::dvec3 sun = glm::normalize(glm::dvec3((16.5 - 32.0) * scale, 1.0, (24.0 - 12.5) * scale));
  for (const Image& image : {renderer.render(camera, sun), atmos::render_cpu(*earth_, *tables_, camera, sun)}) {
    size_t brightest = 0;
    for (size_t i = 0; i < image.rgb.size() / 3; ++i)
      if (image.rgb[3 * i + 1] > image.rgb[3 * brightest + 1]) brightest = i;
    EXPECT_EQ(brightest % 64, 16u);
    EXPECT_EQ(brightest / 64, 12u);
  }

  // Fisheye: black outside the circle, sky inside.
  Camera fisheye = scenes()[3].camera;
  const Image sky = renderer.render(fisheye, sun_at(20.0, 45.0));
  EXPECT_EQ(sky.rgb[0], 0.0f);
  EXPECT_GT(sky.rgb[(size_t(24) * 64 + 32) * 3 + 1], 0.0f);

  // A camera in space looking away from the planet and the sun sees black.
  Camera space;
  space.position = {0.0, 0.0, 3.0 * kEarthRadius};
  space.forward = {0.0, 0.0, 1.0};
  space.up = {0.0, 1.0, 0.0};
  space.width = 8;
  space.height = 8;
  const Image black = renderer.render(space, {1.0, 0.0, 0.0});
  EXPECT_TRUE(std::all_of(black.rgb.begin(), black.rgb.end(), [](float v) { return v == 0.0f; }));
}

// Below the ground a camera stands on it, moved out along its radius
// (camera_above_ground); at the planet's very centre, where no radius has a
// direction, it stands on the ground at the pole on +z, on the GPU as on
// the CPU, and never produces NaN.
TEST_F(Gpu, CameraAtThePlanetsCentreStandsOnTheGroundAtThePole) {
  atmos::Renderer renderer(*earth_, *tables_);
  Camera centre;
  centre.position = {0.0, 0.0, 0.0};
  centre.forward = {0.0, 1.0, 0.2};
  centre.width = 16;
  centre.height = 12;
  Camera pole = centre;
  pole.position = {0.0, 0.0, earth_->bottom_radius_m};
  const glm::dvec3 sun = sun_at(15.0, 30.0);
  const Image gpu_centre = renderer.render(centre, sun), gpu_pole = renderer.render(pole, sun);
  const Image cpu_centre = atmos::render_cpu(*earth_, *tables_, centre, sun);
  const Image cpu_pole = atmos::render_cpu(*earth_, *tables_, pole, sun);
  for (size_t i = 0; i < gpu_pole.rgb.size(); ++i) {
    ASSERT_TRUE(std::isfinite(gpu_centre.rgb[i]) && std::isfinite(cpu_centre.rgb[i])) << i;
    EXPECT_EQ(gpu_centre.rgb[i], gpu_pole.rgb[i]) << i;
    EXPECT_EQ(cpu_centre.rgb[i], cpu_pole.rgb[i]) << i;
  }
  EXPECT_GT(gpu_pole.rgb[1], 0.0f);
}

TEST_F(Gpu, LargeImagesAreTiled) {
  // Larger than one 2048-pixel tile: the tiles must land in the right place,
  // i.e. match the CPU twin everywhere. Thin strips keep it fast; each puts a
  // steep feature in its second tile so that a misplaced tile would show.
  atmos::Renderer renderer(*earth_, *tables_);
  Camera row = scenes()[0].camera;
  row.width = 2100;
  row.height = 3;
  row.fov_deg = 2.0;  // vertical; horizontally ±85°
  // Just above the strip at azimuth 85° (column ~2070): the steep aerosol
  // halo around the sun, without its disc.
  const glm::dvec3 sun_right = sun_at(2.0, 85.0);
  Camera column = row;
  std::swap(column.width, column.height);
  // Tilted up 0.927° so that the horizon (0.045° below the horizontal at 2 m)
  // falls at row ~2070 of 2100.
  column.forward = {0.0, 1.0, std::tan(glm::radians(0.927))};
  for (const auto& [camera, sun, name] : {std::tuple{row, sun_right, "tiled row"},
                                          std::tuple{column, sun_at(20.0, 45.0), "tiled column"}}) {
    const Image gpu = renderer.render(camera, sun);
    const Image cpu = atmos::render_cpu(*earth_, *tables_, camera, sun);
    const Difference d = compare(gpu, cpu);
    report(name, "full vs cpu", d);
    EXPECT_LE(d.max_relative, kGroundMaxRelative) << name;
  }
}

// The sun disc carries the solar irradiance attenuated by the atmosphere. A
// narrow view centred on the sun (30° up, seen from 2 m; the disc 53 pixels
// in radius), minus the sky around the disc, summed over the pixels' solid
// angles, equals the sun's direct normal irradiance at the camera (SkyModel:
// the horizontal irradiance / sin 30°), on the GPU and on the CPU; and the
// disc is limb-darkened (radiance_to_camera.glsl: sun_disc_radiance).
TEST_F(Gpu, SunDiscCarriesTheAttenuatedSolarIrradiance) {
  atmos::Renderer renderer(*earth_, *tables_, TexturePrecision::full);
  const atmos::SkyModel model(*earth_, *tables_);
  const glm::dvec3 sun = sun_at(30.0, 0.0);
  Camera camera;
  camera.position = {0.0, 0.0, kEarthRadius + 2.0};
  camera.forward = sun;
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_deg = 0.8;
  camera.width = camera.height = 160;
  glm::dvec3 sun_irradiance, sky_irradiance;
  model.horizontal_irradiance(camera.position, sun, sun_irradiance, sky_irradiance);
  const glm::dvec3 expected = model.to_srgb(sun_irradiance / std::sin(glm::radians(30.0)));
  const double alpha = earth_->sun_angular_radius_rad;
  // Pixel (i, j): tangent-plane coordinates from the image centre (the sun),
  // the angle from the sun and the solid angle.
  const double pixel = 2.0 * std::tan(glm::radians(camera.fov_deg) / 2.0) / camera.height;
  struct Pixel {
    double angle, solid_angle;
  };
  auto pixel_at = [&](int i, int j) {
    const double x = (i + 0.5 - camera.width / 2.0) * pixel, y = (j + 0.5 - camera.height / 2.0) * pixel;
    const double q = 1.0 + x * x + y * y;
    return Pixel{std::atan(std::sqrt(x * x + y * y)), pixel * pixel / (q * std::sqrt(q))};
  };
  for (const auto& [name, image] : {std::pair<const char*, Image>{"gpu", renderer.render(camera, sun)},
                                    {"cpu", render_cpu(*earth_, *tables_, camera, sun)}}) {
    glm::dvec3 background(0.0);
    int ring = 0;
    for (int j = 0; j < camera.height; ++j)
      for (int i = 0; i < camera.width; ++i) {
        const Pixel p = pixel_at(i, j);
        if (p.angle < 1.3 * alpha || p.angle > 1.5 * alpha) continue;
        const size_t k = 3 * (size_t(j) * size_t(camera.width) + size_t(i));
        background += glm::dvec3(image.rgb[k], image.rgb[k + 1], image.rgb[k + 2]);
        ++ring;
      }
    background /= double(ring);
    glm::dvec3 irradiance(0.0);
    for (int j = 0; j < camera.height; ++j)
      for (int i = 0; i < camera.width; ++i) {
        const Pixel p = pixel_at(i, j);
        if (p.angle > 1.2 * alpha) continue;
        const size_t k = 3 * (size_t(j) * size_t(camera.width) + size_t(i));
        irradiance += (glm::dvec3(image.rgb[k], image.rgb[k + 1], image.rgb[k + 2]) - background) * p.solid_angle;
      }
    std::printf("%s: sun disc %.1f %.1f %.1f lux, direct normal irradiance %.1f %.1f %.1f lux\n", name,
                irradiance.x, irradiance.y, irradiance.z, expected.x, expected.y, expected.z);
    // Partly covered edge pixels: ~0.3 % of the disc's light.
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(irradiance[c] / expected[c], 1.0, 0.005) << name << " channel " << c;
    // Limb darkening: the pixel nearest 0.95 alpha from the centre, against
    // the centre, 1 - 0.6 (1 - sqrt(1 - 0.95²)) = 0.59.
    const int centre = camera.width / 2;
    const int edge = centre + int(std::lround(std::tan(0.95 * alpha) / pixel - 0.5));
    const size_t c0 = 3 * (size_t(centre) * size_t(camera.width) + size_t(centre));
    const size_t c1 = 3 * (size_t(centre) * size_t(camera.width) + size_t(edge));
    const double ratio = (image.rgb[c1 + 1] - background.y) / (image.rgb[c0 + 1] - background.y);
    std::printf("%s: limb / centre at %.3f of the radius: %.3f\n", name, pixel_at(edge, centre).angle / alpha, ratio);
    EXPECT_NEAR(ratio, 1.0 - 0.6 * (1.0 - std::sqrt(1.0 - std::pow(pixel_at(edge, centre).angle / alpha, 2))), 0.03)
        << name;
  }
}

// Stars (stars.glsl) behind the atmosphere: the brightest star more than 40°
// up, seen from 2 m through a 2° view, adds far more than the sky's own light
// at its pixel with the sun 18° below the horizon, and less than a 1 %
// contrast (about the eye's threshold) in the daylight sky with the sun 30°
// up (its pixel with and without the star field); the GPU and CPU renderers
// agree there.
TEST_F(Gpu, StarsShineAtNightAndDrownByDay) {
  float brightest = 100.0f;
  glm::vec3 star(0.0f);
  for (int c = 0; c < 6 * STAR_CELLS * STAR_CELLS; ++c) {
    float magnitude;
    const glm::vec3 s = atmos::physics::star_of_cell(c, magnitude);
    if (s.z > std::sin(glm::radians(40.0f)) && magnitude < brightest) {
      brightest = magnitude;
      star = s;
    }
  }
  atmos::Renderer renderer(*earth_, *tables_, TexturePrecision::full);
  Camera camera;
  camera.position = {0.0, 0.0, kEarthRadius + 2.0};
  camera.forward = glm::dvec3(star);
  camera.up = {0.0, 0.0, 1.0};
  camera.fov_deg = 2.0;
  camera.width = camera.height = 64;
  auto luminance = [](const Image& image, size_t i) {
    return atmos::srgb_luminance(glm::dvec3(image.rgb[3 * i], image.rgb[3 * i + 1], image.rgb[3 * i + 2]));
  };
  // The sun opposite the star's azimuth.
  const double azimuth = glm::degrees(std::atan2(-double(star.x), -double(star.y)));
  size_t pixel = 0;  // the star's: the brightest at night
  for (double elevation : {-18.0, 30.0}) {
    const glm::dvec3 sun = atmos::direction_from_azimuth_elevation(azimuth, elevation);
    renderer.set_stars(true);
    const Image with = renderer.render(camera, sun);
    renderer.set_stars(false);
    const Image without = renderer.render(camera, sun);
    const Image cpu = render_cpu(*earth_, *tables_, camera, sun, true);
    if (elevation < 0.0)
      for (size_t i = 0; i < size_t(camera.width) * size_t(camera.height); ++i)
        if (luminance(with, i) > luminance(with, pixel)) pixel = i;
    const double sky = luminance(without, pixel);
    const double contrast = (luminance(with, pixel) - sky) / sky;
    std::printf("star V = %.2f, sun %+.0f deg: its pixel %.4g cd/m2 (cpu %.4g), without the stars %.4g cd/m2, "
                "contrast %.3g\n",
                brightest, elevation, luminance(with, pixel), luminance(cpu, pixel), sky, contrast);
    EXPECT_NEAR(luminance(cpu, pixel) / luminance(with, pixel), 1.0, 0.01);
    if (elevation < 0.0) {
      EXPECT_GT(contrast, 10.0) << "the star is not visible at night";
    } else {
      EXPECT_GT(contrast, 0.0);
      EXPECT_LT(contrast, 0.01) << "the star shows in the daylight sky";
    }
  }
}

TEST_F(Gpu, RejectsMismatchedTables) {
  atmos::Tables other_wavelengths = *tables_;
  other_wavelengths.wavelengths_nm = atmos::spectral_wavelengths(6);
  atmos::Tables truncated = *tables_;
  truncated.spectral_optical_depth.pop_back();
  for (const atmos::Tables* bad : {&other_wavelengths, &truncated}) {
    EXPECT_THROW(atmos::Renderer(*earth_, *bad), atmos::Error);
    EXPECT_THROW(atmos::render_cpu(*earth_, *bad, scenes()[0].camera, {0.0, 0.0, 1.0}), atmos::Error);
  }
}

TEST_F(Gpu, RejectsBadSunDirection) {
  atmos::Renderer renderer(*earth_, *tables_);
  EXPECT_THROW(renderer.render(scenes()[0].camera, {0.0, 0.0, 0.0}), atmos::Error);
  EXPECT_THROW(renderer.render(scenes()[0].camera, {std::nan(""), 0.0, 1.0}), atmos::Error);
}

// Programs go to the driver pruned to the functions they use
// (data/glsl_prune.hpp, in gpu::link_program): the sky-view table drawn by
// its pruned program and by one of the whole assembled source holds the same
// bits.
TEST_F(Gpu, PrunedProgramDrawsTheBitsOfTheWholeSource) {
  atmos::gpu::GpuTables gpu_tables(*earth_, *tables_, atmos::TexturePrecision::full);
  const glm::vec3 camera(0.0f, gpu_tables.params().bottom_radius + 1000.0f, 0.0f);
  const glm::vec3 sun = glm::normalize(glm::vec3(0.3f, 0.8f, 0.2f));
  ASSERT_FALSE(atmos::physics::sun_may_be_low_on_view_rays(gpu_tables.params(), camera, sun));
  const std::string whole =
      atmos::gpu::sky_view_fragment_shader_source(gpu_tables.params(), gpu_tables.spectral(), false, false).text;
  ASSERT_LT(atmos::data::prune_unreferenced_functions(whole).size(), whole.size());
  const atmos::physics::SkyViewFrame frame = gpu_tables.sky_view_frame(camera, sun);
  const auto draw = [&] {
    gpu_tables.update_sky_view(camera, sun, frame, nullptr);
    std::vector<float> texels(size_t(3 * 4 * SKY_VIEW_WIDTH * SKY_VIEW_HEIGHT));
    const size_t one = texels.size() / 3;
    for (int i = 0; i < 3; ++i)
      glGetTextureImage(gpu_tables.sky_view_texture(i), 0, GL_RGBA, GL_FLOAT, GLsizei(one * sizeof(float)),
                        texels.data() + size_t(i) * one);
    return texels;
  };
  const std::vector<float> pruned = draw();
  GLuint& slot = gpu_tables.sky_view_program(camera, sun, atmos::physics::no_moons());
  const GLuint pruned_program = slot;
  slot = atmos_test::fullscreen_program(whole);
  const std::vector<float> unpruned = draw();
  glDeleteProgram(slot);
  slot = pruned_program;
  atmos::gpu::check_gl("while drawing the sky-view table");
  ASSERT_EQ(pruned.size(), unpruned.size());
  EXPECT_EQ(std::memcmp(pruned.data(), unpruned.data(), pruned.size() * sizeof(float)), 0);
  // Not a table of zeros or NaNs.
  EXPECT_GT(*std::max_element(pruned.begin(), pruned.end()), 0.0f);
  EXPECT_TRUE(std::all_of(pruned.begin(), pruned.end(), [](float x) { return std::isfinite(x); }));
}

// The parameter block as the driver lays it out and as the shaders read
// it: the block's size, the array's offset and stride queried from a
// program (std140), and every field of ATMOSPHERE, SPECTRAL and the colour
// matrix written back by a compute shader, equal to the C++ parameters'
// (the fields the shaders never read are 0). The atmosphere is thick (its
// table axes' weights and knots are read) and spectral (three triples).
TEST_F(Gpu, ParameterBlockMatchesTheDriversLayout) {
  atmos::Atmosphere dense = *earth_;
  atmos::scale_density(dense, 100.0);
  dense.wavelengths_nm = atmos::spectral_wavelengths(7);
  const atmos::TableSizes sizes = atmos_test::small_gpu_sizes();
  const atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(dense, sizes);
  const auto spectral = atmos::physics::make_spectral_sets(dense, sizes);
  ASSERT_EQ(spectral->count, 3);
  ASSERT_GT(params.scattering_r_optical_depth_weight, 0.0f);
  glm::mat3 colour;
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) colour[c][r] = 0.1f * float(3 * c + r) - 0.35f;
  const atmos::gpu::ParameterBlock block = atmos::gpu::parameter_block(params, *spectral, colour, 3);

  // The C++ side of every field, in the order the shader writes them.
  std::vector<float> expected;
  const auto put = [&](float x) { expected.push_back(x); };
  const auto put3 = [&](const glm::vec3& v) { put(v.x), put(v.y), put(v.z); };
  const auto put_params = [&](const atmos::physics::AtmosphereParams& a) {
    put(a.bottom_radius), put(a.top_radius), put(float(a.constituent_count));
    for (int i = 0; i < MAX_CONSTITUENTS; ++i) {
      const bool used = i < a.constituent_count;
      const atmos::physics::DensityProfile& d = a.density[i];
      put(used && d.knot_count == 0 ? d.scale_height : 0.0f), put(used ? float(d.knot_count) : 0.0f);
      for (int k = 0; k < MAX_DENSITY_KNOTS; ++k) {
        const bool knot = used && k < d.knot_count;
        put(knot ? d.knot_altitude[k] : 0.0f), put(knot ? d.knot_density[k] : 0.0f);
      }
      put3(used ? a.scattering[i] : glm::vec3(0.0f)), put3(used ? a.absorption[i] : glm::vec3(0.0f));
      put(used ? float(a.is_aerosol[i]) : 0.0f);
    }
    put(float(a.aerosol_phase_kind)), put3(a.aerosol_g), put3(a.aerosol_g_back), put3(a.aerosol_forward_weight);
    put3(a.ground_albedo), put3(a.solar_irradiance), put(a.sun_angular_radius), put(a.mu_s_min);
    for (int size : {a.transmittance_mu_size, a.transmittance_r_size, a.irradiance_mu_s_size, a.irradiance_r_size,
                     a.scattering_nu_size, a.scattering_mu_s_size, a.scattering_mu_size, a.scattering_r_size,
                     a.transmittance_tile, a.transmittance_tiles, a.single_scattering_tile, a.scattering_nu_in_angle})
      put(float(size));
    put(a.scattering_mu_log_weight), put(a.scattering_r_optical_depth_weight);
    for (int k = 0; k < SCATTERING_R_AXIS_KNOTS; ++k)
      put(a.scattering_r_optical_depth_weight != 0.0f ? a.scattering_r_axis[k] : 0.0f);
    put(a.source_flat_optical_depth), put(a.scattering_row_1_height);
  };
  put_params(params);
  for (int k = 0; k < spectral->count; ++k) {
    put_params(spectral->set[k]);
    for (int c = 0; c < 3; ++c) put3(spectral->to_channels[k][c]);
  }
  for (int c = 0; c < 3; ++c) put3(colour[c]);

  atmos::gpu::AssembledSource source;
  source.append("header", "#version 450 core\n#define IN(T) in T\n#define OUT(T) out T\n#define INOUT(T) inout T\n"
                          "#define INLINE\n#define SPECTRAL_SET_CAPACITY 3\n");
  source.append("definitions.glsl", atmos::data::embedded_file("src/physics/definitions.glsl"));
  source.append("parameters", block.glsl);
  source.append("test", R"(
layout(local_size_x = 1) in;
layout(std430, binding = 0) writeonly buffer Fields { float fields[]; };
int n = 0;
void put(float x) { fields[n++] = x; }
void put3(vec3 v) { put(v.x); put(v.y); put(v.z); }
void put_params(AtmosphereParams a) {
  put(a.bottom_radius); put(a.top_radius); put(float(a.constituent_count));
  for (int i = 0; i < MAX_CONSTITUENTS; ++i) {
    put(a.density[i].scale_height); put(float(a.density[i].knot_count));
    for (int k = 0; k < MAX_DENSITY_KNOTS; ++k) {
      put(a.density[i].knot_altitude[k]);
      put(a.density[i].knot_density[k]);
    }
    put3(a.scattering[i]); put3(a.absorption[i]); put(float(a.is_aerosol[i]));
  }
  put(float(a.aerosol_phase_kind)); put3(a.aerosol_g); put3(a.aerosol_g_back); put3(a.aerosol_forward_weight);
  put3(a.ground_albedo); put3(a.solar_irradiance); put(a.sun_angular_radius); put(a.mu_s_min);
  put(float(a.transmittance_mu_size)); put(float(a.transmittance_r_size)); put(float(a.irradiance_mu_s_size));
  put(float(a.irradiance_r_size)); put(float(a.scattering_nu_size)); put(float(a.scattering_mu_s_size));
  put(float(a.scattering_mu_size)); put(float(a.scattering_r_size)); put(float(a.transmittance_tile));
  put(float(a.transmittance_tiles)); put(float(a.single_scattering_tile)); put(float(a.scattering_nu_in_angle));
  put(a.scattering_mu_log_weight); put(a.scattering_r_optical_depth_weight);
  for (int k = 0; k < SCATTERING_R_AXIS_KNOTS; ++k) put(a.scattering_r_axis[k]);
  put(a.source_flat_optical_depth); put(a.scattering_row_1_height);
}
void main() {
  put_params(ATMOSPHERE);
  SpectralSets sets = SPECTRAL;
  for (int k = 0; k < sets.count; ++k) {
    put_params(sets.set[k]);
    put3(sets.to_channels[k][0]); put3(sets.to_channels[k][1]); put3(sets.to_channels[k][2]);
  }
  mat3 m = atmos_radiance_to_srgb();
  put3(m[0]); put3(m[1]); put3(m[2]);
}
)");
  GLuint program = atmos::gpu::link_compute_program(source);

  // The driver's std140 layout of the block.
  const GLuint block_index = glGetProgramResourceIndex(program, GL_UNIFORM_BLOCK, atmos::gpu::kParameterBlock);
  ASSERT_NE(block_index, GL_INVALID_INDEX);
  const GLenum block_properties[2] = {GL_BUFFER_DATA_SIZE, GL_BUFFER_BINDING};
  GLint block_values[2] = {0, 0};
  glGetProgramResourceiv(program, GL_UNIFORM_BLOCK, block_index, 2, block_properties, 2, nullptr, block_values);
  EXPECT_EQ(block_values[0], GLint(block.values.size() * sizeof(float)));
  EXPECT_EQ(block_values[1], 3);
  const std::string array = std::string(atmos::gpu::kParameterArray) + "[0]";
  const GLuint array_index = glGetProgramResourceIndex(program, GL_UNIFORM, array.c_str());
  ASSERT_NE(array_index, GL_INVALID_INDEX);
  const GLenum array_properties[4] = {GL_OFFSET, GL_ARRAY_STRIDE, GL_ARRAY_SIZE, GL_BLOCK_INDEX};
  GLint array_values[4] = {-1, -1, -1, -1};
  glGetProgramResourceiv(program, GL_UNIFORM, array_index, 4, array_properties, 4, nullptr, array_values);
  EXPECT_EQ(array_values[0], 0);
  EXPECT_EQ(array_values[1], 16);
  EXPECT_EQ(array_values[2], GLint(block.values.size() / 4));
  EXPECT_EQ(array_values[3], GLint(block_index));

  // The fields as the shader reads them.
  GLuint buffers[2] = {0, 0};
  glCreateBuffers(2, buffers);
  glNamedBufferStorage(buffers[0], GLsizeiptr(block.values.size() * sizeof(float)), block.values.data(), 0);
  glNamedBufferStorage(buffers[1], GLsizeiptr(expected.size() * sizeof(float)), nullptr, 0);
  glBindBufferBase(GL_UNIFORM_BUFFER, 3, buffers[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, buffers[1]);
  glUseProgram(program);
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  std::vector<float> fields(expected.size(), -1.0f);
  glGetNamedBufferSubData(buffers[1], 0, GLsizeiptr(fields.size() * sizeof(float)), fields.data());
  glBindBufferBase(GL_UNIFORM_BUFFER, 3, 0);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
  glDeleteBuffers(2, buffers);
  atmos::gpu::release_program(program);
  atmos::gpu::check_gl("while reading the parameter block back");
  size_t differing = 0, first = expected.size();
  for (size_t i = 0; i < expected.size(); ++i)
    if (fields[i] != expected[i]) {
      ++differing;
      first = std::min(first, i);
    }
  EXPECT_EQ(differing, 0u) << "first at field " << first << ": " << fields[std::min(first, fields.size() - 1)]
                           << " for " << expected[std::min(first, expected.size() - 1)];
}

}  // namespace
