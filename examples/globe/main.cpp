// atmos_example_globe: a whole planet under its atmosphere, as an engine
// would draw it with atmos. The terrain globe (atmos::Globe) draws the
// planet's surface lit by the atmosphere into the engine's colour and
// reversed-Z depth textures; atmos::AtmospherePass adds the aerial
// perspective and the sky. Only atmos's public headers are used.
//
//   atmos_example_globe --planet mars --descent 5 --out-dir frames
//
// renders a descent of 5 frames from 2.5 planet radii to 2 m above the
// ground (logarithmic in altitude), each a PNG, and prints per frame the
// globe's tiles, triangles, CPU selection time and the frame's time.
//
// The terrain's sun shadows are on (four cascades near the camera); the
// globe hands its farthest cascade to the pass, which removes the light the
// shadowed air does not scatter (light shafts). --shadow-cascades 0 turns
// both off.
//
// --ocean draws the sea (atmos::Ocean) over the terrain's flat sea, after
// the globe and before the pass, with the wind of --wind.
//
// --moon AZ,EL,ANGULAR_RADIUS_DEG puts a moon in the sky of the ground
// point (at the Moon's distance; azimuth and elevation as the sun's): with
// the sun's azimuth and elevation and an angular radius above the sun's,
// the ground point is in the umbra of a total eclipse. The globe, the sea
// and the pass are given the same moon.
#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <atmos/atmosphere.hpp>
#include <atmos/eclipse.hpp>
#include <atmos/globe.hpp>
#include <atmos/ocean.hpp>
#include <atmos/planet_file.hpp>
#include <atmos/plugin.hpp>
#include <atmos/post.hpp>
#include <atmos/renderer.hpp>
#include <atmos/tables.hpp>

