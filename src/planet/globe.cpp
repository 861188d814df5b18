// The terrain globe (include/atmos/globe.hpp): tile meshes with morph
// targets and skirts, their GPU cache, and the drawing.
#include "atmos/globe.hpp"

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "data/embedded_files.hpp"
#include "planet/cube_sphere.hpp"
#include "planet/globe_mesh.hpp"
#include "planet/surface.hpp"
#include "planet/tile_selection.hpp"

namespace atmos {

namespace {

using planet::TileKey;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

const char* shader_text(const char* path) {
  const char* text = data::embedded_file(path);
  if (text == nullptr) throw Error(std::string("globe: shader source ") + path + " is not embedded");
  return text;
}

GLuint compile(GLenum stage, const std::string& source, const char* name) {
  const GLuint shader = glCreateShader(stage);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error(std::string("globe: the ") + name + " shader does not compile: " + log.c_str());
  }
  return shader;
}

GLuint link(const std::string& vertex, const std::string& fragment) {
  const GLuint vs = compile(GL_VERTEX_SHADER, vertex, "vertex");
  GLuint fs = 0;
  try {
    fs = compile(GL_FRAGMENT_SHADER, fragment, "fragment");
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error(std::string("globe: the shaders do not link: ") + log.c_str());
  }
  return program;
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

// A tile resident on the GPU.
struct Resident {
  GLuint buffer = 0;
  glm::dvec3 origin{0.0};  // planet-centred m
  double min_height_m = 0.0, max_height_m = 0.0;
  int level = 0;
  long long last_drawn = -1;  // frame number
};

}  // namespace

struct Globe::Impl {
  const AtmospherePass* pass = nullptr;
  GlobeSettings settings;
  planet::Surface surface;
  planet::MeshBuilder builder;
  GLuint program = 0;
  GLuint vertex_array = 0;
  GLuint index_buffer = 0;
  GLint u_origin = -1, u_morph = -1, u_clip = -1, u_camera = -1, u_sun = -1, u_light = -1;
  std::map<std::uint64_t, Resident> resident;
  std::size_t resident_bytes = 0;
  long long frame = 0;
  GlobeStats stats;

  Impl(const Atmosphere& a, const PlanetSurface& s, const AtmospherePass& p, const GlobeSettings& g)
      : pass(&p),
        settings(g),
        surface(s, a.bottom_radius_m),
        builder(surface, a.bottom_radius_m) {}

  ~Impl() {
    for (auto& [key, tile] : resident) glDeleteBuffers(1, &tile.buffer);
    if (index_buffer != 0) glDeleteBuffers(1, &index_buffer);
    if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
    if (program != 0) glDeleteProgram(program);
  }

  void upload(const TileKey& key, const planet::TileMesh& mesh) {
    Resident r;
    glCreateBuffers(1, &r.buffer);
    const std::size_t bytes = mesh.vertices.size() * sizeof(planet::TileVertex);
    glNamedBufferStorage(r.buffer, GLsizeiptr(bytes), mesh.vertices.data(), 0);
    r.origin = mesh.origin;
    r.min_height_m = mesh.min_height_m;
    r.max_height_m = mesh.max_height_m;
    r.level = key.level;
    resident[key.packed()] = r;
    resident_bytes += bytes;
  }

