#include "harness.hpp"

#include <epoxy/gl.h>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <thread>

#include "atmos/eclipse.hpp"
#include "atmos/globe.hpp"
#include "atmos/ocean.hpp"
#include "atmos/post.hpp"
#include "atmos/sky.hpp"

namespace atmos_bench {

namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string size_suffix(int width, int height) { return "." + std::to_string(width) + "x" + std::to_string(height); }

}  // namespace

std::string format_figure(const Figure& figure) {
  char value[64];
  const char* format = figure.unit == "s" || figure.unit == "ratio" ? "%.3f" : (figure.unit == "count" ? "%.0f" : "%.1f");
  std::snprintf(value, sizeof value, format, figure.value);
  return figure.name + "\t" + value + "\t" + figure.unit;
}

double median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  return values[values.size() / 2];
}

atmos::Tables time_precomputation(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options,
                                  const FigureSink& sink) {
  const auto start = std::chrono::steady_clock::now();
  atmos::Tables tables = atmos::precompute_tables(atmosphere, options);
  const double total = seconds_since(start);
  for (const auto& step : tables.timings) sink({"precompute." + step.name, step.seconds, "s"});
  sink({"precompute.total", total, "s"});
  return tables;
}

atmos::Tables time_spectral_precomputation(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options,
                                           atmos::Atmosphere& spectral_atmosphere, const FigureSink& sink) {
  spectral_atmosphere = atmosphere;
  spectral_atmosphere.wavelengths_nm = atmos::spectral_wavelengths(15);
  atmos::PrecomputeOptions spectral_options = options;
  spectral_options.scattering_orders = 6;
  spectral_options.auto_orders = false;
  const auto start = std::chrono::steady_clock::now();
  atmos::Tables tables = atmos::precompute_tables(spectral_atmosphere, spectral_options);
  sink({"precompute.spectral15.orders6", seconds_since(start), "s"});
  return tables;
}

atmos::Camera frame_camera(const atmos::Atmosphere& atmosphere, int width, int height) {
  atmos::Camera c;
  c.position = atmos::observer_position(atmosphere, 2.0);
  c.forward = atmos::direction_from_azimuth_elevation(180.0, 10.0);
  c.up = glm::dvec3(0.0, 0.0, 1.0);
  c.fov_deg = 60.0;
  c.projection = atmos::Projection::perspective;
  c.width = width;
  c.height = height;
  return c;
}

FrameTime time_frame(atmos::Renderer& renderer, const atmos::Camera& camera, const glm::dvec3& sun_direction) {
  renderer.render(camera, sun_direction);
  return {renderer.last_frame_ms(), renderer.last_sky_view_ms()};
}

void time_frames(atmos::Renderer& renderer, const atmos::Camera& camera, const glm::dvec3& sun_direction, int runs,
                 const std::string& name, const FigureSink& sink) {
  (void)time_frame(renderer, camera, sun_direction);
  std::vector<double> frame, sky_view;
  for (int i = 0; i < runs; ++i) {
    const FrameTime t = time_frame(renderer, camera, sun_direction);
    frame.push_back(t.frame_ms);
    sky_view.push_back(t.sky_view_ms);
  }
  sink({name + size_suffix(camera.width, camera.height), median(frame), "ms"});
  sink({name + ".sky_view", median(sky_view), "ms"});
}