namespace {

struct Options {
  std::string planet = "earth";
  std::string style;  // default: the planet file's surface style
  std::uint64_t seed = 1;
  bool seed_given = false;
  int width = 960, height = 540;
  int descent = 5;
  double from_radii = 2.5;   // first altitude, planet radii
  double to_m = 2.0;         // last altitude, m
  double sun_elevation = 20.0;  // degrees, at the descent's ground point
  double sun_azimuth = 0.0;     // degrees from north towards east
  double heading = 90.0;        // degrees from north towards east: where the camera looks near the ground
  double latitude = 20.0, longitude = 30.0;  // degrees, the ground point
  double exposure = 13.0;  // EV100 of the PNGs
  double max_screen_error_px = 1.0;
  int shadow_cascades = 4;       // 0: no terrain shadows, no light shafts
  int shadow_size = 2048;        // texels per cascade
  double shadow_distance = 20e3;  // m
  int shadow_steps = 24;         // the pass's shadow-map samples per view ray
  bool ocean = false;       // the sea (atmos::Ocean) over the terrain
  double wind = 7.0;        // m/s, the sea's wind
  int bathymetry_texels = 256;  // per cube face, the sea's depth map (OceanSettings::bathymetry_texels)
  std::optional<double> pitch;  // degrees above the horizontal; none: from the altitude (see run)
  std::vector<double> moon;     // azimuth, elevation, angular radius (degrees); empty: no moon
  bool stars = false;           // the pass's star field
  std::string out_dir = ".";
};

// The engine's texture as an atmos::Image: RGB in cd/m², rows top-down.
atmos::Image read_image(GLuint texture, int width, int height, double nits_per_unit) {
  std::vector<float> rgba(size_t(width) * size_t(height) * 4);
  glGetTextureImage(texture, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
  atmos::Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(size_t(width) * size_t(height) * 3);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      for (int c = 0; c < 3; ++c)
        image.rgb[(size_t(y) * size_t(width) + size_t(x)) * 3 + size_t(c)] =
            float(rgba[(size_t(height - 1 - y) * size_t(width) + size_t(x)) * 4 + size_t(c)] * nits_per_unit);
  return image;
}

int run(const Options& o) {
  auto context = atmos::GlContext::create_headless();
  const atmos::Atmosphere planet = atmos::load_atmosphere(o.planet);
  // The planet file's surface (its "surface" object), the style and seed
  // of the command line replacing its own.
  atmos::PlanetSurface surface = atmos::load_surface(o.planet);
  if (!o.style.empty()) surface.style = atmos::surface_style_from_name(o.style);
  if (o.seed_given) surface.seed = o.seed;
  // The pass's air reaches down to the lowest ground (Mars's lowlands lie
  // kilometres below its datum); the globe keeps the planet's datum.
  const atmos::Atmosphere air = atmos::extend_below_datum(planet, surface);
  // With the tables' response to the ground albedo, the air is lit by the
  // ground below the camera (Globe::regional_albedo), not by a constant.
  atmos::PrecomputeOptions precompute;
  precompute.ground_albedo_response = true;
  const atmos::CacheResult cached = atmos::load_or_precompute_tables(air, precompute, atmos::default_cache_directory());
  // The engine's world: kilometres, planet centred at the origin.
  atmos::PlanetFrame frame;
  frame.units_per_metre = 1e-3;
  atmos::AtmospherePass pass(air, cached.tables, frame);
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  settings.max_screen_error_px = o.max_screen_error_px;
  settings.shadow_cascades = o.shadow_cascades;
  settings.shadow_map_size = o.shadow_size;
  settings.shadow_distance_m = o.shadow_distance;
  atmos::Globe globe(planet, surface, pass, settings);
  std::unique_ptr<atmos::Ocean> ocean;
  if (o.ocean) {
    atmos::OceanSettings sea;
    sea.water.wind_speed_m_s = o.wind;
    sea.bathymetry_texels = o.bathymetry_texels;
    ocean = std::make_unique<atmos::Ocean>(planet, surface, pass, sea);
  }

  // The engine's render targets: lit colour (RGBA32F) and reversed-Z depth.
  GLuint colour = 0, depth = 0, target = 0, output = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &colour);
  glTextureStorage2D(colour, 1, GL_RGBA32F, o.width, o.height);
  glCreateTextures(GL_TEXTURE_2D, 1, &depth);
  glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT32F, o.width, o.height);
  glCreateTextures(GL_TEXTURE_2D, 1, &output);
  glTextureStorage2D(output, 1, GL_RGBA32F, o.width, o.height);
  glCreateFramebuffers(1, &target);
  glNamedFramebufferTexture(target, GL_COLOR_ATTACHMENT0, colour, 0);
  glNamedFramebufferTexture(target, GL_DEPTH_ATTACHMENT, depth, 0);

  // The ground point and its local frame (east, north, up).
  const double lat = glm::radians(o.latitude), lon = glm::radians(o.longitude);
  const glm::dvec3 up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const double radius = planet.bottom_radius_m;
  const double ground = radius + globe.height_m(frame.centre + up * radius * frame.units_per_metre);
  const double sun_el = glm::radians(o.sun_elevation), sun_az = glm::radians(o.sun_azimuth);
  const glm::dvec3 sun = glm::normalize((north * std::cos(sun_az) + east * std::sin(sun_az)) * std::cos(sun_el) +
                                        up * std::sin(sun_el));
  const double heading = glm::radians(o.heading);
  const glm::dvec3 ahead = north * std::cos(heading) + east * std::sin(heading);
  const double nits_per_unit = 1000.0;
  // The moon, placed in the sky of the ground point.
  std::vector<atmos::Moon> moons;
  if (!o.moon.empty()) {
    const double az = glm::radians(o.moon[0]), el = glm::radians(o.moon[1]);
    const glm::dvec3 direction = (north * std::cos(az) + east * std::sin(az)) * std::cos(el) + up * std::sin(el);
    moons.push_back(atmos::moon_in_sky(up * ground, glm::normalize(direction), glm::radians(o.moon[2])));
  }

