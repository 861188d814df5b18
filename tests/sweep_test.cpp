// The random sweep (tools/sweep, docs/hardening.md): its pixel check on images
// with known contents, the reproducibility of its runs, the configurations
// it found wrong, and fixed-seed subsets of random configurations of the
// renderer and the plugin: 24 in the default tier, 500 in the full tier.
#include <gtest/gtest.h>

#include <glm/gtc/packing.hpp>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <sstream>

#include "atmos/colour.hpp"
#include "atmos/renderer.hpp"
#include "gpu/atmosphere_pass.hpp"
#include "gpu/gl_util.hpp"
#include "sweep.hpp"

namespace {

using atmos::Image;
namespace sweep = atmos::sweep;

Image image_of(std::initializer_list<glm::vec3> pixels) {
  Image image;
  image.width = int(pixels.size());
  image.height = 1;
  for (const glm::vec3& p : pixels) image.rgb.insert(image.rgb.end(), {p.x, p.y, p.z});
  return image;
}

TEST(SweepCheck, FlagsNanInfiniteAndNegativeLight) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const glm::dmat3 xyz_only(0.0);
  EXPECT_TRUE(sweep::check_image(image_of({{0.1f, 0.2f, 0.3f}, {0.0f, 0.0f, 0.0f}}), xyz_only).passed());

  const sweep::PixelCheck with_nan = sweep::check_image(image_of({{0.1f, 0.2f, 0.3f}, {0.1f, nan, 0.3f}}), xyz_only);
  EXPECT_EQ(with_nan.kind, "nan");
  EXPECT_EQ(with_nan.nan, 1);
  EXPECT_EQ(with_nan.x, 1);

  const sweep::PixelCheck with_inf = sweep::check_image(image_of({{inf, 0.2f, 0.3f}}), xyz_only);
  EXPECT_EQ(with_inf.kind, "inf");

  // Negative in every channel: negative X, Y and Z.
  const sweep::PixelCheck negative = sweep::check_image(image_of({{-0.1f, -0.1f, -0.1f}}), xyz_only);
  EXPECT_EQ(negative.kind, "negative");
}

// Light at the bottom of the float range (seed 2026, 250 runs per planet,
// run 1265: a sun 0.003 degrees below the horizon, a pixel of 5.6e-34 with a
// blue of -1.2e-35) is underflow noise, not negative light; the same colour
// a billion billion times brighter is.
TEST(SweepCheck, UnderflowNoiseIsNotNegativeLight) {
  const glm::dmat3 xyz_only(0.0);
  EXPECT_TRUE(sweep::check_image(image_of({{5.58458448e-34f, 0.0f, -1.21054681e-35f}}), xyz_only).passed());
  EXPECT_EQ(sweep::check_image(image_of({{5.58458448e-16f, 0.0f, -1.21054681e-17f}}), xyz_only).kind, "negative");
}

TEST(SweepCheck, OutOfGamutLightIsCountedNotFailed) {
  // Monochromatic 520 nm light has XYZ ≈ (0.063, 0.710, 0.078) (CIE 1931):
  // in linear sRGB its red and blue are negative, its XYZ is not.
  const glm::dmat3 xyz_to_srgb(3.2406, -0.9689, 0.0557, -1.5372, 1.8758, -0.2040, -0.4986, 0.0415, 1.0570);
  const glm::dvec3 rgb = xyz_to_srgb * glm::dvec3(0.063, 0.710, 0.078);
  ASSERT_LT(std::min({rgb.x, rgb.y, rgb.z}), 0.0);
  const sweep::PixelCheck c = sweep::check_image(image_of({glm::vec3(rgb)}), glm::dmat3(0.0));
  EXPECT_TRUE(c.passed()) << c.kind;
  EXPECT_EQ(c.out_of_gamut, 1);
}

TEST(SweepCheck, RoundingOfTheOutputFormatIsNotNegativeLight) {
  // A pixel of R11F_G11F_B10F at the bottom of its subnormals: blue rounded
  // to zero below 2^-20, red and green one or two steps of 2^-19 above it.
  const glm::vec3 v(3.0f * 0x1.0p-20f, 2.0f * 0x1.0p-20f, 0.0f);
  const glm::dmat3 to_radiance(1.2, -0.3, 0.1, -0.5, 1.4, -0.2, 0.05, -0.6, 1.3);
  sweep::CheckPrecision float32;
  EXPECT_EQ(sweep::check_image(image_of({v}), to_radiance, float32).kind, "negative");
  sweep::CheckPrecision packed;
  packed.epsilon = 0x1.0p-5;
  packed.subnormal_spacing = 0x1.0p-19;
  EXPECT_TRUE(sweep::check_image(image_of({v}), to_radiance, packed).passed());
  // Far above the subnormals the same ratio of channels is negative light.
  EXPECT_EQ(sweep::check_image(image_of({v * 1e6f}), to_radiance, packed).kind, "negative");
}