PluginScene::PluginScene(const atmos::Atmosphere& atmosphere, int w, int h) {
  const double R = atmosphere.bottom_radius_m;
  camera_ = glm::dvec3(0.0, 0.0, R + 300.0);
  const glm::dvec3 forward = glm::normalize(glm::dvec3(0.0, 1.0, -std::tan(glm::radians(3.0))));
  input_.width = w;
  input_.height = h;
  input_.view = glm::lookAt(camera_, camera_ + forward, glm::dvec3(0.0, 0.0, 1.0));
  input_.projection = glm::perspective(glm::radians(60.0), double(w) / double(h), 0.5, 1e7);
  input_.timed = true;
  // The depth of the nearest sphere along each pixel's ray (ray-sphere
  // intersection), as the engine's depth buffer would hold it.
  struct Sphere {
    glm::dvec3 centre;
    double radius;
  };
  const std::vector<Sphere> scene = {{{0.0, 0.0, 0.0}, R},
                                     {{-3e3, 12e3, R - 4e3}, 5e3},
                                     {{9e3, 30e3, R - 8e3}, 10e3},
                                     {{-20e3, 60e3, R - 15e3}, 18e3}};
  std::vector<float> depth(size_t(w) * size_t(h), 1.0f);
  const glm::dmat4 view_projection = input_.projection * input_.view;
  const glm::dmat4 inverse = glm::inverse(view_projection);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const glm::dvec4 p = inverse * glm::dvec4((x + 0.5) / w * 2.0 - 1.0, (y + 0.5) / h * 2.0 - 1.0, -1.0, 1.0);
      const glm::dvec3 ray = glm::normalize(glm::dvec3(p) / p.w - camera_);
      double nearest = -1.0;
      for (const Sphere& sphere : scene) {
        const glm::dvec3 oc = camera_ - sphere.centre;
        const double b = glm::dot(oc, ray), c = glm::dot(oc, oc) - sphere.radius * sphere.radius;
        const double disc = b * b - c;
        if (disc < 0.0) continue;
        const double t = -b - std::sqrt(disc);
        if (t > 0.0 && (nearest < 0.0 || t < nearest)) nearest = t;
      }
      if (nearest < 0.0) continue;
      const glm::dvec4 clip = view_projection * glm::dvec4(camera_ + ray * nearest, 1.0);
      depth[size_t(y) * size_t(w) + size_t(x)] = float(0.5 * clip.z / clip.w + 0.5);
    }
  const std::vector<float> colour(size_t(w) * size_t(h) * 4, 400.0f);
  GLuint textures[2] = {0, 0};
  glCreateTextures(GL_TEXTURE_2D, 2, textures);
  glTextureStorage2D(textures[0], 1, GL_DEPTH_COMPONENT32F, w, h);
  glTextureSubImage2D(textures[0], 0, 0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
  glTextureStorage2D(textures[1], 1, GL_RGBA16F, w, h);
  glTextureSubImage2D(textures[1], 0, 0, 0, w, h, GL_RGBA, GL_FLOAT, colour.data());
  textures_[0] = textures[0];
  textures_[1] = textures[1];
  input_.depth = textures[0];
  input_.colour = textures[1];
}

PluginScene::~PluginScene() {
  const GLuint textures[2] = {textures_[0], textures_[1]};
  glDeleteTextures(2, textures);
}

atmos::FrameInput PluginScene::input(double sun_elevation_deg, bool eclipse) const {
  atmos::FrameInput input = input_;
  input.sun_direction = atmos::direction_from_azimuth_elevation(20.0, sun_elevation_deg);
  if (eclipse) input.moons = {atmos::moon_in_sky(camera_, input.sun_direction, 0.28 * M_PI / 180.0)};
  return input;
}

void time_plugin(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, int width, int height,
                 const FigureSink& sink) {
  const PluginScene scene(atmosphere, width, height);
  atmos::AtmospherePass pass(atmosphere, tables, atmos::PlanetFrame{});
  struct Case {
    const char* name;
    double sun_elevation_deg;
    bool eclipse;
  };
  const Case cases[] = {{"plugin", 35.0, false}, {"plugin.sunset", 4.0, false}, {"plugin.eclipse", 35.0, true}};
  for (const Case& c : cases) {
    const atmos::FrameInput input = scene.input(c.sun_elevation_deg, c.eclipse);
    pass.render(input);  // warm-up: compiles this variant
    std::vector<double> total, sky_view, volume, composite;
    for (int i = 0; i < 5; ++i) {
      pass.render(input);
      const atmos::PassTimings& t = pass.last_timings();
      total.push_back(t.total_ms());
      sky_view.push_back(t.sky_view_ms);
      volume.push_back(t.volume_ms);
      composite.push_back(t.composite_ms);
    }
    const std::string name = c.name;
    sink({name + size_suffix(width, height), median(total), "ms"});
    sink({name + ".sky_view", median(sky_view), "ms"});
    sink({name + ".volume", median(volume), "ms"});
    sink({name + ".composite", median(composite), "ms"});
  }
}