  std::filesystem::create_directories(o.out_dir);
  const double first = o.from_radii * radius, last = o.to_m;
  for (int f = 0; f < o.descent; ++f) {
    const double t = o.descent > 1 ? double(f) / double(o.descent - 1) : 0.0;
    const double altitude = std::exp(std::log(first) + (std::log(last) - std::log(first)) * t);
    // From far away the camera looks at the planet's centre; near the ground
    // it looks along the heading (east by default), 8 degrees down; with the
    // default sun (north) the relief is lit from the side.
    const double w = std::clamp(std::log10(altitude / 1e3) / std::log10(first / 1e3), 0.0, 1.0);
    const double pitch = glm::radians(o.pitch ? *o.pitch : -8.0 + (-90.0 + 8.0) * w);
    const glm::dvec3 forward = glm::normalize(ahead * std::cos(pitch) + up * std::sin(pitch));
    const glm::dvec3 camera_m = up * (ground + altitude);
    const glm::dvec3 camera = frame.centre + camera_m * frame.units_per_metre;

    atmos::GlobeView view;
    view.view = glm::lookAt(camera, camera + forward, std::abs(pitch) > 1.5 ? ahead : up);
    view.projection = atmos::reversed_z_projection(glm::radians(60.0), double(o.width) / o.height, 1e-6);
    view.width = o.width;
    view.height = o.height;
    view.sun_direction = sun;
    view.nits_per_unit = nits_per_unit;
    view.moons = moons;

    const auto start = std::chrono::steady_clock::now();
    const float clear_colour[4] = {0, 0, 0, 0};
    const float clear_depth = 0.0f;
    glClearNamedFramebufferfv(target, GL_COLOR, 0, clear_colour);
    glClearNamedFramebufferfv(target, GL_DEPTH, 0, &clear_depth);
    glBindFramebuffer(GL_FRAMEBUFFER, target);
    // Before the globe's draw: its ground is lit with the pass's sky light.
    pass.set_ground_albedo(globe.regional_albedo(camera));
    globe.draw(view);
    glFinish();
    const double terrain_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    double ocean_ms = 0.0;
    if (ocean) {
      const auto sea_start = std::chrono::steady_clock::now();
      ocean->draw(view);
      glFinish();
      ocean_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - sea_start).count();
    }

    atmos::FrameInput input;
    input.colour = colour;
    input.depth = depth;
    input.width = o.width;
    input.height = o.height;
    input.depth_encoding = atmos::DepthEncoding::reversed_z;
    input.view = view.view;
    input.projection = view.projection;
    input.sun_direction = sun;
    input.nits_per_unit = nits_per_unit;
    input.output = output;
    input.moons = moons;
    input.stars = o.stars;
    // The terrain's shadow for the pass's light shafts (texture 0: none,
    // when shadows are off or the ground is beyond their reach).
    const atmos::GlobeShadowMap shadow = globe.shadow_map_for_pass();
    input.shadow_map = shadow.texture;
    input.shadow_matrix = shadow.matrix;
    input.shadow_steps = o.shadow_steps;
    pass.render(input);
    glFinish();
    const double frame_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

