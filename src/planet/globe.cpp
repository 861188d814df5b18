// The terrain globe (include/atmos/globe.hpp): tile meshes with morph
// targets and skirts, their GPU cache, the sun's shadow maps and the
// drawing.
#include "atmos/globe.hpp"

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "planet/gl_program.hpp"
#include "planet/cube_sphere.hpp"
#include "planet/globe_internal.hpp"
#include "planet/globe_mesh.hpp"
#include "planet/globe_shadows.hpp"
#include "planet/surface.hpp"
#include "planet/tile_selection.hpp"
#include "planet/tile_streamer.hpp"

namespace atmos {

namespace {

using planet::TileKey;
using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// set_globe_morph (globe_internal.hpp).
std::atomic<bool> morph_enabled{true};

// A tile resident on the GPU.
struct Resident {
  GLuint buffer = 0;
  glm::dvec3 origin{0.0};  // planet-centred m
  double min_height_m = 0.0, max_height_m = 0.0;
  // A sphere holding every vertex, skirts and morph targets included
  // (planet-centred m): the shadow casters' culling.
  glm::dvec3 bound_centre{0.0};
  double bound_radius_m = 0.0;
  int level = 0;
  long long last_drawn = -1;  // frame number
};

// The uniforms of a program drawing tiles (-1: not in this variant).
struct TileProgram {
  GLuint id = 0;
  GLint origin = -1, morph = -1, clip = -1, camera = -1, sun = -1, light = -1;
  // The shadowed variants' cascades (globe.frag.glsl).
  GLint cascade_count = -1, light_clip = -1, far = -1, blend = -1, texel = -1, depth_per_m = -1, forward = -1,
        maps = -1;
  // The eclipse variants' moons.
  GLint moon_count = -1, moon_spheres = -1;
  void locate() {
    origin = glGetUniformLocation(id, "origin_from_camera");
    morph = glGetUniformLocation(id, "morph_range");
    clip = glGetUniformLocation(id, "clip_from_offset");
    camera = glGetUniformLocation(id, "camera_planet");
    sun = glGetUniformLocation(id, "sun_direction");
    light = glGetUniformLocation(id, "light_scale");
    cascade_count = glGetUniformLocation(id, "cascade_count");
    light_clip = glGetUniformLocation(id, "light_clip_from_offset");
    far = glGetUniformLocation(id, "cascade_far");
    blend = glGetUniformLocation(id, "cascade_blend");
    texel = glGetUniformLocation(id, "cascade_texel");
    depth_per_m = glGetUniformLocation(id, "cascade_depth_per_m");
    forward = glGetUniformLocation(id, "view_forward");
    maps = glGetUniformLocation(id, "shadow_maps");
    moon_count = glGetUniformLocation(id, "moon_count");
    moon_spheres = glGetUniformLocation(id, "moon_spheres");
  }
};

// One tile to draw: a selected tile, or for a tile not resident yet its
// nearest resident ancestor, whole and unmorphed; a tile met twice draws
// the union of its quadrants.
struct TileDraw {
  TileKey key;
  unsigned quadrants = 0u;
  double morph_start = INFINITY, morph_end = INFINITY;
};

// The sun's cascaded shadow maps (globe_shadows.hpp): one depth texture
// array, a 2D view of each layer for the engine plugin, a framebuffer per
// layer, the depth-only program and the lit program that reads them.
struct Shadows {
  int count = 0, size = 0;
  double distance_m = 0.0;
  GLuint maps = 0;
  std::array<GLuint, planet::kMaxShadowCascades> views{}, framebuffers{};
  GLuint sampler = 0;
  TileProgram depth;
  TileProgram lit;
  // The last draw's view and cascades (none: no shadows this frame).
  planet::ShadowView view;
  planet::ShadowLight light;
  std::vector<planet::ShadowCascade> cascades;

  ~Shadows() {
    for (GLuint& f : framebuffers)
      if (f != 0) glDeleteFramebuffers(1, &f);
    for (GLuint& v : views)
      if (v != 0) glDeleteTextures(1, &v);
    if (maps != 0) glDeleteTextures(1, &maps);
    if (sampler != 0) glDeleteSamplers(1, &sampler);
    if (depth.id != 0) glDeleteProgram(depth.id);
    if (lit.id != 0) glDeleteProgram(lit.id);
  }
};

// Programs that light tiles: the library of the pass, and the variant's
// switches (globe.vert.glsl, globe.frag.glsl); the fragment shader has the
// library too when it evaluates the eclipse.
TileProgram lit_program(const AtmospherePass& pass, int first_unit, bool shadows, bool eclipse) {
  std::string head = "#version 450 core\n";
  if (shadows) head += "#define ATMOS_GLOBE_SHADOWS 1\n";
  if (eclipse) head += "#define ATMOS_GLOBE_ECLIPSE 1\n";
  const std::string library = pass.glsl_library(first_unit) + "\n";
  TileProgram program;
  program.id = planet::link_program(
      "globe", head + library + planet::shader_text("globe", "src/planet/globe.vert.glsl"),
      head + (eclipse ? library : std::string()) + planet::shader_text("globe", "src/planet/globe.frag.glsl"));
  program.locate();
  if (shadows) glProgramUniform1i(program.id, program.maps, first_unit + 5);
  return program;
}

// The tiles always resident: levels 0 and 1, the coarsest stand-ins, whose
// chords lie within a few kilometres of the datum sphere (a level-0 tile's
// 16 quads span 5.6 degrees each, and the middle of their triangles sags
// about 15 km below the sphere; a level-1 tile's, 4 km).
constexpr int kPermanentLevel = 1;
constexpr int kPermanentTiles = 6 * (1 + 4);

// The nearest view depth of any point of a tile's volume between the
// radii: its nearest distance times the cosine of the frustum's widest
// angle from the view axis (a point at distance d inside the frustum is at
// least d / sqrt(1 + s^2) deep, s the largest slope of a corner ray).
double nearest_view_depth_m(const glm::dvec3& camera, const TileKey& key, double min_radius_m, double max_radius_m,
                            double widest_slope) {
  return planet::nearest_distance_m(camera, key, min_radius_m, max_radius_m) /
         std::sqrt(1.0 + widest_slope * widest_slope);
}

}  // namespace

namespace planet {
void set_globe_morph(bool enabled) { morph_enabled.store(enabled, std::memory_order_relaxed); }
}  // namespace planet

struct Globe::Impl {
  const AtmospherePass* pass = nullptr;
  GlobeSettings settings;
  PlanetSurface description;  // what `surface` was opened from (rebind's checks)
  double datum_radius_m = 0.0;
  planet::Surface surface;
  planet::MeshBuilder builder;
  TileProgram program;
  // The eclipse's variants, [0] unshadowed and [1] shadowed, linked at the
  // first draw with moons that eclipse (id 0 until then).
  std::array<TileProgram, 2> eclipse_programs{};
  // The lit programs of a pass the globe is to be rebound to, linked
  // beforehand (link_rebind_programs; id 0 when none), and that pass's
  // library (AtmospherePass::glsl_library), which they were linked with.
  std::string prelinked_for;
  TileProgram prelinked_lit, prelinked_shadowed;
  // The library the lit programs (and the eclipse's) were linked with: it
  // depends on the atmosphere's structure alone, and a pass with the same
  // library is drawn with the same programs.
  std::string linked_for;
  void drop_prelinked() {
    if (prelinked_lit.id != 0) glDeleteProgram(prelinked_lit.id);
    if (prelinked_shadowed.id != 0) glDeleteProgram(prelinked_shadowed.id);
    prelinked_lit = prelinked_shadowed = TileProgram{};
    prelinked_for.clear();
  }
  // The atmosphere's top (m) and the sun's angular radius (rad): which
  // moons may eclipse.
  double top_radius_m = 0.0, sun_angular_radius_rad = 0.0;
  GLuint vertex_array = 0;
  GLuint index_buffer = 0;
  std::unique_ptr<Shadows> shadows;  // none when GlobeSettings::shadow_cascades is 0
  std::map<std::uint64_t, Resident> resident;
  std::size_t resident_bytes = 0;
  long long frame = 0;
  GlobeStats stats;
  // The background builder of tiles, without complete_every_frame (none
  // with it). After the builder it reads, and stopped first.
  std::unique_ptr<planet::TileStreamer> streamer;