void time_instant(const atmos::Atmosphere& atmosphere, int width, int height, const FigureSink& sink) {
  using Clock = std::chrono::steady_clock;
  const auto seconds_of = [](const atmos::Atmosphere& a) {
    std::vector<double> times;
    for (int i = 0; i < 3; ++i) {
      const auto t0 = Clock::now();
      (void)atmos::compute_instant_tables(a);
      times.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
    }
    return median(times);
  };
  sink({"precompute.instant", seconds_of(atmosphere), "s"});
  atmos::Atmosphere spectral = atmosphere;
  spectral.wavelengths_nm = atmos::spectral_wavelengths(15);
  sink({"precompute.instant.spectral15", seconds_of(spectral), "s"});
  const atmos::InstantTables tables = atmos::compute_instant_tables(atmosphere);
  const PluginScene scene(atmosphere, width, height);
  const auto t0 = Clock::now();
  atmos::AtmospherePass pass(atmosphere, tables, atmos::PlanetFrame{});
  glFinish();
  sink({"plugin.instant.create", std::chrono::duration<double, std::milli>(Clock::now() - t0).count(), "ms"});
  for (const auto& [name, sun_elevation] : {std::pair{"plugin.instant", 35.0}, std::pair{"plugin.instant.sunset", 4.0}}) {
    const atmos::FrameInput input = scene.input(sun_elevation, false);
    pass.render(input);  // warm-up: compiles this variant
    std::vector<double> total, sky_view, volume, composite;
    for (int i = 0; i < 5; ++i) {
      pass.render(input);
      const atmos::PassTimings& t = pass.last_timings();
      total.push_back(t.total_ms());
      sky_view.push_back(t.sky_view_ms);
      volume.push_back(t.volume_ms);
      composite.push_back(t.composite_ms);
    }
    const std::string n = name;
    sink({n + size_suffix(width, height), median(total), "ms"});
    sink({n + ".sky_view", median(sky_view), "ms"});
    sink({n + ".volume", median(volume), "ms"});
    sink({n + ".composite", median(composite), "ms"});
  }
}

void time_ground_albedo(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options,
                        const FigureSink& sink) {
  using Clock = std::chrono::steady_clock;
  atmos::PrecomputeOptions o = options;
  o.ground_albedo_response = true;
  const auto t0 = Clock::now();
  const atmos::Tables tables = atmos::precompute_tables(atmosphere, o);
  sink({"precompute.ground_albedo_response", std::chrono::duration<double>(Clock::now() - t0).count(), "s"});
  atmos::AtmospherePass pass(atmosphere, tables, atmos::PlanetFrame{});
  std::vector<double> times;
  for (int i = 0; i < 6; ++i) {
    const auto t1 = Clock::now();
    pass.set_ground_albedo(glm::dvec3(i % 2 == 0 ? 0.3 : 0.35));
    glFinish();
    times.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t1).count());
  }
  sink({"plugin.ground_albedo", median(times), "ms"});
}