TEST(SweepCheck, ClampedOutOfGamutLightIsCheckedInXyzOnly) {
  // Light of the red and green working wavelengths whose sRGB blue is
  // negative, clamped at zero as the plugin clamps it: its radiances from the
  // clamped colour have a negative blue, its XYZ does not.
  const glm::dmat3 to_radiance(1.2, -0.3, 0.1, -0.5, 1.4, -0.2, 0.05, -0.6, 1.3);
  const glm::vec3 clamped(3.4e-3f, 1.2e-4f, 0.0f);
  sweep::CheckPrecision unclamped;
  EXPECT_EQ(sweep::check_image(image_of({clamped}), to_radiance, unclamped).kind, "negative");
  sweep::CheckPrecision plugin;
  plugin.clamped_at_zero = true;
  EXPECT_TRUE(sweep::check_image(image_of({clamped}), to_radiance, plugin).passed());
  EXPECT_EQ(sweep::check_image(image_of({{-3.4e-3f, -1.2e-4f, 0.0f}}), to_radiance, plugin).kind, "negative");
}

TEST(SweepCases, EveryRunIsReproducedFromItsSeedAndIndexAlone) {
  for (int index : {0, 7, 123, 4711}) {
    const sweep::PlanetCase a = sweep::make_planet(42, index / 100);
    const sweep::PlanetCase b = sweep::make_planet(42, index / 100);
    EXPECT_EQ(sweep::describe(a), sweep::describe(b));
    EXPECT_EQ(sweep::describe(sweep::make_run(42, index, a, sweep::Targets::both)),
              sweep::describe(sweep::make_run(42, index, b, sweep::Targets::both)));
  }
  EXPECT_NE(sweep::describe(sweep::make_planet(42, 0)), sweep::describe(sweep::make_planet(43, 0)));
}

TEST(SweepCases, PlanetsAreValidAndCoverPresetsAndRandomPlanets) {
  int presets = 0, random = 0;
  for (int i = 0; i < 64; ++i) {
    const sweep::PlanetCase p = sweep::make_planet(1, i);
    EXPECT_NO_THROW(p.atmosphere.validate()) << sweep::describe(p);
    (p.recipe.rfind("preset", 0) == 0 ? presets : random) += 1;
  }
  EXPECT_GT(presets, 8);
  EXPECT_GT(random, 8);
}

TEST(SweepCases, CamerasReachFromInsideTheGroundTo100PlanetRadii) {
  const sweep::PlanetCase p = sweep::make_planet(1, 0);
  const double bottom = p.atmosphere.bottom_radius_m;
  double nearest = INFINITY, farthest = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const sweep::RunCase run = sweep::make_run(1, i, p, sweep::Targets::renderer_only);
    const double r = glm::length(run.renderer.camera.position);
    nearest = std::min(nearest, r);
    farthest = std::max(farthest, r);
  }
  EXPECT_LT(nearest, 0.5 * bottom);
  EXPECT_GT(farthest, 50.0 * bottom);
  EXPECT_LE(farthest, 100.0 * bottom * (1.0 + 1e-12));
}

