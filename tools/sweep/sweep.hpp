// atmos_sweep's library: random valid configurations of the renderer
// (atmos::Renderer) and of the engine plugin (atmos::AtmospherePass), run at
// small image sizes and checked for NaN, infinite and negative light.
//
// A sweep of N runs with seed S is a sequence of planets, each with the
// tables of one random atmosphere (a preset, varied, or a random valid
// planet) and `runs_per_planet` consecutive runs: run i belongs to planet
// i / runs_per_planet. Every planet and every run draws from its own
// SplitMix64 stream derived from (S, i), so run i is reproduced by itself
// (replay) without the runs before it.
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>

#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/image.hpp"
#include "atmos/plugin.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"

namespace atmos::sweep {

class Random;

// `x` with `digits` significant digits, as the recipes and reports print it
// (6 in a planet's recipe, 9 in a run's, so that a replay rebuilds it).
std::string number_text(double x, int digits);

enum class Target { renderer, plugin };
// Which targets the runs exercise: each run of `both` picks one at random.
enum class Targets { both, renderer_only, plugin_only };

// One planet: its atmosphere, how its tables are computed, the engine
// frame and texture precision its plugin and renderer are built with, and
// the features of its runs that select a program variant of the plugin
// (AtmospherePass compiles each variant at its first use: seconds on a
// software rasteriser, against tenths of a second for a frame). Drawn per
// planet, they leave a planet's runs a few variants to compile, and the
// sweep's planets all of them; the cameras, suns, moons' places,
// projections, depth encodings and buffers are drawn per run.
// The GL internal formats of the engine's textures of a plugin frame.
// llvmpipe compiles a program again for every new combination of the
// formats it samples and renders to, so they are drawn per planet too.
struct TextureFormats {
  std::uint32_t depth = 0;
  std::uint32_t colour = 0;
  std::uint32_t output = 0;  // 0: the pass's own output texture
  std::uint32_t shadow = 0;  // the shadow map's depth (with shadow_map)
};

struct PlanetCase {
  int index = 0;
  std::string recipe;  // how it was made: "preset earth ..." or "random ..."
  Atmosphere atmosphere;
  PrecomputeOptions options;
  PlanetFrame frame;
  TexturePrecision precision = TexturePrecision::full;
  SurfaceMode surfaces = SurfaceMode::lit_colour;  // the plugin's surface mode
  bool shadow_map = false;                          // the plugin's frames have a sun shadow map
  bool plugin_stars = false;                        // the plugin's star field (the renderer's is drawn per run)
  bool moons = false;                               // runs have 1..kMaxMoons moons (else none)
  TextureFormats formats;
};

// Random formats among those an engine may hand the plugin.
TextureFormats random_texture_formats(Random& random);

// A valid random planet for (seed, planet index).
PlanetCase make_planet(std::uint64_t seed, int planet);
// A multi-line description: radii, constituents, phase function, albedo,
// sun, table sizes and orders, engine frame, features.
std::string describe(const PlanetCase& planet);

// A camera position (planet-centred metres) from the centre of the planet
// (inside the ground) out to 100 planet radii, over regimes that each get a
// share of the runs: below the surface, the first kilometre above it, the
// atmosphere, around its top, and space.
glm::dvec3 random_camera_position(Random& random, const Atmosphere& atmosphere);
// 1..kMaxMoons valid moons (validate_moons), some of them on or near the
// sun as seen from the atmosphere below `camera`.
std::vector<Moon> random_moons(Random& random, const Atmosphere& atmosphere, const glm::dvec3& camera,
                               const glm::dvec3& sun);

struct RendererCase {
  Camera camera;
  glm::dvec3 sun{0.0, 0.0, 1.0};
  std::vector<Moon> moons;
  bool stars = false;
};

// The engine's frame: FrameInput without texture names, the contents of its
// textures, and their formats (GL enums).
struct PluginCase {
  FrameInput input;                // textures 0: filled in by the run
  glm::dvec3 camera_planet{0.0};   // camera position, planet-centred metres
  std::string projection_kind;     // "standard finite", "reversed-Z infinite", ...
  std::string depth_content;       // "sky", "planet", "noise", "planet + noise"
  std::uint32_t depth_format = 0;  // GL internal format of the depth texture
  std::uint32_t colour_format = 0;
  std::uint32_t output_format = 0;  // 0: the pass's own output texture
  std::vector<float> depth;         // width x height, rows bottom-up (GL order)
  std::vector<glm::vec3> colour;    // lit colour (lit_colour) or albedo (gbuffer)
  std::vector<glm::vec3> normal;    // gbuffer
  int shadow_size = 0;              // 0: no shadow map
  std::uint32_t shadow_format = 0;
  std::vector<float> shadow_depth;
};

struct RunCase {
  int index = 0;
  Target target = Target::renderer;
  RendererCase renderer;
  PluginCase plugin;
};

RunCase make_run(std::uint64_t seed, int index, const PlanetCase& planet, Targets targets);
std::string describe(const RunCase& run);

// The check of one output image. Non-finite values are failures. Light is
// never negative, but linear sRGB can be: a saturated spectral colour lies
// outside the sRGB gamut (440 nm light alone has a negative green). So a
// pixel is negative when its coordinates in a basis where all light is
// non-negative are: CIE XYZ (non-negative colour matching functions) for
// every pixel, and for the pixels that hold only the atmosphere's light in
// three-wavelength mode, the radiances at the working wavelengths (the
// inverse of radiance_to_srgb_matrix). A coordinate q_i = Σ_j T_ij c_j of
// the channels c is negative below -Σ_j |T_ij| (ε |c_j| + δ), the bound of
// the rounding of the channels by a relative ε (the shaders' float
// arithmetic, or the output format's mantissa) or, among the format's
// subnormals, by their spacing δ. Pixels with a negative sRGB channel
// that pass are out of gamut: counted, not failed.
struct CheckPrecision {
  double epsilon = 1e-4;                // relative rounding of the channels
  // Absolute rounding of the smallest channels. GLSL lets shaders flush
  // float subnormals to zero (GLSL 4.50, §4.7.1), so even a 32-bit float
  // channel is uncertain by the smallest normal float, 2^-126.
  double subnormal_spacing = 0x1.0p-126;
  // Absolute uncertainty of a channel from the shaders' intermediate values
  // near the bottom of the float range (spectral radiances of a sun deep
  // below the horizon, ~1e-38, flushed or rounded before the sun's
  // irradiance and the colour matrix scale them by up to ~1e4): 1e-30 in
  // output units, 24 orders of magnitude below the faintest stars' light
  // (~1e-6 cd/m2).
  double underflow_floor = 1e-30;
  // The image's renderer clamps linear sRGB at zero (the plugin clamps the
  // atmosphere's light converted to sRGB, composite.glsl): a zero channel
  // may stand for a negative one of out-of-gamut light, so the radiance
  // check skips pixels with a zero channel (XYZ is still checked).
  bool clamped_at_zero = false;
  double saturation = INFINITY;         // channels at or above it were clamped by the format: not checked
};

struct PixelCheck {
  int nan = 0, inf = 0, negative = 0, out_of_gamut = 0;
  // The first failing pixel (x, y in the image's rows) and its value.
  int x = -1, y = -1;
  glm::vec3 value{0.0f};
  std::string kind;  // "nan", "inf", "negative" or "" (passed)
  bool passed() const { return kind.empty(); }
};

// `to_radiance`: radiance_from_srgb (zero: XYZ only). `atmosphere_only`:
// which pixels hold only the atmosphere's light (the plugin's sky pixels;
// the others carry an engine's sRGB colour or albedo, not a non-negative
// combination of three wavelengths); empty: every pixel (the renderer).
PixelCheck check_image(const Image& image, const glm::dmat3& to_radiance, const CheckPrecision& precision = {},
                       const std::vector<bool>& atmosphere_only = {});
// The inverse of radiance_to_srgb_matrix for the atmosphere's three working
// wavelengths when it is invertible; zero in spectral mode.
glm::dmat3 radiance_from_srgb(const Atmosphere& atmosphere);

struct Failure {
  int index = 0;
  int planet = 0;
  Target target = Target::renderer;
  std::string kind;     // "nan", "inf", "negative", "error", "exception", "gl error"
  std::string message;  // the pixel and its value, or the exception's message
  std::string configuration;
};

struct SweepOptions {
  std::uint64_t seed = 1;
  int runs = 1000;
  int runs_per_planet = 100;
  Targets targets = Targets::both;
  // Run only this index (its planet's tables and the one run); -1: all.
  int replay = -1;
  // Without replay: start at this index (0 .. runs - 1), to resume a sweep;
  // the runs before it are skipped, not run.
  int first_run = 0;
  // Called after every run with the runs done and the total.
  std::function<void(int done, int total, const std::string& status)> progress;
  // Called with one line per planet (its preparation times) and per run
  // (target, time, outcome) when set.
  std::function<void(const std::string& line)> log;
};

struct SweepResult {
  int runs = 0;
  int renderer_runs = 0;
  int plugin_runs = 0;
  int planets = 0;
  std::map<std::string, int> failures_by_kind;
  std::vector<Failure> failures;
  // Planets whose tables the library refuses with an atmos::Error (e.g. a
  // thick atmosphere its coarse random tables cannot represent): a clear
  // error is the library's answer to an impossible combination, so their
  // runs are counted here, not as failures. One line per planet: its index,
  // recipe and the error.
  int refused_runs = 0;
  std::vector<std::string> refusals;
  long long pixels = 0;
  long long out_of_gamut_pixels = 0;
  long long half_overflow_pixels = 0;  // infinite in an RGBA16F output whose RGBA32F render exceeds 65504
  double precompute_seconds = 0.0;
  double setup_seconds = 0.0;  // Renderer and AtmospherePass construction
  double render_seconds = 0.0;
  double seconds = 0.0;
};

// Runs the sweep with an OpenGL 4.5 context current on the calling thread
// (GlContext::create_headless()). Never throws for the library's errors:
// every atmos::Error or other exception of a run is a Failure, except the
// precomputation's atmos::Error for a planet (SweepResult::refusals).
SweepResult run_sweep(const SweepOptions& options);

// One line per failure kind, the counts and the times.
std::string summary(const SweepResult& result, const SweepOptions& options);
std::string describe(const Failure& failure);

// The run index being executed by run_sweep (for a crash handler), or -1.
int current_run_index();

}  // namespace atmos::sweep