namespace {

// A camera `altitude_m` above the ground (or above `floor_m`, the sea level
// over a sea) at latitude 20°, longitude 30° (or the given point), looking
// at the planet's centre from afar and towards the horizon (8° down) below
// 1 km, as examples/globe does; sun 25° up in the north.
atmos::GlobeView globe_view(const atmos::Globe& globe, const atmos::Atmosphere& atmosphere, double altitude_m,
                            int width, int height, double latitude_deg = 20.0, double longitude_deg = 30.0,
                            double floor_m = -std::numeric_limits<double>::infinity()) {
  const double lat = latitude_deg * M_PI / 180.0, lon = longitude_deg * M_PI / 180.0;
  const glm::dvec3 up(std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat));
  const glm::dvec3 east = glm::normalize(glm::cross(glm::dvec3(0, 0, 1), up));
  const glm::dvec3 north = glm::cross(up, east);
  const double radius = atmosphere.bottom_radius_m;
  const double ground = radius + std::max(globe.height_m(up * radius), floor_m);
  const double far = 2.5 * radius;
  const double w = std::clamp(std::log10(altitude_m / 1e3) / std::log10(far / 1e3), 0.0, 1.0);
  const double pitch = (-8.0 + (-90.0 + 8.0) * w) * M_PI / 180.0;
  const glm::dvec3 forward = glm::normalize(north * std::cos(pitch) + up * std::sin(pitch));
  const glm::dvec3 camera = up * (ground + altitude_m);
  atmos::GlobeView view;
  view.view = glm::lookAt(camera, camera + forward, std::abs(pitch) > 1.5 ? north : up);
  view.projection = atmos::reversed_z_projection(60.0 * M_PI / 180.0, double(width) / height, 0.05);
  view.width = width;
  view.height = height;
  const double sun_el = 25.0 * M_PI / 180.0;
  view.sun_direction = glm::normalize(north * std::cos(sun_el) + up * std::sin(sun_el));
  view.nits_per_unit = 1000.0;
  return view;
}

// An engine's frame for the globe: its colour and depth targets and the
// pass's output at width x height. frame() draws the terrain into them, the
// sea over it if `ocean` (its own time in `sea_ms`), then the pass; it
// returns the whole frame's wall-clock time up to glFinish, ms, and the
// terrain's in `terrain_ms`.
class EngineFrame {
 public:
  EngineFrame(atmos::AtmospherePass& pass, int width, int height) : pass_(pass), width_(width), height_(height) {
    glCreateTextures(GL_TEXTURE_2D, 1, &colour_);
    glTextureStorage2D(colour_, 1, GL_RGBA16F, width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &depth_);
    glTextureStorage2D(depth_, 1, GL_DEPTH_COMPONENT32F, width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &output_);
    glTextureStorage2D(output_, 1, GL_RGBA16F, width, height);
    glCreateFramebuffers(1, &framebuffer_);
    glNamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, colour_, 0);
    glNamedFramebufferTexture(framebuffer_, GL_DEPTH_ATTACHMENT, depth_, 0);
  }
  EngineFrame(const EngineFrame&) = delete;
  EngineFrame& operator=(const EngineFrame&) = delete;
  ~EngineFrame() {
    glDeleteFramebuffers(1, &framebuffer_);
    glDeleteTextures(1, &colour_);
    glDeleteTextures(1, &depth_);
    glDeleteTextures(1, &output_);
  }

  double operator()(atmos::Globe& globe, const atmos::GlobeView& view, double& terrain_ms,
                    atmos::Ocean* ocean = nullptr, double* sea_ms = nullptr) {
    using Clock = std::chrono::steady_clock;
    const auto ms_since = [](Clock::time_point t0) {
      return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    };
    const auto t0 = Clock::now();
    const float clear_colour[4] = {0, 0, 0, 0}, clear_depth = 0.0f;
    glClearNamedFramebufferfv(framebuffer_, GL_COLOR, 0, clear_colour);
    glClearNamedFramebufferfv(framebuffer_, GL_DEPTH, 0, &clear_depth);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    globe.draw(view);
    glFinish();
    terrain_ms = ms_since(t0);
    if (ocean != nullptr) {
      const auto sea_start = Clock::now();
      ocean->draw(view);
      glFinish();
      if (sea_ms != nullptr) *sea_ms = ms_since(sea_start);
    }
    pass_.render(input(globe, view));
    glFinish();
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    return ms_since(t0);
  }

  // The pass's input for the globe's view.
  atmos::FrameInput input(const atmos::Globe& globe, const atmos::GlobeView& view) const {
    atmos::FrameInput input;
    input.colour = colour_;
    input.depth = depth_;
    input.width = width_;
    input.height = height_;
    input.depth_encoding = atmos::DepthEncoding::reversed_z;
    input.view = view.view;
    input.projection = view.projection;
    input.sun_direction = view.sun_direction;
    input.nits_per_unit = view.nits_per_unit;
    input.output = output_;
    // With the globe's shadows, its farthest cascade for the light shafts.
    const atmos::GlobeShadowMap shadow = globe.shadow_map_for_pass();
    input.shadow_map = shadow.texture;
    input.shadow_matrix = shadow.matrix;
    return input;
  }

 private:
  atmos::AtmospherePass& pass_;
  int width_, height_;
  GLuint colour_ = 0, depth_ = 0, output_ = 0, framebuffer_ = 0;
};

}  // namespace