  // Evicts the least recently drawn tiles above the memory cap, never the
  // six roots nor a tile of the current frame.
  void evict() {
    const std::size_t tile_bytes = builder.vertex_count() * sizeof(planet::TileVertex);
    if (resident_bytes <= settings.memory_cap_bytes) return;
    std::vector<std::pair<long long, std::uint64_t>> candidates;
    for (const auto& [packed, tile] : resident)
      if (tile.last_drawn < frame && tile.level > 0) candidates.emplace_back(tile.last_drawn, packed);
    std::sort(candidates.begin(), candidates.end());
    for (const auto& [last, packed] : candidates) {
      if (resident_bytes <= settings.memory_cap_bytes) break;
      glDeleteBuffers(1, &resident[packed].buffer);
      resident.erase(packed);
      resident_bytes -= tile_bytes;
    }
  }
};

Globe::Globe(const Atmosphere& atmosphere, const PlanetSurface& surface, const AtmospherePass& pass,
             const GlobeSettings& settings) {
  if (epoxy_gl_version() < 45) throw Error("globe: needs a current OpenGL 4.5 core context");
  if (surface.sea_level_m &&
      !(std::isfinite(*surface.sea_level_m) && *surface.sea_level_m > -atmosphere.bottom_radius_m &&
        *surface.sea_level_m < atmosphere.top_radius_m - atmosphere.bottom_radius_m))
    throw Error("globe: the sea level " + std::to_string(*surface.sea_level_m) +
                " m lies outside the atmosphere (below the planet's centre or above its top, " +
                std::to_string(atmosphere.top_radius_m - atmosphere.bottom_radius_m) + " m)");
  if (!(settings.max_screen_error_px > 0.0) || !std::isfinite(settings.max_screen_error_px))
    throw Error("globe settings: max_screen_error_px must be a positive number of pixels");
  if (settings.max_tiles_per_frame < 1) throw Error("globe settings: max_tiles_per_frame must be at least 1");
  if (settings.first_unit < 0) throw Error("globe settings: first_unit must be a texture unit (>= 0)");
  impl_ = std::make_unique<Impl>(atmosphere, surface, pass, settings);
  Impl& p = *impl_;
  // The pass's tables must reach the lowest ground (as lowest_surface_height_m
  // estimates it): below their bottom the light and the aerial perspective
  // would be clamped to it.
  const double lowest = p.surface.estimated_lowest_m();
  const double lowest_radius = atmosphere.bottom_radius_m + lowest;
  if (pass.bottom_radius_m() > lowest_radius + 1.0)
    throw Error("globe: the ground goes down to " + std::to_string(lowest) +
                " m, below the bottom of the pass's atmosphere (" +
                std::to_string(pass.bottom_radius_m() - atmosphere.bottom_radius_m) +
                " m): build the pass from extend_below_datum(atmosphere, surface)");
  if (settings.memory_cap_bytes < 6 * p.builder.vertex_count() * sizeof(planet::TileVertex))
    throw Error("globe settings: memory_cap_bytes " + std::to_string(settings.memory_cap_bytes) +
                " holds less than the six root tiles");

  const std::string version = "#version 450 core\n";
  p.program = link(version + pass.glsl_library(settings.first_unit) + "\n" + shader_text("src/planet/globe.vert.glsl"),
                   version + shader_text("src/planet/globe.frag.glsl"));
  p.u_origin = glGetUniformLocation(p.program, "origin_from_camera");
  p.u_morph = glGetUniformLocation(p.program, "morph_range");
  p.u_clip = glGetUniformLocation(p.program, "clip_from_offset");
  p.u_camera = glGetUniformLocation(p.program, "camera_planet");
  p.u_sun = glGetUniformLocation(p.program, "sun_direction");
  p.u_light = glGetUniformLocation(p.program, "light_scale");

  // One vertex layout and one index buffer serve every tile.
  glCreateVertexArrays(1, &p.vertex_array);
  const auto attribute = [&](GLuint index, std::size_t offset) {
    glEnableVertexArrayAttrib(p.vertex_array, index);
    glVertexArrayAttribFormat(p.vertex_array, index, 3, GL_FLOAT, GL_FALSE, GLuint(offset));
    glVertexArrayAttribBinding(p.vertex_array, index, 0);
  };
  attribute(0, offsetof(planet::TileVertex, position));
  attribute(1, offsetof(planet::TileVertex, morph_offset));
  attribute(2, offsetof(planet::TileVertex, normal));
  attribute(3, offsetof(planet::TileVertex, parent_normal));
  attribute(4, offsetof(planet::TileVertex, albedo));
  const std::vector<std::uint32_t>& indices = p.builder.indices();
  glCreateBuffers(1, &p.index_buffer);
  glNamedBufferStorage(p.index_buffer, GLsizeiptr(indices.size() * sizeof(std::uint32_t)), indices.data(), 0);
  glVertexArrayElementBuffer(p.vertex_array, p.index_buffer);

  for (int face = 0; face < 6; ++face) {
    const TileKey root{face, 0, 0, 0};
    p.upload(root, p.builder.build(root));
  }
}

Globe::~Globe() = default;

void Globe::draw(const GlobeView& view) {
  Impl& p = *impl_;
  const PlanetFrame& frame = p.pass->frame();
  // --- Validation, before any state change. ---
  if (view.width < 1 || view.height < 1) throw Error("globe view: empty viewport");
  if (!finite(view.view) || !finite(view.projection)) throw Error("globe view: non-finite view or projection matrix");
  if (!std::isfinite(glm::determinant(view.view)) || std::abs(glm::determinant(view.view)) < 1e-12)
    throw Error("globe view: singular view matrix");
  if (!(std::abs(view.projection[1][1]) > 0.0)) throw Error("globe view: degenerate projection");
  const double sun_length = glm::length(view.sun_direction);
  if (!(sun_length > 0.0) || !std::isfinite(sun_length)) throw Error("globe view: zero or non-finite sun direction");
  if (!(view.nits_per_unit > 0.0) || !std::isfinite(view.nits_per_unit))
    throw Error("globe view: nits_per_unit must be positive");
  if (!(view.sun_illuminance_lux >= 0.0) || !std::isfinite(view.sun_illuminance_lux))
    throw Error("globe view: sun_illuminance_lux must be >= 0");

  // The camera in planet-centred metres, and the transform of
  // camera-relative metres to clip space: projection x the view's rotation
  // x engine units per metre (the view is rigid: view x world = R (world - eye)).
  const glm::dmat4 world_from_view = glm::inverse(view.view);
  const glm::dvec3 eye_world(world_from_view[3]);
  const glm::dvec3 camera = (eye_world - frame.centre) / frame.units_per_metre;
  glm::dmat4 rotation = view.view;
  rotation[3] = glm::dvec4(0.0, 0.0, 0.0, 1.0);
  const glm::dmat4 clip_from_offset =
      view.projection * rotation * glm::scale(glm::dmat4(1.0), glm::dvec3(frame.units_per_metre));
  const glm::dvec3 sun = view.sun_direction / sun_length;

  // --- Selection. ---
  const auto t0 = Clock::now();
  planet::LodCamera lod_camera;
  lod_camera.position = camera;
  lod_camera.view_projection = view.projection * view.view * glm::translate(glm::dmat4(1.0), frame.centre) *
                               glm::scale(glm::dmat4(1.0), glm::dvec3(frame.units_per_metre));
  lod_camera.viewport_height_px = double(view.height);
  lod_camera.tan_half_fov_y = 1.0 / std::abs(view.projection[1][1]);
  const planet::TileHeightRange known_range = [&](const TileKey& key, double& lo, double& hi) {
    const auto it = p.resident.find(key.packed());
    if (it == p.resident.end()) return false;
    // The range must bound the surface of every finer level too
    // (tile_selection.hpp): the tile's vertices, widened by its mesh error.
    const double error = p.builder.bounds().error_m(p.builder.spacing_m(key.level));
    lo = it->second.min_height_m - error;
    hi = it->second.max_height_m + error;
    return true;
  };
  const planet::Selection selection =
      planet::select_tiles(lod_camera, p.builder.lod_settings(p.settings.max_screen_error_px), p.builder.bounds(),
                           known_range);
  GlobeStats stats;
  stats.selection_ms = ms_since(t0);
  stats.nodes_visited = selection.nodes_visited;

  // --- New tiles: generated in parallel (CPU), uploaded here. ---
  const auto t1 = Clock::now();
  std::vector<TileKey> missing;
  for (const planet::SelectedTile& s : selection.tiles)
    if (p.resident.find(s.key.packed()) == p.resident.end()) missing.push_back(s.key);
  // Coarse levels first: they stand in for the others.
  std::stable_sort(missing.begin(), missing.end(),
                   [](const TileKey& a, const TileKey& b) { return a.level < b.level; });
  std::vector<TileKey> batch = missing;
  if (!p.settings.complete_every_frame && batch.size() > size_t(p.settings.max_tiles_per_frame))
    batch.resize(size_t(p.settings.max_tiles_per_frame));
  // The memory cap: the resident tiles this frame draws (the selected ones,
  // and the nearest resident ancestors of the others) stay; new tiles fit in
  // what remains. Tiles that do not fit stay pending, their ancestors drawn
  // instead: the view is coarser, the cap holds.
  {
    std::set<std::uint64_t> kept;
    for (const planet::SelectedTile& s : selection.tiles) {
      TileKey key = s.key;
      while (p.resident.find(key.packed()) == p.resident.end()) key = planet::parent(key);
      kept.insert(key.packed());
    }
    const std::size_t tile_bytes = p.builder.vertex_count() * sizeof(planet::TileVertex);
    const std::size_t kept_bytes = (kept.size() + 6) * tile_bytes;  // the roots always stay
    const std::size_t room =
        p.settings.memory_cap_bytes > kept_bytes ? (p.settings.memory_cap_bytes - kept_bytes) / tile_bytes : 0;
    if (batch.size() > room) batch.resize(room);
  }
  std::vector<planet::TileMesh> meshes(batch.size());
  tbb::parallel_for(size_t(0), batch.size(), [&](size_t i) { meshes[i] = p.builder.build(batch[i]); });
  for (size_t i = 0; i < batch.size(); ++i) p.upload(batch[i], meshes[i]);
  stats.tiles_generated = int(batch.size());
  stats.tiles_pending = int(missing.size() - batch.size());
  stats.generation_ms = ms_since(t1);

  // --- Draw: each selected tile, or its nearest resident ancestor. ---
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  glViewport(0, 0, view.width, view.height);
  glUseProgram(p.program);
  glBindVertexArray(p.vertex_array);
  p.pass->bind_textures(p.settings.first_unit);
  const glm::mat4 clip_f(clip_from_offset);
  glUniformMatrix4fv(p.u_clip, 1, GL_FALSE, glm::value_ptr(clip_f));
  glUniform3f(p.u_camera, float(camera.x), float(camera.y), float(camera.z));
  glUniform3f(p.u_sun, float(sun.x), float(sun.y), float(sun.z));
  const double lux_scale = view.sun_illuminance_lux > 0.0 ? view.sun_illuminance_lux / p.pass->sun_illuminance_lux() : 1.0;
  glUniform1f(p.u_light, float(lux_scale / view.nits_per_unit));

  ++p.frame;
  // What to draw: each selected tile (its drawn quadrants), or for a tile
  // not resident yet its nearest resident ancestor, whole and unmorphed; a
  // tile met twice draws the union of its quadrants.
  struct Draw {
    TileKey key;
    unsigned quadrants = 0u;
    double morph_start = INFINITY, morph_end = INFINITY;
  };
  std::vector<Draw> draws;
  std::map<std::uint64_t, size_t> draw_of;
  for (const planet::SelectedTile& s : selection.tiles) {
    Draw d{s.key, s.quadrants, s.morph_start_m, s.morph_end_m};
    while (p.resident.find(d.key.packed()) == p.resident.end()) {
      d.key = planet::parent(d.key);
      d.quadrants = 0xFu;
      d.morph_start = d.morph_end = INFINITY;
    }
    const auto [it, added] = draw_of.emplace(d.key.packed(), draws.size());
    if (added)
      draws.push_back(d);
    else
      draws[it->second].quadrants |= d.quadrants;
  }
  const GLsizei quadrant_count = GLsizei(p.builder.quadrant_index_count());
  const GLsizei tile_count = GLsizei(p.builder.tile_index_count());
  long long triangles = 0;
  for (const Draw& d : draws) {
    Resident& tile = p.resident.find(d.key.packed())->second;
    tile.last_drawn = p.frame;
    const glm::dvec3 origin = tile.origin - camera;
    glUniform3f(p.u_origin, float(origin.x), float(origin.y), float(origin.z));
    glUniform2f(p.u_morph, std::isfinite(d.morph_start) ? float(d.morph_start) : 3.0e38f,
                std::isfinite(d.morph_end) ? float(d.morph_end) : 3.0e38f);
    glVertexArrayVertexBuffer(p.vertex_array, 0, tile.buffer, 0, GLsizei(sizeof(planet::TileVertex)));
    if (d.quadrants == 0xFu) {
      const std::size_t offset = p.builder.tile_index_offset() * sizeof(std::uint32_t);
      glDrawElements(GL_TRIANGLES, tile_count, GL_UNSIGNED_INT, reinterpret_cast<const void*>(offset));
      triangles += tile_count / 3;
      continue;
    }
    for (int q = 0; q < 4; ++q)
      if (d.quadrants & (1u << q)) {
        const std::size_t offset = std::size_t(q) * std::size_t(quadrant_count) * sizeof(std::uint32_t);
        glDrawElements(GL_TRIANGLES, quadrant_count, GL_UNSIGNED_INT, reinterpret_cast<const void*>(offset));
        triangles += quadrant_count / 3;
      }
  }
  stats.tiles_drawn = int(draws.size());
  stats.triangles = triangles;
  p.evict();
  stats.resident_bytes = p.resident_bytes;
  p.stats = stats;
}

double Globe::height_m(const glm::dvec3& position) const {
  const PlanetFrame& frame = impl_->pass->frame();
  const glm::dvec3 r = (position - frame.centre) / frame.units_per_metre;
  const double length = glm::length(r);
  if (!std::isfinite(length)) throw Error("globe: height_m of a non-finite position");
  if (length == 0.0) return impl_->builder.surface_height_m(glm::dvec3(0.0, 0.0, 1.0));
  return impl_->builder.surface_height_m(r / length);
}

double Globe::min_height_m() const { return impl_->builder.min_surface_height_m(); }
double Globe::max_height_m() const { return impl_->builder.max_surface_height_m(); }
const GlobeStats& Globe::last_stats() const { return impl_->stats; }

double lowest_surface_height_m(const PlanetSurface& surface, double datum_radius_m) {
  return planet::lowest_height_m(surface, datum_radius_m);
}

Atmosphere extend_below_datum(const Atmosphere& atmosphere, const PlanetSurface& surface) {
  const double depth = -lowest_surface_height_m(surface, atmosphere.bottom_radius_m);
  if (!(depth > 0.0)) return atmosphere;
  if (!(depth < 0.5 * atmosphere.bottom_radius_m))
    throw Error("extend_below_datum: the surface goes " + std::to_string(depth) +
                " m below the datum, more than half the planet's radius");
  Atmosphere deeper = atmosphere;
  deeper.bottom_radius_m -= depth;
  for (Constituent& c : deeper.constituents) {
    DensityProfile& d = c.density;
    if (d.kind == DensityProfile::Kind::exponential) {
      const double factor = std::exp(depth / d.scale_height_m);
      c.scattering = c.scattering.scaled(factor);
      c.absorption = c.absorption.scaled(factor);
    } else {
      std::vector<std::pair<double, double>> knots;
      // A profile that reaches the datum keeps its lowest density below it.
      if (!d.knots.empty() && d.knots.front().first <= 0.0 && d.knots.front().first + depth > 0.0)
        knots.emplace_back(0.0, d.knots.front().second);
      for (const auto& [altitude, density] : d.knots) knots.emplace_back(altitude + depth, density);
      d.knots = knots;
    }
  }
  deeper.validate();
  return deeper;
}

glm::dmat4 reversed_z_projection(double fov_y_rad, double aspect, double near) {
  if (!(fov_y_rad > 0.0 && fov_y_rad < 3.14159) || !(aspect > 0.0) || !(near > 0.0) || !std::isfinite(aspect) ||
      !std::isfinite(near))
    throw Error("reversed_z_projection: needs 0 < fov_y < pi, aspect > 0 and near > 0");
  const double f = 1.0 / std::tan(0.5 * fov_y_rad);
  glm::dmat4 p(0.0);
  p[0][0] = f / aspect;
  p[1][1] = f;
  p[3][2] = near;  // z_clip = near: depth = near / distance along the view axis
  p[2][3] = -1.0;  // w_clip = -z_view
  return p;
}

}  // namespace atmos