// A configuration the sweep found (seed 15, 250 runs per planet, run 343):
// the plugin's G-buffer lighting on a random planet whose sky light, converted
// to sRGB, has a negative blue. Multiplied by the albedo channel by channel it
// gave a surface pixel of negative CIE Z. The CPU twin of the pass
// (composite_cpu, the same composite.glsl) on the run's engine buffers must
// pass the sweep's own check.
TEST(SweepCases, GbufferLightOutsideTheSrgbGamutGivesNoNegativeSurface) {
  const sweep::PlanetCase planet = sweep::make_planet(15, 343 / 250);
  const sweep::RunCase run = sweep::make_run(15, 343, planet, sweep::Targets::both);
  ASSERT_EQ(run.target, sweep::Target::plugin);
  const sweep::PluginCase& c = run.plugin;
  ASSERT_EQ(c.input.surfaces, atmos::SurfaceMode::gbuffer);
  const atmos::Tables tables = atmos::precompute_tables(planet.atmosphere, planet.options);

  atmos::gpu::CpuEngineBuffers buffers;
  buffers.depth = c.depth;
  buffers.albedo = c.colour;
  buffers.normal = c.normal;
  atmos::FrameInput input = c.input;
  if (c.shadow_size > 0) {
    input.shadow_map = 1;  // any name: the CPU twin reads buffers.shadow_depth
    buffers.shadow_width = buffers.shadow_height = c.shadow_size;
    for (float d : c.shadow_depth) buffers.shadow_depth.emplace_back(d, 0.0f, 0.0f);
  }
  std::vector<glm::ivec2> pixels;
  for (int y = 0; y < input.height; ++y)
    for (int x = 0; x < input.width; ++x) pixels.emplace_back(x, y);
  const std::vector<glm::vec3> out =
      atmos::gpu::composite_cpu(planet.atmosphere, tables, planet.frame, input, buffers, pixels);

  Image image;
  image.width = input.width;
  image.height = input.height;
  for (const glm::vec3& p : out) image.rgb.insert(image.rgb.end(), {p.x, p.y, p.z});
  std::vector<bool> sky(c.depth.size());
  const float clear = input.depth_encoding == atmos::DepthEncoding::reversed_z ? 0.0f : 1.0f;
  for (size_t i = 0; i < sky.size(); ++i) sky[i] = c.depth[i] == clear;
  sweep::CheckPrecision precision;
  precision.clamped_at_zero = true;
  const sweep::PixelCheck check =
      sweep::check_image(image, sweep::radiance_from_srgb(planet.atmosphere), precision, sky);
  EXPECT_TRUE(check.passed()) << check.kind << " at (" << check.x << ", " << check.y << "): (" << check.value.x
                              << ", " << check.value.y << ", " << check.value.z << ")";
  int surface_pixels = 0;
  for (size_t i = 0; i < sky.size(); ++i) surface_pixels += sky[i] ? 0 : 1;
  EXPECT_GT(surface_pixels, 0);
}

// The sweep's OpenGL context; a failure (never a skip) without one.
std::unique_ptr<atmos::GlContext> headless_context() {
  try {
    return atmos::GlContext::create_headless();
  } catch (const atmos::Error& e) {
    ADD_FAILURE() << e.what();
    return nullptr;
  }
}

// A fixed-seed subset: `runs` runs of `seed`, half through atmos::Renderer
// and half through atmos::AtmospherePass, with no NaN, infinite or negative
// pixel and no error.
void expect_clean_subset(std::uint64_t seed, int runs, int runs_per_planet) {
  const std::unique_ptr<atmos::GlContext> context = headless_context();
  ASSERT_TRUE(context != nullptr);
  sweep::SweepOptions options;
  options.seed = seed;
  options.runs = runs;
  options.runs_per_planet = runs_per_planet;
  const sweep::SweepResult result = sweep::run_sweep(options);
  std::ostringstream failures;
  for (const sweep::Failure& f : result.failures) failures << sweep::describe(f) << "\n";
  EXPECT_EQ(result.runs, runs);
  EXPECT_GT(result.renderer_runs, runs / 3);
  EXPECT_GT(result.plugin_runs, runs / 3);
  EXPECT_EQ(result.planets, (runs + runs_per_planet - 1) / runs_per_planet);
  EXPECT_EQ(result.refused_runs, 0);
  EXPECT_TRUE(result.failures.empty()) << sweep::summary(result, options) << failures.str();
}

// Run `run` of the 10^4 sweep of seed 2026 with 250 runs per planet
// (docs/hardening.md), by itself.
sweep::SweepResult replay_2026(int run) {
  sweep::SweepOptions options;
  options.seed = 2026;
  options.runs = 10000;
  options.runs_per_planet = 250;
  options.replay = run;
  return sweep::run_sweep(options);
}

// A planet the library refuses with a clear error (seed 2026, 250 runs per
// planet, planet 2: the Venus preset at 9 wavelengths with coarse random
// tables, whose third scattering order would add more light than the
// second) is a refusal, not a failure: its runs are counted apart.
TEST(Sweep, ThickPlanetOnCoarseTablesIsRefusedWithAClearErrorNotAFailure) {
  const std::unique_ptr<atmos::GlContext> context = headless_context();
  ASSERT_TRUE(context != nullptr);
  const sweep::SweepResult result = replay_2026(500);
  EXPECT_EQ(result.runs, 1);
  EXPECT_EQ(result.refused_runs, 1);
  ASSERT_EQ(result.refusals.size(), 1u);
  EXPECT_NE(result.refusals[0].find("venus"), std::string::npos) << result.refusals[0];
  EXPECT_NE(result.refusals[0].find("cannot represent"), std::string::npos) << result.refusals[0];
  EXPECT_TRUE(result.failures.empty());
}