void time_globe(atmos::GlContext& context, const atmos::Atmosphere& atmosphere, const atmos::Tables& tables,
                int width, int height, const FigureSink& sink) {
  atmos::AtmospherePass pass(atmosphere, tables, atmos::PlanetFrame{});
  EngineFrame frame(pass, width, height);
  {
    atmos::GlobeSettings settings;
    settings.complete_every_frame = true;
    atmos::Globe globe(atmosphere, atmos::load_surface("earth"), pass, settings);
    const double radius = atmosphere.bottom_radius_m;
    const std::pair<const char*, double> altitudes[] = {
        {"2m", 2.0}, {"10km", 10e3}, {"400km", 400e3}, {"2.5R", 2.5 * radius}};
    for (const auto& [name, altitude] : altitudes) {
      const atmos::GlobeView view = globe_view(globe, atmosphere, altitude, width, height);
      double terrain_ms = 0.0;
      frame(globe, view, terrain_ms);  // generates the tiles, compiles the pass's variant
      std::vector<double> frames, terrain, selection;
      for (int i = 0; i < 3; ++i) {
        frames.push_back(frame(globe, view, terrain_ms));
        terrain.push_back(terrain_ms);
        selection.push_back(globe.last_stats().selection_ms);
      }
      const std::string prefix = std::string("globe.") + name;
      sink({prefix + ".frame", median(frames), "ms"});
      sink({prefix + ".terrain", median(terrain), "ms"});
      sink({prefix + ".selection", median(selection), "ms"});
      sink({prefix + ".triangles", double(globe.last_stats().triangles), "count"});
      sink({prefix + ".tiles", double(globe.last_stats().tiles_drawn), "count"});
    }
  }
  {
    // Sun shadows (4 cascades of 2048^2 over 20 km) and the pass's light
    // shafts from the farthest cascade, near the ground.
    atmos::GlobeSettings settings;
    settings.complete_every_frame = true;
    settings.shadow_cascades = 4;
    atmos::Globe globe(atmosphere, atmos::load_surface("earth"), pass, settings);
    const std::pair<const char*, double> altitudes[] = {{"2m", 2.0}, {"10km", 10e3}};
    for (const auto& [name, altitude] : altitudes) {
      const atmos::GlobeView view = globe_view(globe, atmosphere, altitude, width, height);
      double terrain_ms = 0.0;
      frame(globe, view, terrain_ms);  // generates the tiles, compiles the pass's shadow variant
      std::vector<double> frames, terrain, shadow_selection;
      for (int i = 0; i < 3; ++i) {
        frames.push_back(frame(globe, view, terrain_ms));
        terrain.push_back(terrain_ms);
        shadow_selection.push_back(globe.last_stats().shadow_selection_ms);
      }
      const std::string prefix = std::string("globe.") + name + ".shadows";
      sink({prefix + ".frame", median(frames), "ms"});
      sink({prefix + ".terrain", median(terrain), "ms"});
      sink({prefix + ".selection", median(shadow_selection), "ms"});
      sink({prefix + ".triangles", double(globe.last_stats().shadow_triangles), "count"});
      sink({prefix + ".casters", double(globe.last_stats().shadow_casters), "count"});
    }
  }
  {
    // The descent: tiles streamed as a viewer would, after the pass's
    // programs for the flight were linked and compiled beforehand by
    // AtmospherePass::link_programs (ProgramScope::flight) from the first
    // frame's view, in a shared context on a second thread as an engine
    // would while it loads (`globe.descent.link_programs`, s).
    atmos::Globe globe(atmosphere, atmos::load_surface("earth"), pass, atmos::GlobeSettings{});
    const double first = 2.5 * atmosphere.bottom_radius_m, last = 2.0;
    const int frames = 40;
    {
      const auto start = std::chrono::steady_clock::now();
      std::unique_ptr<atmos::GlContext> linker_context = context.create_shared();
      std::exception_ptr linker_error;
      std::thread linker([&, input = frame.input(globe, globe_view(globe, atmosphere, first, width, height))] {
        try {
          linker_context->make_current();
          pass.link_programs(input, atmos::ProgramScope::flight);
        } catch (...) {
          linker_error = std::current_exception();
        }
        linker_context.reset();
      });
      linker.join();
      if (linker_error) std::rethrow_exception(linker_error);
      sink({"globe.descent.link_programs", seconds_since(start), "s"});
    }
    std::vector<double> times;
    for (int f = 0; f < frames; ++f) {
      const double altitude = std::exp(std::log(first) + (std::log(last) - std::log(first)) * f / (frames - 1));
      double terrain_ms = 0.0;
      times.push_back(frame(globe, globe_view(globe, atmosphere, altitude, width, height), terrain_ms));
    }
    // The first frame of a new globe includes the driver's compilation of
    // its programs at their first draw (a one-off, reported apart); the
    // ratio is over the frames of the flight.
    sink({"globe.descent.first", times.front(), "ms"});
    times.erase(times.begin());
    const double longest = *std::max_element(times.begin(), times.end());
    sink({"globe.descent.median", median(times), "ms"});
    sink({"globe.descent.max", longest, "ms"});
    sink({"globe.descent.max_over_median", longest / median(times), "ratio"});
  }
}