  Impl(const Atmosphere& a, const PlanetSurface& s, const AtmospherePass& p, const GlobeSettings& g)
      : pass(&p),
        settings(g),
        description(s),
        datum_radius_m(a.bottom_radius_m),
        surface(s, a.bottom_radius_m),
        builder(surface, a.bottom_radius_m) {}

  ~Impl() {
    streamer.reset();  // joins its thread, which reads builder and surface
    shadows.reset();
    for (auto& [key, tile] : resident) glDeleteBuffers(1, &tile.buffer);
    if (index_buffer != 0) glDeleteBuffers(1, &index_buffer);
    if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
    if (program.id != 0) glDeleteProgram(program.id);
    for (const TileProgram& e : eclipse_programs)
      if (e.id != 0) glDeleteProgram(e.id);
    drop_prelinked();
  }

  // The pass's tables must reach the lowest ground (as lowest_surface_height_m
  // estimates it): below their bottom the light and the aerial perspective
  // would be clamped to it. The estimate samples the elevation raster:
  // taken once, the surface being fixed.
  std::optional<double> lowest_m;
  void check_pass_reaches_ground(const AtmospherePass& with) {
    if (!lowest_m) lowest_m = surface.estimated_lowest_m();
    const double lowest = *lowest_m;
    if (with.bottom_radius_m() > datum_radius_m + lowest + 1.0)
      throw Error("globe: the ground goes down to " + std::to_string(lowest) +
                  " m, below the bottom of the pass's atmosphere (" +
                  std::to_string(with.bottom_radius_m() - datum_radius_m) +
                  " m): build the pass from extend_below_datum(atmosphere, surface)");
  }

  void upload(const TileKey& key, const planet::TileMesh& mesh) {
    Resident r;
    glCreateBuffers(1, &r.buffer);
    const std::size_t bytes = mesh.vertices.size() * sizeof(planet::TileVertex);
    glNamedBufferStorage(r.buffer, GLsizeiptr(bytes), mesh.vertices.data(), 0);
    r.origin = mesh.origin;
    r.min_height_m = mesh.min_height_m;
    r.max_height_m = mesh.max_height_m;
    glm::dvec3 lo(INFINITY), hi(-INFINITY);
    for (const planet::TileVertex& v : mesh.vertices) {
      const glm::dvec3 p(v.position[0], v.position[1], v.position[2]);
      const glm::dvec3 q = p + glm::dvec3(v.morph_offset[0], v.morph_offset[1], v.morph_offset[2]);
      lo = glm::min(lo, glm::min(p, q));
      hi = glm::max(hi, glm::max(p, q));
    }
    const glm::dvec3 middle = 0.5 * (lo + hi);
    double radius2 = 0.0;
    for (const planet::TileVertex& v : mesh.vertices) {
      const glm::dvec3 p(v.position[0], v.position[1], v.position[2]);
      const glm::dvec3 q = p + glm::dvec3(v.morph_offset[0], v.morph_offset[1], v.morph_offset[2]);
      radius2 = std::max({radius2, glm::dot(p - middle, p - middle), glm::dot(q - middle, q - middle)});
    }
    r.bound_centre = mesh.origin + middle;
    r.bound_radius_m = std::sqrt(radius2) * (1.0 + 1e-6) + 1e-3;
    r.level = key.level;
    resident[key.packed()] = r;
    resident_bytes += bytes;
  }