// The rounding behind the replay below, on the CPU: faint light in the
// spectral mode's linear sRGB channels (night and twilight, 1e-9 to 1e-5
// cd/m² per channel, in and just out of the gamut) rounded to half floats
// keeps every CIE XYZ coordinate at or above min(0, the float texel's own),
// within one half-float step of each channel. Rounding each channel to the
// nearest half float alone breaks this for some of the same texels, so the
// check can fail.
TEST(SweepCheck, HalfFloatTablesKeepFaintLightInsideTheSpectralLocus) {
  std::mt19937 random(2026);
  std::uniform_real_distribution<double> exponent(-9.0, -5.0), tint(-0.15, 1.0);
  int nearest_violations = 0;
  for (int i = 0; i < 20000; ++i) {
    const double scale = std::pow(10.0, exponent(random));
    const glm::vec3 texel(float(scale * tint(random)), float(scale * tint(random)), float(scale * tint(random)));
    const glm::dvec3 floor_xyz = glm::min(atmos::srgb_to_xyz(glm::dvec3(texel)), glm::dvec3(0.0));
    const glm::vec3 half = atmos::gpu::half_texel(texel, true);
    const glm::dvec3 xyz = atmos::srgb_to_xyz(glm::dvec3(half));
    ASSERT_TRUE(glm::all(glm::greaterThanEqual(xyz, floor_xyz)))
        << "texel " << texel.x << " " << texel.y << " " << texel.z << " -> " << half.x << " " << half.y << " "
        << half.z;
    for (int c = 0; c < 3; ++c) {
      const float step = std::max(std::abs(texel[c]) * 1.0e-3f, 6.0e-8f);  // a half float's spacing, bounded
      ASSERT_LE(std::abs(half[c] - texel[c]), step) << "channel " << c << " of texel " << i;
    }
    const glm::dvec3 nearest(glm::unpackHalf1x16(glm::packHalf1x16(texel.x)),
                             glm::unpackHalf1x16(glm::packHalf1x16(texel.y)),
                             glm::unpackHalf1x16(glm::packHalf1x16(texel.z)));
    if (!glm::all(glm::greaterThanEqual(atmos::srgb_to_xyz(nearest), floor_xyz))) ++nearest_violations;
  }
  EXPECT_GT(nearest_violations, 0) << "the sample never reaches the case the rounding is for";
}

// Run 8209 of seed 2026 (250 runs per planet): Titan at 25 wavelengths on
// half-float tables, the camera on the ground with the sun 22° below the
// horizon and four moons, a fisheye of faint twilight (~1e-6 cd/m²). With
// each channel of the tables rounded to the nearest half float, 11 pixels
// were beyond the spectral locus (a negative CIE Z); gpu::half_texel keeps
// the tables' texels light. Full tier only: Titan's 25 wavelengths compile
// programs of minutes on llvmpipe; the default tier checks the rounding on
// the CPU above.
TEST(SweepLong, FaintTwilightOnHalfFloatTablesHasNoNegativeLight) {
  const std::unique_ptr<atmos::GlContext> context = headless_context();
  ASSERT_TRUE(context != nullptr);
  const sweep::SweepResult result = replay_2026(8209);
  std::ostringstream failures;
  for (const sweep::Failure& f : result.failures) failures << sweep::describe(f) << "\n";
  EXPECT_EQ(result.runs, 1);
  EXPECT_EQ(result.refused_runs, 0);
  EXPECT_TRUE(result.failures.empty()) << failures.str();
}

// A sweep resumed at an index runs the same runs as the whole sweep from
// there (here the refused planet 2 of seed 2026 from its run 500).
TEST(Sweep, ResumedSweepStartsAtItsFirstRun) {
  const std::unique_ptr<atmos::GlContext> context = headless_context();
  ASSERT_TRUE(context != nullptr);
  sweep::SweepOptions options;
  options.seed = 2026;
  options.runs = 503;
  options.runs_per_planet = 250;
  options.first_run = 500;
  const sweep::SweepResult result = sweep::run_sweep(options);
  EXPECT_EQ(result.runs, 3);
  EXPECT_EQ(result.planets, 1);
  EXPECT_EQ(result.refused_runs, 3);
}

// The full tier's subset: 250 runs of seed 1 on two planets (the Mars and
// Titan presets, varied; atmos_sweep covers random planets). Its cost is the
// programs of each planet and variant, compiled at their first use (seconds
// each on llvmpipe with a cold shader cache): the default tier has no subset.
TEST(SweepLong, FixedSeedSubsetHasNoNanInfiniteOrNegativePixel) { expect_clean_subset(1, 250, 125); }

}  // namespace