void time_water(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, int width, int height,
                const FigureSink& sink) {
  atmos::AtmospherePass pass(atmosphere, tables, atmos::PlanetFrame{});
  EngineFrame frame(pass, width, height);
  // The sea (atmos::Ocean) over the Pacific at 0°, 150° W, drawn after the
  // terrain: the frame with it, the sea's own draw, and the frame without
  // it, from 2 m, 1 km and 400 km above the sea level.
  atmos::GlobeSettings settings;
  settings.complete_every_frame = true;
  const atmos::PlanetSurface surface = atmos::load_surface("earth");
  atmos::Globe globe(atmosphere, surface, pass, settings);
  atmos::Ocean ocean(atmosphere, surface, pass);
  const std::pair<const char*, double> altitudes[] = {{"2m", 2.0}, {"1km", 1e3}, {"400km", 400e3}};
  for (const auto& [name, altitude] : altitudes) {
    const atmos::GlobeView view =
        globe_view(globe, atmosphere, altitude, width, height, 0.0, -150.0, ocean.sea_level_m());
    double terrain_ms = 0.0, sea_ms = 0.0;
    frame(globe, view, terrain_ms, &ocean, &sea_ms);  // generates the tiles, compiles the programs
    std::vector<double> with_sea, without_sea, sea;
    for (int i = 0; i < 3; ++i) {
      without_sea.push_back(frame(globe, view, terrain_ms));
      with_sea.push_back(frame(globe, view, terrain_ms, &ocean, &sea_ms));
      sea.push_back(sea_ms);
    }
    const std::string prefix = std::string("water.") + name;
    sink({prefix + ".frame", median(with_sea), "ms"});
    sink({prefix + ".sea", median(sea), "ms"});
    sink({prefix + ".frame_without_sea", median(without_sea), "ms"});
    sink({prefix + ".overhead", median(with_sea) / median(without_sea) - 1.0, "ratio"});
  }
}

