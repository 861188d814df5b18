// atmos_example_terrain — an example engine that renders its own scene and
// hands its colour and depth buffers to atmos::AtmospherePass.
//
// The engine (everything in this folder but the calls to atmos) draws a
// fractal terrain on an 80 km patch of the planet and a few objects with its
// own shaders into its own framebuffer, lit with the atmosphere's sun and sky
// through atmos's GLSL library, with a sun shadow map. The plugin then adds
// the sky, the rest of the planet, aerial perspective and light shafts.
// docs/plugin.md walks through the integration; it is all in run() below.
//
//   atmos_example_terrain --scene noon-valley -o valley.png -o valley.exr
//   atmos_example_terrain --scene sunset-shafts --depth reversed-z -o shafts.png
//   atmos_example_terrain --scene orbit-400km --surfaces gbuffer -o orbit.png
//
// Exit codes: 0 success, 1 runtime error (no OpenGL 4.5, bad planet file,
// unwritable output), 2 usage error (unknown flag, bad value).
#include <CLI/CLI.hpp>

#include <glm/vec3.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <atmos/atmosphere.hpp>
#include <atmos/image.hpp>
#include <atmos/plugin.hpp>
#include <atmos/post.hpp>
#include <atmos/renderer.hpp>
#include <atmos/tables.hpp>

#include "gl.hpp"
#include "renderer.hpp"
#include "scene.hpp"
#include "terrain.hpp"
#include "world.hpp"
#include "atmos/planet_file.hpp"

namespace {

// A bad command-line value: exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

struct Options {
  std::string scene = "noon-valley";
  std::string planet = "earth";
  int width = 1280;
  int height = 720;
  std::string depth = "standard";
  bool infinite_far = false;
  std::string surfaces = "lit-colour";
  std::vector<std::string> outputs;
  double exposure = 13.0;
  std::optional<double> exposure_ev;  // --exposure if given, else the scene's
  bool no_atmosphere = false;
  std::string tables = "default";
  int terrain_cells = 512;
  int shadow_size = 2048;
  int shadow_steps = 24;
  unsigned seed = 7;
  int frames = 1;
  double camera_altitude = 0.0, sun_elevation = 0.0, sun_azimuth = 0.0, fov = 0.0;
  std::string look;
  bool stars = false;
  std::vector<std::string> moons;  // --moon AZ,EL,ANGULAR_RADIUS_DEG (parse_moon)
  std::vector<glm::dvec3> moon_angles;  // parsed: azimuth, elevation, angular radius (degrees)
  // Camera-like PNG output by atmos::PostProcess on the composited texture
  // (any of these given); without, the PNG is write_png's exp tone map.
  std::string tonemap = "exp";
  double bloom = 0.0;
  bool auto_exposure = false;
  bool post = false;
};

double finite(double v, const std::string& name) {
  if (!std::isfinite(v)) throw UsageError(name + " must be a finite number");
  return v;
}

void check_range(double v, double lo, double hi, const std::string& name) {
  if (!(finite(v, name) >= lo && v <= hi)) {
    std::ostringstream message;
    message << name << " must be in [" << lo << ", " << hi << "], got " << v;
    throw UsageError(message.str());
  }
}

// "AZ,EL" -> two finite numbers.
std::pair<double, double> parse_look(const std::string& text) {
  std::istringstream in(text);
  double az = 0.0, el = 0.0;
  char comma = 0, extra = 0;
  if (!(in >> az >> comma >> el) || comma != ',' || (in >> extra))
    throw UsageError("--look expects AZ,EL in degrees, e.g. 180,10, got \"" + text + "\"");
  check_range(az, -360.0, 360.0, "--look azimuth");
  check_range(el, -90.0, 90.0, "--look elevation");
  return {az, el};
}

// "AZ,EL,R" -> (AZ, EL, R) in degrees: a moon R degrees in angular radius
// in the direction (AZ, EL), see the moons in run().
glm::dvec3 parse_moon(const std::string& text) {
  std::istringstream in(text);
  double az = 0.0, el = 0.0, radius = 0.0;
  char comma_1 = 0, comma_2 = 0, extra = 0;
  if (!(in >> az >> comma_1 >> el >> comma_2 >> radius) || comma_1 != ',' || comma_2 != ',' || (in >> extra))
    throw UsageError("--moon expects AZ,EL,ANGULAR_RADIUS_DEG, e.g. 180,25,0.28, got \"" + text + "\"");
  check_range(az, -360.0, 360.0, "--moon azimuth");
  check_range(el, -90.0, 90.0, "--moon elevation");
  if (!(finite(radius, "--moon angular radius") > 0.0) || radius > 10.0)
    throw UsageError("--moon angular radius must be in (0, 10] degrees");
  return {az, el, radius};
}

bool has_extension(const std::string& path, const std::string& extension) {
  if (path.size() < extension.size()) return false;
  std::string tail = path.substr(path.size() - extension.size());
  std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return tail == extension;
}

atmos::DepthEncoding depth_encoding(const std::string& name) {
  if (name == "reversed-z") return atmos::DepthEncoding::reversed_z;
  if (name == "log") return atmos::DepthEncoding::logarithmic;
  return atmos::DepthEncoding::standard;
}

// The plugin's output texture (or the engine's colour buffer) as an
// atmos::Image: RGB floats in cd/m², rows top-down (OpenGL's go bottom-up).
atmos::Image read_image(GLuint texture, int width, int height, double nits_per_unit) {
  std::vector<float> rgba(static_cast<size_t>(width) * height * 4);
  glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, static_cast<GLsizei>(rgba.size() * sizeof(float)), rgba.data());
  atmos::Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(static_cast<size_t>(width) * height * 3);
  for (int y = 0; y < height; ++y) {
    const float* source = rgba.data() + static_cast<size_t>(height - 1 - y) * width * 4;
    float* target = image.rgb.data() + static_cast<size_t>(y) * width * 3;
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c) target[3 * x + c] = static_cast<float>(source[4 * x + c] * nits_per_unit);
  }
  return image;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