    const atmos::GlobeStats& s = globe.last_stats();
    char name[64];
    std::snprintf(name, sizeof name, "globe-%02d.png", f);
    const std::string path = (std::filesystem::path(o.out_dir) / name).string();
    atmos::write_png(read_image(output, o.width, o.height, nits_per_unit), path, o.exposure);
    std::printf(
        "%s: altitude %.6g m, %d tiles (%d generated in %.1f ms), %lld triangles, selection %.3f ms (%d nodes), "
        "shadows %d cascades (%d casters, %lld triangles, %.3f ms selection), "
        "terrain %.1f ms, sea %.1f ms, frame %.1f ms, resident %.1f MiB\n",
        path.c_str(), altitude, s.tiles_drawn, s.tiles_generated, s.generation_ms, s.triangles, s.selection_ms,
        s.nodes_visited, s.shadow_cascades, s.shadow_casters, s.shadow_triangles, s.shadow_selection_ms, terrain_ms,
        ocean_ms, frame_ms, double(s.resident_bytes) / (1024.0 * 1024.0));
  }
  glDeleteFramebuffers(1, &target);
  glDeleteTextures(1, &colour);
  glDeleteTextures(1, &depth);
  glDeleteTextures(1, &output);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"atmos_example_globe: a descent from orbit to the ground of a whole planet under its atmosphere"};
  app.add_option("--planet", o.planet, "Planet preset or planet file")->capture_default_str();
  app.add_option("--style", o.style,
                 "Relief style: earth, mars, venus, titan or flat (default: the planet file's \"surface\")");
  auto* seed = app.add_option("--seed", o.seed, "Seed of the procedural relief (default: the planet file's)");
  app.add_option("--width", o.width, "Image width, pixels")->capture_default_str()->check(CLI::Range(16, 8192));
  app.add_option("--height", o.height, "Image height, pixels")->capture_default_str()->check(CLI::Range(16, 8192));
  app.add_option("--descent", o.descent, "Frames of the descent")->capture_default_str()->check(CLI::Range(1, 1000));
  app.add_option("--from-radii", o.from_radii, "First altitude, planet radii")
      ->capture_default_str()
      ->check(CLI::Range(1e-6, 100.0));
  app.add_option("--to", o.to_m, "Last altitude, metres")->capture_default_str()->check(CLI::Range(0.5, 1e9));
  app.add_option("--sun-elevation", o.sun_elevation, "Sun elevation at the ground point, degrees")
      ->capture_default_str()
      ->check(CLI::Range(-90.0, 90.0));
  app.add_option("--sun-azimuth", o.sun_azimuth, "Sun azimuth at the ground point, degrees from north towards east")
      ->capture_default_str()
      ->check(CLI::Range(-360.0, 360.0));
  app.add_option("--heading", o.heading, "Where the camera looks near the ground, degrees from north towards east")
      ->capture_default_str()
      ->check(CLI::Range(-360.0, 360.0));
  app.add_option("--latitude", o.latitude, "Latitude of the ground point, degrees")
      ->capture_default_str()
      ->check(CLI::Range(-89.0, 89.0));
  app.add_option("--longitude", o.longitude, "Longitude of the ground point, degrees")
      ->capture_default_str()
      ->check(CLI::Range(-180.0, 180.0));
  app.add_option("--exposure", o.exposure, "Exposure of the PNGs, EV100")->capture_default_str();
  app.add_option("--max-error", o.max_screen_error_px, "Screen-space error bound of the terrain, pixels")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 100.0));
  app.add_option("--shadow-cascades", o.shadow_cascades,
                 "Cascades of the terrain's sun shadows (0: no shadows, no light shafts)")
      ->capture_default_str()
      ->check(CLI::Range(0, 4));
  app.add_option("--shadow-size", o.shadow_size, "Shadow map size per cascade, texels (even)")
      ->capture_default_str()
      ->check(CLI::Range(64, 16384));
  app.add_option("--shadow-distance", o.shadow_distance, "How far from the camera shadows reach, metres")
      ->capture_default_str()
      ->check(CLI::Range(1.0, 1e7));
  app.add_option("--shadow-steps", o.shadow_steps, "Shadow map samples per view ray for the light shafts (1-256)")
      ->capture_default_str()
      ->check(CLI::Range(1, 256));
  app.add_flag("--ocean", o.ocean, "Draw the sea (atmos::Ocean) over the terrain");
  app.add_option("--wind", o.wind, "Wind over the sea, m/s")->capture_default_str()->check(CLI::Range(0.0, 50.0));
  app.add_option("--bathymetry-texels", o.bathymetry_texels, "The sea's depth map, texels per cube face")
      ->capture_default_str()
      ->check(CLI::Range(16, 2048));
  app.add_option("--pitch", o.pitch, "The camera's pitch, degrees above the horizontal (default: 8 down near "
                                     "the ground, turning to straight down from orbit)")
      ->check(CLI::Range(-90.0, 90.0));
  app.add_option("--moon", o.moon, "A moon in the sky of the ground point: AZ,EL,ANGULAR_RADIUS_DEG")
      ->delimiter(',')
      ->expected(3);
  app.add_flag("--stars", o.stars, "Draw the pass's star field");
  app.add_option("--out-dir", o.out_dir, "Directory of the PNG frames")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  o.seed_given = seed->count() > 0;
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "atmos_example_globe: %s\n", e.what());
    return 1;
  }
}