  // The tiles to draw for a selection: each selected tile, or its nearest
  // resident ancestor.
  std::vector<TileDraw> resolve(const planet::Selection& selection) const {
    std::vector<TileDraw> draws;
    std::map<std::uint64_t, size_t> draw_of;
    for (const planet::SelectedTile& s : selection.tiles) {
      TileDraw d{s.key, s.quadrants, s.morph_start_m, s.morph_end_m};
      while (resident.find(d.key.packed()) == resident.end()) {
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
    return draws;
  }

  // Draws tiles with the program `with` (its clip_from_offset set); returns the
  // triangles drawn.
  long long draw_tiles(const std::vector<TileDraw>& draws, const TileProgram& with, const glm::dvec3& camera) {
    const GLsizei quadrant_count = GLsizei(builder.quadrant_index_count());
    const GLsizei tile_count = GLsizei(builder.tile_index_count());
    long long triangles = 0;
    for (const TileDraw& d : draws) {
      Resident& tile = resident.find(d.key.packed())->second;
      tile.last_drawn = frame;
      const glm::dvec3 origin = tile.origin - camera;
      glUniform3f(with.origin, float(origin.x), float(origin.y), float(origin.z));
      const bool morph = morph_enabled.load(std::memory_order_relaxed);
      glUniform2f(with.morph, morph && std::isfinite(d.morph_start) ? float(d.morph_start) : 3.0e38f,
                  morph && std::isfinite(d.morph_end) ? float(d.morph_end) : 3.0e38f);
      glVertexArrayVertexBuffer(vertex_array, 0, tile.buffer, 0, GLsizei(sizeof(planet::TileVertex)));
      if (d.quadrants == 0xFu) {
        const std::size_t offset = builder.tile_index_offset() * sizeof(std::uint32_t);
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
    return triangles;
  }

  void create_shadows(const std::string& version);
  // The cascades of a view (none when shadows are off or out of reach),
  // into shadows->cascades; false when there are none.
  bool fit_cascades(const GlobeView& view, const glm::dmat4& rotation, const glm::dvec3& camera,
                    const glm::dvec3& sun, const std::vector<TileDraw>& draws);
  // Renders the cascades' depth from the sun, cascade i with the tiles of
  // casters[i] that may shadow the tiles the view draws (`receivers`).
  void render_shadow_maps(const std::vector<std::vector<TileDraw>>& casters, const std::vector<TileDraw>& receivers,
                          const glm::dvec3& camera, GlobeStats& out);

  std::size_t tile_bytes() const { return builder.vertex_count() * sizeof(planet::TileVertex); }

  // The resident tiles a frame keeps: those that selections draw (each
  // selected tile, or its nearest resident ancestor) and their resident
  // ancestors.
  std::set<std::uint64_t> kept_by(const std::vector<const planet::Selection*>& selections) const {
    std::set<std::uint64_t> kept;
    for (const planet::Selection* s : selections)
      for (const planet::SelectedTile& t : s->tiles) {
        TileKey key = t.key;
        while (resident.find(key.packed()) == resident.end()) key = planet::parent(key);
        for (;; key = planet::parent(key)) {
          if (resident.find(key.packed()) != resident.end() && !kept.insert(key.packed()).second) break;
          if (key.level == 0) break;
        }
      }
    return kept;
  }

  // The tiles selections need that are not resident, each once: the
  // selected tiles and their ancestors. An ancestor's heights bound its
  // descendants' more tightly than the planet's (the selection culls and
  // refines less: tile_selection.hpp), and it stands in for them while they
  // load.
  std::vector<TileKey> needed_by(const std::vector<const planet::Selection*>& selections) const {
    std::vector<TileKey> out;
    std::set<std::uint64_t> listed;
    for (const planet::Selection* s : selections)
      for (const planet::SelectedTile& t : s->tiles)
        for (TileKey key = t.key; resident.find(key.packed()) == resident.end(); key = planet::parent(key)) {
          if (!listed.insert(key.packed()).second) break;
          out.push_back(key);
        }
    return out;
  }

  // The selected tiles that are not resident, each once.
  int pending_in(const std::vector<const planet::Selection*>& selections) const {
    std::set<std::uint64_t> listed;
    for (const planet::Selection* s : selections)
      for (const planet::SelectedTile& t : s->tiles)
        if (resident.find(t.key.packed()) == resident.end()) listed.insert(t.key.packed());
    return int(listed.size());
  }

  // The memory cap: the resident tiles a frame keeps (kept_by) and the
  // permanent ones stay; this many new tiles fit in what remains. Tiles
  // beyond it stay pending, their ancestors drawn instead: the view is
  // coarser, the cap holds.
  std::size_t room_for(const std::set<std::uint64_t>& kept) const {
    const std::size_t kept_bytes = (kept.size() + std::size_t(kPermanentTiles)) * tile_bytes();
    return settings.memory_cap_bytes > kept_bytes ? (settings.memory_cap_bytes - kept_bytes) / tile_bytes() : 0;
  }

  // Evicts the least recently drawn tiles, never a permanent one nor a tile
  // of `kept`, until `incoming` new tiles (at most room_for(kept)) fit
  // under the memory cap: the cap holds at every upload, not only after
  // the draw.
  void make_room(std::size_t incoming, const std::set<std::uint64_t>& kept) {
    const std::size_t bytes = tile_bytes(), needed = incoming * bytes;
    if (resident_bytes + needed <= settings.memory_cap_bytes) return;
    std::vector<std::pair<long long, std::uint64_t>> candidates;
    for (const auto& [packed, tile] : resident)
      if (tile.level > kPermanentLevel && kept.count(packed) == 0) candidates.emplace_back(tile.last_drawn, packed);
    std::sort(candidates.begin(), candidates.end());
    for (const auto& [last, packed] : candidates) {
      if (resident_bytes + needed <= settings.memory_cap_bytes) break;
      glDeleteBuffers(1, &resident[packed].buffer);
      resident.erase(packed);
      resident_bytes -= bytes;
    }
  }

  // complete_every_frame: builds every tile the selections need that fits
  // under the cap, coarse levels first, in parallel (TBB), and uploads
  // them. Returns the selected tiles still pending (those beyond the cap).
  int complete(const std::vector<const planet::Selection*>& selections, GlobeStats& out) {
    std::vector<TileKey> batch = needed_by(selections);
    std::stable_sort(batch.begin(), batch.end(), [](const TileKey& a, const TileKey& b) { return a.level < b.level; });
    build(batch, kept_by(selections), out);
    return pending_in(selections);
  }

  // complete_every_frame, the view's tiles: built a generation at a time,
  // each missing selected tile's coarsest missing ancestor (or the tile),
  // and selected again after each generation. A missing tile inherits its
  // nearest resident ancestor's height range, at first the planet's
  // (tile_selection.hpp): a selection over that range keeps every tile
  // whose column from the deepest trench to the highest summit might be in
  // view, and refines near the camera as if the ground were at the trench.
  // Each generation's own heights bound its descendants tightly, so the
  // selection the frame ends with is the one it would make with every tile
  // resident, and only its tiles and their ancestors are built. Returns the
  // selected tiles still pending (beyond the memory cap). At most one
  // generation per level of the quadtree, and a few more: under a memory
  // cap that evicts what an earlier generation built, the selections could
  // otherwise ask for the same tiles again and again.
  int complete_by_generations(const std::function<planet::Selection()>& select, planet::Selection& selection,
                              GlobeStats& out) {
    for (int generations = 0; generations < 2 * planet::kMaxTileLevel; ++generations) {
      std::vector<TileKey> generation;
      std::set<std::uint64_t> listed;
      for (const planet::SelectedTile& t : selection.tiles) {
        if (resident.count(t.key.packed()) != 0) continue;
        TileKey key = t.key;
        while (key.level > 0 && resident.count(planet::parent(key).packed()) == 0) key = planet::parent(key);
        if (listed.insert(key.packed()).second) generation.push_back(key);
      }
      if (!build(generation, kept_by({&selection}), out)) break;
      selection = select();
    }
    return pending_in({&selection});
  }

  // Builds (in parallel) and uploads the tiles of `batch` that fit under
  // the memory cap beside `kept`; returns how many.
  std::size_t build(std::vector<TileKey> batch, const std::set<std::uint64_t>& kept, GlobeStats& out) {
    batch.resize(std::min(batch.size(), room_for(kept)));
    std::vector<planet::TileMesh> meshes(batch.size());
    tbb::parallel_for(size_t(0), batch.size(), [&](size_t i) { meshes[i] = builder.build(batch[i]); });
    make_room(batch.size(), kept);
    for (size_t i = 0; i < batch.size(); ++i) upload(batch[i], meshes[i]);
    out.tiles_generated += int(batch.size());
    return batch.size();
  }

  // Streaming: asks the worker for the tiles the selections need that fit
  // under the cap (coarse levels first, then the nearest to the camera),
  // and uploads at most max_tiles_per_frame of those it has finished.
  // Returns the selected tiles still pending.
  int stream(const std::vector<const planet::Selection*>& selections, const glm::dvec3& camera, GlobeStats& out) {
    const std::vector<TileKey> wanted = needed_by(selections);
    const std::set<std::uint64_t> kept = kept_by(selections);
    const std::size_t room = room_for(kept);
    const planet::ReliefBounds& bounds = builder.bounds();
    std::vector<planet::TileRequest> requests;
    requests.reserve(wanted.size());
    for (const TileKey& key : wanted)
      requests.push_back({key, planet::nearest_distance_m(camera, key, bounds.radius_m + bounds.min_height_m,
                                                          bounds.radius_m + bounds.max_height_m)});
    streamer->request(requests, room);
    std::vector<planet::ReadyTile> ready =
        streamer->take(std::min(room, std::size_t(settings.max_tiles_per_frame)));
    make_room(ready.size(), kept);
    for (const planet::ReadyTile& t : ready)
      if (resident.find(t.key.packed()) == resident.end()) {
        upload(t.key, t.mesh);
        ++out.tiles_generated;
      }
    const planet::TileStreamer::Counts counts = streamer->counts();
    out.tiles_queued = int(counts.queued);
    out.tiles_ready = int(counts.ready);
    return pending_in(selections);
  }
};

void Globe::Impl::create_shadows(const std::string& version) {
  auto s = std::make_unique<Shadows>();
  s->count = settings.shadow_cascades;
  s->size = settings.shadow_map_size;
  s->distance_m = settings.shadow_distance_m;
  GLint max_size = 0, max_units = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  glGetIntegerv(GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, &max_units);
  if (s->size > max_size)
    throw Error("globe settings: shadow_map_size " + std::to_string(s->size) +
                " exceeds the context's largest texture, " + std::to_string(max_size));
  if (settings.first_unit + 5 >= max_units)
    throw Error("globe settings: first_unit + 5 (the shadow maps) is beyond the context's " +
                std::to_string(max_units) + " texture units");
  glCreateTextures(GL_TEXTURE_2D_ARRAY, 1, &s->maps);
  glTextureStorage3D(s->maps, 1, GL_DEPTH_COMPONENT32F, s->size, s->size, s->count);
  for (int i = 0; i < s->count; ++i) {
    // A 2D view of layer i: what AtmospherePass reads (a GL_TEXTURE_2D).
    glGenTextures(1, &s->views[size_t(i)]);
    glTextureView(s->views[size_t(i)], GL_TEXTURE_2D, s->maps, GL_DEPTH_COMPONENT32F, 0, 1, GLuint(i), 1);
    glCreateFramebuffers(1, &s->framebuffers[size_t(i)]);
    const GLuint framebuffer = s->framebuffers[size_t(i)];
    glNamedFramebufferTextureLayer(framebuffer, GL_DEPTH_ATTACHMENT, s->maps, 0, i);
    glNamedFramebufferDrawBuffer(framebuffer, GL_NONE);
    glNamedFramebufferReadBuffer(framebuffer, GL_NONE);
    if (glCheckNamedFramebufferStatus(framebuffer, GL_DRAW_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE ||
        glIsTexture(s->views[size_t(i)]) != GL_TRUE)
      throw Error("globe: the context cannot render the shadow maps (a depth texture array and its views)");
  }
  // Depth comparison with bilinear weights of the four nearest texels
  // (percentage-closer filtering by the texture unit); lit outside the map.
  glCreateSamplers(1, &s->sampler);
  glSamplerParameteri(s->sampler, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glSamplerParameteri(s->sampler, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  glSamplerParameteri(s->sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glSamplerParameteri(s->sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glSamplerParameteri(s->sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_BORDER);
  glSamplerParameteri(s->sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_BORDER);
  const float far_depth[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  glSamplerParameterfv(s->sampler, GL_TEXTURE_BORDER_COLOR, far_depth);

  const std::string depth_only = version + "#define ATMOS_GLOBE_DEPTH_ONLY 1\n";
  s->depth.id = planet::link_program("globe",
                                     depth_only + planet::shader_text("globe", "src/planet/globe.vert.glsl"),
                                     depth_only + planet::shader_text("globe", "src/planet/globe.frag.glsl"));
  s->depth.locate();
  s->lit = lit_program(*pass, settings.first_unit, true, false);
  shadows = std::move(s);
}

bool Globe::Impl::fit_cascades(const GlobeView& view, const glm::dmat4& rotation, const glm::dvec3& camera,
                               const glm::dvec3& sun, const std::vector<TileDraw>& draws) {
  Shadows& s = *shadows;
  s.cascades.clear();
  // The frustum's slopes: with z_view = -d, w_clip = c d (c = -P[2][3]) and
  // x_clip = P[0][0] x - P[2][0] d, the side planes x_ndc = -1, 1 are
  // x / d = (c x_ndc + P[2][0]) / P[0][0].
  const glm::dmat4& projection = view.projection;
  const double c = -projection[2][3];
  planet::ShadowView v;
  v.camera = camera;
  v.right = glm::dvec3(rotation[0][0], rotation[1][0], rotation[2][0]);
  v.up = glm::dvec3(rotation[0][1], rotation[1][1], rotation[2][1]);
  v.forward = -glm::dvec3(rotation[0][2], rotation[1][2], rotation[2][2]);
  const double x0 = (-c + projection[2][0]) / projection[0][0], x1 = (c + projection[2][0]) / projection[0][0];
  const double y0 = (-c + projection[2][1]) / projection[1][1], y1 = (c + projection[2][1]) / projection[1][1];
  v.x_min = std::min(x0, x1);
  v.x_max = std::max(x0, x1);
  v.y_min = std::min(y0, y1);
  v.y_max = std::max(y0, y1);
  const double widest = std::sqrt(std::max(v.x_min * v.x_min, v.x_max * v.x_max) +
                                  std::max(v.y_min * v.y_min, v.y_max * v.y_max));
  // The first cascade starts at the nearest ground the view may show (the
  // tiles drawn, each within its vertices' heights widened by its mesh
  // error): the slices nearer than that hold nothing.
  const double radius = builder.bounds().radius_m;
  double nearest = INFINITY;
  for (const TileDraw& d : draws) {
    const Resident& tile = resident.find(d.key.packed())->second;
    const double error = builder.bounds().error_m(builder.spacing_m(d.key.level));
    nearest = std::min(nearest, nearest_view_depth_m(camera, d.key, radius + tile.min_height_m - error,
                                                     radius + tile.max_height_m + error, widest));
  }
  v.nearest_depth_m = std::max(nearest, 0.05);
  v.sun = sun;
  v.shadow_distance_m = s.distance_m;
  s.view = v;
  s.light = planet::shadow_light(sun);
  s.cascades = planet::fit_shadow_cascades(v, s.light, s.count, s.size);
  return !s.cascades.empty();
}

void Globe::Impl::render_shadow_maps(const std::vector<std::vector<TileDraw>>& casters,
                                     const std::vector<TileDraw>& receivers, const glm::dvec3& camera,
                                     GlobeStats& out) {
  Shadows& s = *shadows;
  GLint previous_framebuffer = 0;
  glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &previous_framebuffer);
  // Standard depth, as AtmospherePass reads a shadow map: clip z in [-1, 1]
  // from the sun's side (the near plane) away from it.
  glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);  // the terrain is a single-sided sheet: both sides cast
  glDisable(GL_BLEND);
  // Casters in front of the near plane are clamped onto it instead of
  // clipped ("pancaking"): they still shadow everything behind them.
  glEnable(GL_DEPTH_CLAMP);
  glViewport(0, 0, s.size, s.size);
  glUseProgram(s.depth.id);
  glBindVertexArray(vertex_array);
  const double inner = builder.bounds().radius_m + builder.bounds().min_height_m;
  const double outer = builder.bounds().radius_m + builder.bounds().max_height_m;
  const float clear_depth = 1.0f;
  std::vector<TileDraw> kept;
  std::vector<glm::dvec4> spheres;
  for (size_t i = 0; i < s.cascades.size(); ++i) {
    planet::ShadowCascade& c = s.cascades[i];
    // A caster must lie between a receiver of the cascade (a drawn tile in
    // its slice of view depths) and the sun, no farther than where the
    // sun's ray from the slice leaves the highest ground's sphere; the
    // receivers' lookups reach 4 texels beyond their points (normal offset
    // and filter). The farthest cascade, handed to the engine plugin for the
    // light shafts along the view rays through the air, holds the casters
    // of the whole frustum up to the shadow distance.
    const double shell = planet::sun_shell_distance_m(c.centre, c.radius_m, s.light.z, inner, outer);
    const double limit = c.z_far_m + c.half_size_m + c.radius_m + shell;
    planet::ShadowFootprint footprint;
    if (i + 1 == s.cascades.size()) {
      footprint = planet::shadow_footprint(s.view, s.light, s.cascades.front().near_depth_m, c.far_depth_m);
    } else {
      spheres.clear();
      for (const TileDraw& d : receivers) {
        const Resident& tile = resident.find(d.key.packed())->second;
        const double depth = glm::dot(tile.bound_centre - camera, s.view.forward);
        if (depth + tile.bound_radius_m >= c.near_depth_m && depth - tile.bound_radius_m <= c.far_depth_m)
          spheres.emplace_back(tile.bound_centre, tile.bound_radius_m);
      }
      footprint = planet::sphere_footprint(s.light, spheres);
    }
    double top = -INFINITY;
    kept.clear();
    for (const TileDraw& d : casters[i]) {
      const Resident& tile = resident.find(d.key.packed())->second;
      const double r = tile.bound_radius_m;
      const double x = glm::dot(tile.bound_centre, s.light.x) - c.box_centre.x;
      const double y = glm::dot(tile.bound_centre, s.light.y) - c.box_centre.y;
      const double z = glm::dot(tile.bound_centre, s.light.z);
      if (std::abs(x) > c.half_size_m + r || std::abs(y) > c.half_size_m + r || z + r < c.z_far_m || z - r > limit ||
          !planet::may_cast_onto(footprint, s.light, tile.bound_centre, r, 4.0 * c.texel_m, shell))
        continue;
      top = std::max(top, z + r);
      kept.push_back(d);
    }
    planet::extend_towards_sun(c, top, shell);
    const glm::mat4 clip(planet::cascade_clip_from_planet(s.light, c) * glm::translate(glm::dmat4(1.0), camera));
    glUniformMatrix4fv(s.depth.clip, 1, GL_FALSE, glm::value_ptr(clip));
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, s.framebuffers[i]);
    glClearNamedFramebufferfv(s.framebuffers[i], GL_DEPTH, 0, &clear_depth);
    out.shadow_triangles += draw_tiles(kept, s.depth, camera);
    out.shadow_casters += int(kept.size());
  }
  out.shadow_cascades = int(s.cascades.size());
  glDisable(GL_DEPTH_CLAMP);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, GLuint(previous_framebuffer));
}

Globe::Globe(const Atmosphere& atmosphere, const PlanetSurface& surface, const AtmospherePass& pass,
             const GlobeSettings& settings) {
  if (epoxy_gl_version() < 45) throw Error("globe: needs a current OpenGL 4.5 core context");
  planet::validate_sea_level(surface, atmosphere, "globe");
  if (!(settings.max_screen_error_px > 0.0) || !std::isfinite(settings.max_screen_error_px))
    throw Error("globe settings: max_screen_error_px must be a positive number of pixels");
  if (settings.max_tiles_per_frame < 1) throw Error("globe settings: max_tiles_per_frame must be at least 1");
  if (settings.first_unit < 0) throw Error("globe settings: first_unit must be a texture unit (>= 0)");
  if (settings.shadow_cascades < 0 || settings.shadow_cascades > planet::kMaxShadowCascades)
    throw Error("globe settings: shadow_cascades must be 0 (off) to " + std::to_string(planet::kMaxShadowCascades) +
                ", not " + std::to_string(settings.shadow_cascades));
  if (settings.shadow_cascades > 0) {
    if (settings.shadow_map_size < 64 || settings.shadow_map_size > 16384 || settings.shadow_map_size % 2 != 0)
      throw Error("globe settings: shadow_map_size must be an even number of texels in 64..16384, not " +
                  std::to_string(settings.shadow_map_size));
    if (!(settings.shadow_distance_m > 0.0) || !std::isfinite(settings.shadow_distance_m))
      throw Error("globe settings: shadow_distance_m must be a positive number of metres");
  }
  impl_ = std::make_unique<Impl>(atmosphere, surface, pass, settings);
  Impl& p = *impl_;
  p.check_pass_reaches_ground(pass);
  if (settings.memory_cap_bytes < std::size_t(kPermanentTiles) * p.builder.vertex_count() * sizeof(planet::TileVertex))
    throw Error("globe settings: memory_cap_bytes " + std::to_string(settings.memory_cap_bytes) +
                " holds less than the " + std::to_string(kPermanentTiles) + " tiles of levels 0 and 1");

  const std::string version = "#version 450 core\n";
  p.program = lit_program(pass, settings.first_unit, false, false);
  p.linked_for = pass.glsl_library(settings.first_unit);
  p.top_radius_m = atmosphere.top_radius_m;
  p.sun_angular_radius_rad = atmosphere.sun_angular_radius_rad;
  if (settings.shadow_cascades > 0) p.create_shadows(version);

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

  // The permanent tiles, levels 0 and 1: every area is drawn at least by
  // its level-1 tile, even before its own has arrived.
  std::vector<TileKey> base;
  for (int face = 0; face < 6; ++face)
    for (int level = 0; level <= kPermanentLevel; ++level)
      for (std::uint32_t y = 0; y < (1u << level); ++y)
        for (std::uint32_t x = 0; x < (1u << level); ++x) base.push_back({face, level, x, y});
  std::vector<planet::TileMesh> meshes(base.size());
  tbb::parallel_for(size_t(0), base.size(), [&](size_t i) { meshes[i] = p.builder.build(base[i]); });
  for (size_t i = 0; i < base.size(); ++i) p.upload(base[i], meshes[i]);
  // Finished meshes wait for at most two frames' uploads.
  if (!settings.complete_every_frame)
    p.streamer = std::make_unique<planet::TileStreamer>(p.builder, 2 * std::size_t(settings.max_tiles_per_frame));
}

Globe::~Globe() = default;

void Globe::link_rebind_programs(const AtmospherePass& pass) {
  Impl& p = *impl_;
  std::string library = pass.glsl_library(p.settings.first_unit);
  if (library == p.linked_for || (p.prelinked_lit.id != 0 && p.prelinked_for == library)) return;
  p.drop_prelinked();
  TileProgram lit = lit_program(pass, p.settings.first_unit, false, false);
  TileProgram shadowed;
  if (p.shadows) {
    try {
      shadowed = lit_program(pass, p.settings.first_unit, true, false);
    } catch (...) {
      glDeleteProgram(lit.id);
      throw;
    }
  }
  // Drawn with in another context of the share group: its commands must
  // have completed here (OpenGL 4.5 core, 5.3.1).
  glFinish();
  p.prelinked_lit = lit;
  p.prelinked_shadowed = shadowed;
  p.prelinked_for = std::move(library);
}

void Globe::rebind(const Atmosphere& atmosphere, const AtmospherePass& pass) {
  Impl& p = *impl_;
  if (atmosphere.bottom_radius_m != p.datum_radius_m)
    throw Error("globe rebind: the atmosphere's bottom radius " + std::to_string(atmosphere.bottom_radius_m) +
                " m is not the globe's datum " + std::to_string(p.datum_radius_m) +
                " m (the relief is built on it): build a new Globe");
  planet::validate_sea_level(p.description, atmosphere, "globe");
  p.check_pass_reaches_ground(pass);
  // The programs that light tiles carry the pass's library: kept when it
  // is the same text, else the new ones are linked (or taken from
  // link_rebind_programs) before anything changes, so that a failure
  // leaves the globe bound to its old pass.
  std::string library = pass.glsl_library(p.settings.first_unit);
  if (library == p.linked_for) {
    p.drop_prelinked();
    p.pass = &pass;
    p.top_radius_m = atmosphere.top_radius_m;
    p.sun_angular_radius_rad = atmosphere.sun_angular_radius_rad;
    return;
  }
  TileProgram lit, shadowed;
  if (p.prelinked_lit.id != 0 && p.prelinked_for == library) {
    lit = p.prelinked_lit;
    shadowed = p.prelinked_shadowed;
    p.prelinked_lit = p.prelinked_shadowed = TileProgram{};
    p.prelinked_for.clear();
  } else {
    p.drop_prelinked();
    lit = lit_program(pass, p.settings.first_unit, false, false);
  }
  if (p.shadows && shadowed.id == 0) {
    try {
      shadowed = lit_program(pass, p.settings.first_unit, true, false);
    } catch (...) {
      glDeleteProgram(lit.id);
      throw;
    }
  }
  glDeleteProgram(p.program.id);
  p.program = lit;
  if (p.shadows) {
    glDeleteProgram(p.shadows->lit.id);
    p.shadows->lit = shadowed;
  }
  // The eclipse's variants are linked again at their next use.
  for (TileProgram& e : p.eclipse_programs) {
    if (e.id != 0) glDeleteProgram(e.id);
    e = TileProgram{};
  }
  p.linked_for = std::move(library);
  p.pass = &pass;
  p.top_radius_m = atmosphere.top_radius_m;
  p.sun_angular_radius_rad = atmosphere.sun_angular_radius_rad;
}

void Globe::draw(const GlobeView& view) { draw_views(view, {}, {}); }

void Globe::draw_views(const GlobeView& view, const std::vector<GlobeView>& eye_views,
                       const std::function<void(std::size_t)>& bind_target) {
  Impl& p = *impl_;
  const PlanetFrame& frame = p.pass->frame();
  // --- Validation, before any state change. ---
  const auto check_matrices = [&p](const GlobeView& v) {
    planet::check_view_matrices("globe", v);
    // The cascades slice a perspective frustum: w_clip = c x (distance along
    // the view axis), c > 0, and x_clip, y_clip independent of w.
    if (p.shadows && !(v.projection[2][3] < 0.0 && v.projection[0][3] == 0.0 && v.projection[1][3] == 0.0 &&
                       v.projection[3][3] == 0.0 && std::abs(v.projection[0][0]) > 0.0))
      throw Error("globe view: shadows need a perspective projection (w_clip proportional to the view depth)");
  };
  check_matrices(view);
  for (const GlobeView& v : eye_views) check_matrices(v);
  const double sun_length = glm::length(view.sun_direction);
  if (!(sun_length > 0.0) || !std::isfinite(sun_length)) throw Error("globe view: zero or non-finite sun direction");
  if (!(view.nits_per_unit > 0.0) || !std::isfinite(view.nits_per_unit))
    throw Error("globe view: nits_per_unit must be positive");
  if (!(view.sun_illuminance_lux >= 0.0) || !std::isfinite(view.sun_illuminance_lux))
    throw Error("globe view: sun_illuminance_lux must be >= 0");
  // Moons that may hide part of the sun from some ground point select the
  // eclipse's variant; others change nothing (as in AtmospherePass).
  bool eclipse = false;
  try {
    eclipse = moons_may_eclipse(view.moons, view.sun_direction, p.top_radius_m, p.sun_angular_radius_rad);
  } catch (const Error& e) {
    throw Error(std::string("globe view: GlobeView::moons: ") + e.what());
  }

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
  const planet::LodSettings lod_settings = p.builder.lod_settings(p.settings.max_screen_error_px);
  GlobeStats stats;
  stats.view_selections = 1;
  const auto select = [&] {
    const auto t = Clock::now();
    planet::Selection s = planet::select_tiles(lod_camera, lod_settings, p.builder.bounds(), known_range);
    stats.selection_ms += ms_since(t);
    stats.nodes_visited += s.nodes_visited;
    return s;
  };
  planet::Selection selection = select();

  // --- New tiles. complete_every_frame: every missing tile built here (in
  // parallel) and uploaded, first the view's, then the shadow casters'.
  // Otherwise the worker's finished tiles are uploaded once the casters
  // are known (below). ---
  const bool complete = p.settings.complete_every_frame;
  const auto t1 = Clock::now();
  const double selection_before_ms = stats.selection_ms;
  if (complete) stats.tiles_pending = p.complete_by_generations(select, selection, stats);
  stats.generation_ms = ms_since(t1) - (stats.selection_ms - selection_before_ms);

  // --- The sun's cascades and their casters: for each cascade the tiles
  // of the view's level of detail inside its box's prism along the sun (the
  // view's tiles there, and those outside the view that shadow it), no
  // finer than the cascade's texels. ---
  std::vector<planet::Selection> casters;
  const auto t_shadows = Clock::now();
  const bool shadowed = p.shadows && p.fit_cascades(view, rotation, camera, sun, p.resolve(selection));
  if (shadowed) {
    const Shadows& s = *p.shadows;
    for (const planet::ShadowCascade& c : s.cascades) {
      // The box's side planes as those of a "view-projection" (select_tiles
      // uses its x, y and w rows only). A finest spacing of a texel keeps
      // the tiles near the camera out of the far cascades (their receivers
      // are far away, where the view's mesh is no finer either); the
      // nearest cascades keep the view's levels, the mesh their receivers
      // are drawn with.
      planet::LodCamera light_camera = lod_camera;
      light_camera.view_projection = planet::cascade_clip_from_planet(s.light, c);
      planet::LodSettings light_settings = lod_settings;
      light_settings.finest_spacing_m = std::max(lod_settings.finest_spacing_m, c.texel_m);
      casters.push_back(planet::select_tiles(light_camera, light_settings, p.builder.bounds(), known_range));
    }
    stats.shadow_selection_ms = ms_since(t_shadows);
  }
  // The view's tiles count again: the memory cap holds all, and the pending
  // tiles are the view's and the casters'.
  std::vector<const planet::Selection*> all{&selection};
  for (const planet::Selection& c : casters) all.push_back(&c);
  const auto t2 = Clock::now();
  if (!complete)
    stats.tiles_pending = p.stream(all, camera, stats);
  else if (shadowed)
    stats.tiles_pending = p.complete(all, stats);
  stats.generation_ms += ms_since(t2);

  ++p.frame;
  const std::vector<TileDraw> draws = p.resolve(selection);
  // --- The shadow maps. ---
  if (shadowed) {
    const auto t_resolve = Clock::now();
    std::vector<std::vector<TileDraw>> caster_draws;
    for (const planet::Selection& c : casters) caster_draws.push_back(p.resolve(c));
    stats.shadow_selection_ms += ms_since(t_resolve);
    p.render_shadow_maps(caster_draws, draws, camera, stats);
  }

  // --- Draw: each selected tile, or its nearest resident ancestor. ---
  glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_GREATER);
  glDepthMask(GL_TRUE);
  // Back faces culled: the terrain is a height field seen from above it,
  // where a triangle facing away lies behind one facing the camera (the
  // hidden slopes of the relief, and the skirts' inner sides: globe_mesh.cpp
  // winds them). Grid triangles are counter-clockwise seen from outside the
  // planet; a clip transform whose x, y and w rows have a positive
  // determinant mirrors the image (the usual perspective's is negative:
  // -P00 P11 times the rotation's 1), and the front face is then clockwise.
  GLint engine_front_face = GL_CCW, engine_cull_face = GL_BACK;
  glGetIntegerv(GL_FRONT_FACE, &engine_front_face);
  glGetIntegerv(GL_CULL_FACE_MODE, &engine_cull_face);
  glCullFace(GL_BACK);
  glEnable(GL_CULL_FACE);
  glDisable(GL_BLEND);
  TileProgram* lit = shadowed ? &p.shadows->lit : &p.program;
  if (eclipse) {
    lit = &p.eclipse_programs[shadowed ? 1 : 0];
    if (lit->id == 0) *lit = lit_program(*p.pass, p.settings.first_unit, shadowed, true);
  }
  const TileProgram& program = *lit;
  glUseProgram(program.id);
  glBindVertexArray(p.vertex_array);
  p.pass->bind_textures(p.settings.first_unit);
  glUniform3f(program.camera, float(camera.x), float(camera.y), float(camera.z));
  glUniform3f(program.sun, float(sun.x), float(sun.y), float(sun.z));
  const double lux_scale = view.sun_illuminance_lux > 0.0 ? view.sun_illuminance_lux / p.pass->sun_illuminance_lux() : 1.0;
  glUniform1f(program.light, float(lux_scale / view.nits_per_unit));
  if (shadowed) {
    const Shadows& s = *p.shadows;
    const int n = int(s.cascades.size());
    std::array<glm::mat4, planet::kMaxShadowCascades> light_clip{};
    std::array<float, planet::kMaxShadowCascades> far{}, blend{}, texel{}, depth_per_m{};
    for (int i = 0; i < n; ++i) {
      const planet::ShadowCascade& c = s.cascades[size_t(i)];
      light_clip[size_t(i)] =
          glm::mat4(planet::cascade_clip_from_planet(s.light, c) * glm::translate(glm::dmat4(1.0), camera));
      far[size_t(i)] = float(c.far_depth_m);
      blend[size_t(i)] = float(c.blend_start_m);
      texel[size_t(i)] = float(c.texel_m);
      depth_per_m[size_t(i)] = float(1.0 / (c.z_near_m - c.z_far_m));
    }
    glUniform1i(program.cascade_count, n);
    glUniformMatrix4fv(program.light_clip, n, GL_FALSE, glm::value_ptr(light_clip[0]));
    glUniform1fv(program.far, n, far.data());
    glUniform1fv(program.blend, n, blend.data());
    glUniform1fv(program.texel, n, texel.data());
    glUniform1fv(program.depth_per_m, n, depth_per_m.data());
    glBindTextureUnit(GLuint(p.settings.first_unit + 5), s.maps);
    glBindSampler(GLuint(p.settings.first_unit + 5), s.sampler);
  }
  if (eclipse) {
    // In float, as the pass's moons (physics::make_moons).
    std::array<glm::vec4, kMaxMoons> spheres{};
    for (size_t i = 0; i < view.moons.size(); ++i)
      spheres[i] = glm::vec4(glm::vec3(view.moons[i].centre_m), float(view.moons[i].radius_m));
    glUniform1i(program.moon_count, int(view.moons.size()));
    glUniform4fv(program.moon_spheres, kMaxMoons, glm::value_ptr(spheres[0]));
  }

  // Each view with the one selection: draw()'s view, or each of draw_views'
  // views, whose tiles are placed relative to the selection's camera
  // (morphs and lighting by the same offsets in every view) and carried to
  // the view's own eye: view x world = R (offset + camera - eye) in metres.
  const std::size_t view_count = eye_views.empty() ? 1 : eye_views.size();
  for (std::size_t i = 0; i < view_count; ++i) {
    const GlobeView& v = eye_views.empty() ? view : eye_views[i];
    glm::dmat4 view_rotation = rotation, clip = clip_from_offset;
    if (!eye_views.empty()) {
      const glm::dvec3 eye = (glm::dvec3(glm::inverse(v.view)[3]) - frame.centre) / frame.units_per_metre;
      view_rotation = v.view;
      view_rotation[3] = glm::dvec4(0.0, 0.0, 0.0, 1.0);
      clip = v.projection * view_rotation * glm::scale(glm::dmat4(1.0), glm::dvec3(frame.units_per_metre)) *
             glm::translate(glm::dmat4(1.0), camera - eye);
    }
    if (bind_target) bind_target(i);
    const glm::dmat3 clip_xyw(glm::dvec3(clip[0][0], clip[0][1], clip[0][3]),
                              glm::dvec3(clip[1][0], clip[1][1], clip[1][3]),
                              glm::dvec3(clip[2][0], clip[2][1], clip[2][3]));
    glFrontFace(glm::determinant(clip_xyw) < 0.0 ? GL_CCW : GL_CW);
    glViewport(0, 0, v.width, v.height);
    const glm::mat4 clip_f(clip);
    glUniformMatrix4fv(program.clip, 1, GL_FALSE, glm::value_ptr(clip_f));
    if (shadowed) {
      const glm::dvec3 forward = -glm::dvec3(view_rotation[0][2], view_rotation[1][2], view_rotation[2][2]);
      glUniform3f(program.forward, float(forward.x), float(forward.y), float(forward.z));
    }
    stats.triangles += p.draw_tiles(draws, program, camera);
  }
  glDisable(GL_CULL_FACE);
  glFrontFace(GLenum(engine_front_face));
  glCullFace(GLenum(engine_cull_face));
  stats.tiles_drawn = int(draws.size());
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

glm::dvec3 Globe::regional_albedo(const glm::dvec3& position) const {
  const PlanetFrame& frame = impl_->pass->frame();
  const glm::dvec3 r = (position - frame.centre) / frame.units_per_metre;
  const double length = glm::length(r);
  if (!std::isfinite(length)) throw Error("globe: regional_albedo of a non-finite position");
  const double radius = impl_->builder.bounds().radius_m;
  const glm::dvec3 nadir = length > 0.0 ? r / length : glm::dvec3(0.0, 0.0, 1.0);
  // The cap: the horizon's distance sqrt(2 R h + h^2) as an angle on the
  // sphere, at least 50 km, at most the visible cap acos(R / (R + h)).
  const double h = std::max(length - radius, 0.0);
  const double visible = std::acos(radius / (radius + h));
  const double horizon = std::sqrt(2.0 * radius * h + h * h) / radius;
  const double angle = std::max(std::min(horizon, visible), 50e3 / radius);
  // A Fibonacci lattice on the cap, uniform in area (cos theta uniform in
  // [cos angle, 1]; González 2010), around the nadir.
  constexpr int kSamples = 256;
  const glm::dvec3 helper = std::abs(nadir.z) < 0.9 ? glm::dvec3(0.0, 0.0, 1.0) : glm::dvec3(1.0, 0.0, 0.0);
  const glm::dvec3 east = glm::normalize(glm::cross(helper, nadir));
  const glm::dvec3 north = glm::cross(nadir, east);
  const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
  std::vector<glm::dvec3> directions(kSamples);
  for (int i = 0; i < kSamples; ++i) {
    const double cos_theta = 1.0 - (i + 0.5) / kSamples * (1.0 - std::cos(angle));
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    const double phi = golden_angle * i;
    directions[size_t(i)] =
        cos_theta * nadir + sin_theta * (std::cos(phi) * east + std::sin(phi) * north);
  }
  // The albedo at the scale of the samples' spacing (the imagery's overview
  // of that resolution averages what lies between them).
  const double spacing_m = radius * angle * std::sqrt(M_PI / kSamples);
  std::vector<glm::vec3> albedos(kSamples);
  impl_->surface.albedos(directions.data(), directions.size(), spacing_m, albedos.data());
  glm::dvec3 sum(0.0);
  for (const glm::vec3& a : albedos) sum += glm::dvec3(a);
  return glm::clamp(sum / double(kSamples), 0.0, 1.0);
}

double Globe::min_height_m() const { return impl_->builder.min_surface_height_m(); }
double Globe::max_height_m() const { return impl_->builder.max_surface_height_m(); }
const GlobeStats& Globe::last_stats() const { return impl_->stats; }

GlobeShadowMap Globe::shadow_map_for_pass() const {
  GlobeShadowMap map;
  const Impl& p = *impl_;
  if (!p.shadows || p.shadows->cascades.empty()) return map;
  const Shadows& s = *p.shadows;
  const size_t last = s.cascades.size() - 1;
  const PlanetFrame& frame = p.pass->frame();
  map.texture = s.views[last];
  // The engine's world -> planet-centred metres -> the cascade's clip space.
  map.matrix = planet::cascade_clip_from_planet(s.light, s.cascades[last]) *
               glm::scale(glm::dmat4(1.0), glm::dvec3(1.0 / frame.units_per_metre)) *
               glm::translate(glm::dmat4(1.0), -frame.centre);
  map.texel_m = s.cascades[last].texel_m;
  return map;
}

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