void check_gl_errors(const char* where) {
  const GLenum error = glGetError();
  if (error != GL_NO_ERROR) {
    char message[96];
    std::snprintf(message, sizeof message, "OpenGL error 0x%04x in %s", error, where);
    throw engine::gl::Error(message);
  }
}

int run(const Options& o, const engine::SceneOverrides& overrides) {
  // --- Start-up -------------------------------------------------------------
  // 1. An OpenGL 4.5 core context. A real engine has its own (window, EGL,
  //    GLFW...); this one is headless. It must stay current while the pass
  //    and the engine's GL objects live.
  auto context = atmos::GlContext::create_headless();

  // 2. The planet and its precomputed tables (cached on disk, in
  //    $ATMOS_CACHE_DIR or ~/.cache/atmos: only the first run computes them).
  const atmos::Atmosphere planet = atmos::load_atmosphere(o.planet);
  atmos::PrecomputeOptions precompute;
  if (o.tables == "small") precompute.sizes = atmos::TableSizes{64, 16, 32, 8, 4, 16, 32, 8};  // tests only
  const auto tables_start = std::chrono::steady_clock::now();
  const atmos::CacheResult cached =
      atmos::load_or_precompute_tables(planet, precompute, atmos::default_cache_directory());
  const double tables_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - tables_start).count();

  // 3. The engine's world and scene. Engine units are kilometres and the
  //    planet's centre is far from the origin: PlanetFrame tells the pass.
  const engine::World world(planet.bottom_radius_m);
  const glm::vec3 planet_albedo(static_cast<float>(planet.ground_albedo.at(680.0)),
                                static_cast<float>(planet.ground_albedo.at(550.0)),
                                static_cast<float>(planet.ground_albedo.at(440.0)));
  const auto terrain_start = std::chrono::steady_clock::now();
  const engine::Terrain terrain(world, {o.seed, o.terrain_cells}, planet_albedo);
  const double terrain_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - terrain_start).count();
  engine::Scene scene = engine::make_scene(o.scene, overrides, world, terrain);
  // The moons (--moon), in planet-centred metres as atmos wants them: seen
  // from the camera in the direction (AZ, EL) of the patch centre's local
  // frame — the frame of --sun-azimuth / --sun-elevation, so that the sun's
  // own angles put the moon on the sun as seen from the camera — at the
  // Moon's distance (the CLI's `atmos render --moon`).
  const glm::dvec3 camera_planet_m = (scene.camera.position - world.planet_centre()) / engine::kUnitsPerMetre;
  for (const glm::dvec3& moon : o.moon_angles)
    scene.moons.push_back(atmos::moon_in_sky(camera_planet_m, world.local_frame({0.0, 0.0}).direction(moon.x, moon.y),
                                             moon.z * M_PI / 180.0));

  // 4. The atmosphere pass, in the engine's current context. Its GLSL
  //    library goes into the engine's fragment shader, which lights the
  //    terrain with the atmosphere's sun and sky.
  //    Its programs compile at their first use, in the first frame
  //    (PassPrograms::none: the timings below skip that frame), not ahead.
  const auto pass_start = std::chrono::steady_clock::now();
  atmos::AtmospherePass pass(planet, cached.tables, world.planet_frame(), atmos::PassPrograms::none);
  const double pass_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - pass_start).count();
  engine::RenderSettings settings;
  settings.width = o.width;
  settings.height = o.height;
  settings.depth = depth_encoding(o.depth);
  settings.infinite_far = o.infinite_far;
  settings.surfaces = o.surfaces == "gbuffer" ? atmos::SurfaceMode::gbuffer : atmos::SurfaceMode::lit_colour;
  settings.shadow_map_size = o.shadow_size;
  settings.eclipse = !scene.moons.empty();  // the engine's own shader dims its lighting (lit colour)
  engine::SceneRenderer renderer(settings, world, terrain, pass.glsl_library(engine::kAtmosphereFirstUnit));
  // The composited image goes into a texture the engine owns (RGBA32F: the
  // sun's disc, ~1e9 cd/m², would overflow half floats).
  const engine::gl::Handle composited = engine::gl::create_texture_2d(GL_RGBA32F, o.width, o.height);
  check_gl_errors("start-up");

  std::printf("atmos_example_terrain: %s, %dx%d, depth %s%s, %s surfaces, planet %s\n", scene.name.c_str(), o.width,
              o.height, o.depth.c_str(), o.infinite_far ? " (infinite far plane)" : "", o.surfaces.c_str(),
              planet.name.c_str());
  std::printf("  GL: %s\n", context->renderer_string().c_str());
  std::printf("  tables: %s %s in %.2f s\n", cached.status == atmos::CacheStatus::hit ? "loaded from" : "computed into",
              cached.path.c_str(), tables_s);
  std::printf("  terrain: %dx%d vertices, generated in %.2f s\n", o.terrain_cells + 1, o.terrain_cells + 1, terrain_s);
  std::printf("  atmosphere pass: created in %.2f s (table upload, shader compilation)\n", pass_s);

  // --- One frame (several with --frames, for steadier timings) --------------
  std::vector<double> shadow_ms, scene_ms, sky_view_ms, volume_ms, composite_ms, total_ms;
  for (int frame = 0; frame < o.frames; ++frame) {
    // The engine's own passes: shadow map, then its scene.
    shadow_ms.push_back(engine::gl::timed_ms([&] { renderer.render_shadow_map(scene); }));
    scene_ms.push_back(engine::gl::timed_ms([&] { renderer.render_scene(scene, pass); }));
    check_gl_errors("the engine's passes");
    if (o.no_atmosphere) continue;

    // The atmosphere over the engine's buffers.
    atmos::FrameInput input;
    input.colour = renderer.colour_texture();
    input.depth = renderer.depth_texture();
    input.albedo = renderer.albedo_texture();  // G-buffer mode only (0 otherwise)
    input.normal = renderer.normal_texture();
    input.width = o.width;
    input.height = o.height;
    input.surfaces = settings.surfaces;
    input.depth_encoding = settings.depth;
    input.log_depth_far = renderer.log_depth_far();
    input.view = renderer.view();  // world -> view, double, engine units
    input.projection = renderer.projection();
    input.sun_direction = scene.sun_direction;
    input.nits_per_unit = settings.nits_per_unit;
    input.shadow_map = renderer.shadow_map();  // 0 with --shadow-size 0: no shafts
    input.shadow_matrix = renderer.shadow_matrix();
    input.shadow_steps = o.shadow_steps;
    input.stars = o.stars;
    input.moons = scene.moons;  // an eclipse (empty: none)
    input.output = composited.get();
    input.timed = true;  // measure the pass (waits for the GPU: a tool's choice, not a game's)
    pass.render(input);
    check_gl_errors("AtmospherePass::render");
    const atmos::PassTimings& timings = pass.last_timings();
    sky_view_ms.push_back(timings.sky_view_ms);
    volume_ms.push_back(timings.volume_ms);
    composite_ms.push_back(timings.composite_ms);
    total_ms.push_back(timings.total_ms());
  }

  // Timings: the median over the frames after the first (which includes
  // shader compilation and, on llvmpipe, code generation), if there are any.
  auto steady = [](std::vector<double> v) {
    if (v.size() > 1) v.erase(v.begin());
    return median(std::move(v));
  };
  std::printf("  engine: shadow map %.1f ms (%d^2), scene %.1f ms (%lld triangles)\n", steady(shadow_ms), o.shadow_size,
              steady(scene_ms), renderer.triangles());
  if (!o.no_atmosphere)
    std::printf("  atmosphere: sky-view %.1f ms, aerial-perspective volume %.1f ms, composite %.1f ms, total %.1f ms\n",
                steady(sky_view_ms), steady(volume_ms), steady(composite_ms), steady(total_ms));

  // --- Output ---------------------------------------------------------------
  const GLuint shown = o.no_atmosphere ? renderer.colour_texture() : composited.get();
  const atmos::Image image = read_image(shown, o.width, o.height, settings.nits_per_unit);
  check_gl_errors("read-back");
  const double exposure = o.exposure_ev.value_or(scene.exposure_ev);
  // Camera-like output: the post chain runs on the GPU over the composited
  // texture itself (in the engine's units: nits_per_unit), as an engine
  // would run it every frame, and only its 8-bit result is read back.
  atmos::DisplayImage display;
  if (o.post) {
    atmos::PostProcess post;
    atmos::PostSettings post_settings;
    post_settings.tone_mapping = atmos::parse_tone_mapping(o.tonemap);
    post_settings.exposure_ev = exposure;
    post_settings.bloom.strength = o.bloom;
    post_settings.auto_exposure.enabled = o.auto_exposure;
    atmos::PostInput in;
    in.colour = shown;
    in.width = o.width;
    in.height = o.height;
    in.nits_per_unit = settings.nits_per_unit;
    in.timed = true;
    const GLuint ldr = post.process(in, post_settings);
    const atmos::DisplayImage rows_up = atmos::read_display_image(ldr, o.width, o.height);
    // GL's rows go up, an image's down.
    display = rows_up;
    for (int y = 0; y < o.height; ++y)
      std::copy_n(rows_up.rgb.begin() + std::ptrdiff_t(size_t(o.height - 1 - y) * size_t(o.width) * 3),
                  size_t(o.width) * 3, display.rgb.begin() + std::ptrdiff_t(size_t(y) * size_t(o.width) * 3));
    const atmos::PostTimings& t = post.last_timings();
    std::printf("  post: bloom %.1f ms, exposure %.1f ms, tone map %.1f ms (%s%s)\n", t.bloom_ms, t.exposure_ms,
                t.tone_map_ms, o.tonemap.c_str(), o.auto_exposure ? ", auto exposure" : "");
    if (o.auto_exposure) std::printf("  auto exposure: EV100 %.2f\n", post.current_exposure_ev());
    check_gl_errors("post-processing");
  }
  for (const std::string& path : o.outputs.empty() ? std::vector<std::string>{scene.name + ".png"} : o.outputs) {
    if (o.post && has_extension(path, ".png")) {
      atmos::write_png(display, path);
    } else {
      atmos::write_image(image, path, exposure);
    }
    std::printf("wrote %s\n", path.c_str());
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "atmos example engine: a fractal terrain rendered by its own shaders, composited by "
      "atmos::AtmospherePass (sky, aerial perspective, light shafts)"};
  Options o;
  app.add_option("--scene", o.scene, "noon-valley | sunset-shafts | orbit-400km")
      ->check(CLI::IsMember(engine::scene_names()))
      ->capture_default_str();
  app.add_option("--planet", o.planet, "Preset name (earth, mars, ...) or planet JSON file")->capture_default_str();
  app.add_option("--width", o.width, "Image width, pixels")->capture_default_str();
  app.add_option("--height", o.height, "Image height, pixels")->capture_default_str();
  app.add_option("--depth", o.depth, "Depth encoding: standard | reversed-z | log")
      ->check(CLI::IsMember({"standard", "reversed-z", "log"}))
      ->capture_default_str();
  app.add_flag("--infinite-far", o.infinite_far, "Standard depth with an infinite far plane");
  app.add_option("--surfaces", o.surfaces,
                 "lit-colour (the engine lights its surfaces) | gbuffer (albedo + normals, the plugin lights them)")
      ->check(CLI::IsMember({"lit-colour", "gbuffer"}))
      ->capture_default_str();
  app.add_option("-o,--output", o.outputs, "Output file, .png or .exr, repeatable (default <scene>.png)");
  app.add_option("--exposure", o.exposure, "Exposure value EV100 for PNG output (default: the scene's)");
  app.add_flag(
      "--no-atmosphere", o.no_atmosphere,
      "Write the engine's own colour buffer, without the plugin's pass (still lit with the atmosphere's sun and sky)");
  app.add_option("--camera-altitude", o.camera_altitude, "Camera height above the terrain below it, metres");
  app.add_option("--look", o.look, "View direction AZ,EL in degrees (azimuth from north towards east)");
  app.add_option("--sun-elevation", o.sun_elevation, "Sun elevation at the patch centre, degrees");
  app.add_option("--sun-azimuth", o.sun_azimuth, "Sun azimuth at the patch centre, degrees from north towards east");
  app.add_option("--fov", o.fov, "Vertical field of view, degrees");
  app.add_option("--tables", o.tables, "Table sizes: default | small (fast, for tests)")
      ->check(CLI::IsMember({"default", "small"}))
      ->capture_default_str();
  app.add_option("--terrain-cells", o.terrain_cells, "Terrain grid cells per side (vertices: cells + 1)")
      ->capture_default_str();
  app.add_option("--seed", o.seed, "Terrain noise seed")->capture_default_str();
  app.add_option("--shadow-size", o.shadow_size, "Sun shadow map size, texels (0: no shadows, no shafts)")
      ->capture_default_str();
  app.add_option("--shadow-steps", o.shadow_steps, "Shadow map samples per view ray for light shafts (1-256)")
      ->capture_default_str();
  app.add_option("--frames", o.frames, "Frames to render (timings: median after the first)")->capture_default_str();
  app.add_flag("--stars", o.stars, "Draw the star field behind the sky (FrameInput::stars)");
  app.add_option("--moon", o.moons,
                 "A moon AZ,EL,ANGULAR_RADIUS_DEG seen from the camera (patch-centre frame, e.g. the sun's angles and "
                 "0.28 for a total eclipse), repeatable (FrameInput::moons)");
  auto* tonemap_opt = app.add_option("--tonemap", o.tonemap, "PNG through atmos::PostProcess: exp|reinhard|filmic|aces")
                          ->check(CLI::IsMember({"exp", "reinhard", "filmic", "aces"}));
  auto* bloom_opt = app.add_option("--bloom", o.bloom, "Bloom strength in [0, 1] (PNG through atmos::PostProcess)");
  auto* auto_exposure_opt =
      app.add_flag("--auto-exposure", o.auto_exposure, "Auto exposure (PNG through atmos::PostProcess)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "atmos_example_terrain: error: %s\n", e.what());
    return 2;
  }

  try {
    engine::SceneOverrides overrides;
    if (o.width < 1 || o.width > 16384 || o.height < 1 || o.height > 16384)
      throw UsageError("--width and --height must be in [1, 16384]");
    if (app.count("--camera-altitude")) {
      check_range(o.camera_altitude, 0.5, 1e9, "--camera-altitude");
      overrides.camera_altitude_m = o.camera_altitude;
    }
    if (app.count("--look")) {
      const auto [az, el] = parse_look(o.look);
      overrides.look_azimuth_deg = az;
      overrides.look_elevation_deg = el;
    }
    if (app.count("--sun-elevation")) {
      check_range(o.sun_elevation, -90.0, 90.0, "--sun-elevation");
      overrides.sun_elevation_deg = o.sun_elevation;
    }
    if (app.count("--sun-azimuth")) {
      check_range(o.sun_azimuth, -360.0, 360.0, "--sun-azimuth");
      overrides.sun_azimuth_deg = o.sun_azimuth;
    }
    if (app.count("--fov")) {
      check_range(o.fov, 1.0, 170.0, "--fov");
      overrides.fov_deg = o.fov;
    }
    if (app.count("--exposure")) {
      check_range(o.exposure, -20.0, 40.0, "--exposure");
      o.exposure_ev = o.exposure;
    }
    if (o.infinite_far && o.depth != "standard")
      throw UsageError("--infinite-far applies to --depth standard (reversed-z and log are always infinite)");
    check_range(o.terrain_cells, 2, 4096, "--terrain-cells");
    if (o.shadow_size != 0) check_range(o.shadow_size, 16, 16384, "--shadow-size");
    check_range(o.shadow_steps, 1, 256, "--shadow-steps");
    check_range(o.frames, 1, 1000, "--frames");
    check_range(o.bloom, 0.0, 1.0, "--bloom");
    for (const std::string& text : o.moons) o.moon_angles.push_back(parse_moon(text));
    o.post = tonemap_opt->count() > 0 || bloom_opt->count() > 0 || auto_exposure_opt->count() > 0;
    for (const std::string& path : o.outputs)
      if (!has_extension(path, ".png") && !has_extension(path, ".exr"))
        throw UsageError("output \"" + path + "\" must end in .png or .exr");
    return run(o, overrides);
  } catch (const UsageError& e) {
    std::fprintf(stderr, "atmos_example_terrain: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // atmos::Error, engine::gl::Error, I/O
    std::fprintf(stderr, "atmos_example_terrain: error: %s\n", e.what());
    return 1;
  }
}