void time_post(atmos::Renderer& renderer, const atmos::Camera& camera, const FigureSink& sink) {
  const int w = camera.width, h = camera.height;
  const atmos::Image hdr = renderer.render(camera, atmos::direction_from_azimuth_elevation(180.0, 12.0));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, 1, GL_RGBA32F, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  glTextureSubImage2D(texture, 0, 0, 0, w, h, GL_RGB, GL_FLOAT, hdr.rgb.data());
  std::vector<double> bloom, exposure, tone_map;
  {
    atmos::PostProcess post;
    atmos::PostSettings settings;
    settings.tone_mapping = atmos::ToneMapping::filmic;
    settings.bloom.strength = 0.05;
    settings.auto_exposure.enabled = true;
    atmos::PostInput input;
    input.colour = texture;
    input.width = w;
    input.height = h;
    input.dt_s = 1.0 / 60.0;
    input.timed = true;
    // The warm-up frame also starts the eye adaptation: in the timed frames
    // the bloom's bright pass does the exposure's reduction (post.bloom
    // includes it, post.exposure is the adaptation alone; docs/post.md).
    post.process(input, settings);
    for (int i = 0; i < 5; ++i) {
      post.process(input, settings);
      bloom.push_back(post.last_timings().bloom_ms);
      exposure.push_back(post.last_timings().exposure_ms);
      tone_map.push_back(post.last_timings().tone_map_ms);
    }
  }
  glDeleteTextures(1, &texture);
  sink({"post.bloom" + size_suffix(w, h), median(bloom), "ms"});
  sink({"post.exposure" + size_suffix(w, h), median(exposure), "ms"});
  sink({"post.tonemap" + size_suffix(w, h), median(tone_map), "ms"});
}

void run_all(const atmos::Atmosphere& atmosphere, const atmos::PrecomputeOptions& options, int width, int height,
             const FigureSink& sink) {
  const atmos::Tables tables = time_precomputation(atmosphere, options, sink);
  atmos::Atmosphere spectral_atmosphere;
  const atmos::Tables spectral_tables = time_spectral_precomputation(atmosphere, options, spectral_atmosphere, sink);

  // The context outlives the renderers (declared first, destroyed last).
  const std::unique_ptr<atmos::GlContext> context = atmos::GlContext::create_headless();
  atmos::Renderer renderer(atmosphere, tables);
  const atmos::Camera camera = frame_camera(atmosphere, width, height);
  time_frames(renderer, camera, atmos::direction_from_azimuth_elevation(150.0, 20.0), 5, "render", sink);
  // A total eclipse seen from the centre of the shadow: the sky-view pass
  // integrates single scattering along every view ray, eclipsed node by node.
  const glm::dvec3 eclipse_sun = atmos::direction_from_azimuth_elevation(150.0, 40.0);
  renderer.set_moons({atmos::moon_in_sky(camera.position, eclipse_sun, 0.27 * M_PI / 180.0)});
  time_frames(renderer, camera, eclipse_sun, 3, "render.eclipse", sink);
  renderer.set_moons({});
  // Twilight with the spectral tables: the sky-view pass integrates the low
  // sun's single scattering at all 15 wavelengths.
  atmos::Renderer spectral_renderer(spectral_atmosphere, spectral_tables);
  time_frames(spectral_renderer, camera, atmos::direction_from_azimuth_elevation(150.0, -3.0), 3,
              "render.spectral15.twilight", sink);
  time_plugin(atmosphere, tables, width, height, sink);
  time_instant(atmosphere, width, height, sink);
  time_ground_albedo(atmosphere, options, sink);
  time_post(renderer, camera, sink);
  {
    // The globe and its descent in a context of their own, as an engine runs
    // the pass: with the Renderer above in the same context, the programs
    // that the descent's preparation compiles on another thread
    // (AtmospherePass::link_programs) were seen to compile again at their
    // first frame (docs/plugin.md, Compiling ahead of a flight).
    const std::unique_ptr<atmos::GlContext> globe_context = atmos::GlContext::create_headless();
    time_globe(*globe_context, atmosphere, tables, width, height, sink);
  }
  context->make_current();
  time_water(atmosphere, tables, width, height, sink);
}

}  // namespace atmos_bench
