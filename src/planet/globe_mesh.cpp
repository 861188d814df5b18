#include "planet/globe_mesh.hpp"

#include <glm/geometric.hpp>

#include <numbers>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace atmos::planet {

namespace {

// Vertex spacing above which the albedo is averaged over the vertex's cell.
constexpr double kAlbedoFilterSpacing_m = 2000.0;

// The grid extended by a ring of two vertices on every side, for the normals
// of this level and of the parent's (central differences over 1 and 2 cells).
constexpr int kRing = 2;
constexpr int kExtended = kTileSide + 2 * kRing;

int grid_index(int i, int j) { return j * kTileSide + i; }

// The grid vertex k of skirt line e (0: s = 0, 1: s = 1, 2: t = 0, 3: t = 1,
// 4: s = 1/2, 5: t = 1/2).
int edge_grid_index(int e, int k) {
  switch (e) {
    case 0: return grid_index(0, k);
    case 1: return grid_index(kTileQuads, k);
    case 2: return grid_index(k, 0);
    case 3: return grid_index(k, kTileQuads);
    case 4: return grid_index(kTileQuads / 2, k);
    default: return grid_index(k, kTileQuads / 2);
  }
}

void store(float out[3], const glm::dvec3& v) {
  out[0] = float(v.x);
  out[1] = float(v.y);
  out[2] = float(v.z);
}

}  // namespace

MeshBuilder::MeshBuilder(const Surface& surface, double radius_m) : surface_(surface), radius_m_(radius_m) {
  bounds_.radius_m = radius_m;
  bounds_.min_height_m = surface.min_height_m();
  bounds_.max_height_m = surface.max_height_m();
  measure_level_errors();
  // The mesh's error against the true surface: the relief's deviation from
  // the mesh's triangles, plus the sagitta of a chord of the datum sphere,
  // spacing^2 / (8 R), by which a flat triangle falls below the sphere. At
  // least 1/16 of the spacing: the albedo and the normals are sampled at the
  // vertices, so the vertices must not be more than 16 error bounds (16 px at
  // 1 px) apart on the screen, even where the relief is smooth (the sea).
  // Where imagery holds detail finer than the spacing, at least 1/4 of it:
  // its colours then stay within 4 px of where they belong.
  const double r = radius_m, imagery_pixel = surface.imagery_pixel_m();
  bounds_.error_m = [this, r, imagery_pixel](double spacing_m) {
    const double floor = imagery_pixel > 0.0 && spacing_m > 2.0 * imagery_pixel ? spacing_m / 4.0 : spacing_m / 16.0;
    return std::max(measured_error_m(spacing_m) + spacing_m * spacing_m / (8.0 * r), floor);
  };

  // The triangles: a run per quadrant (bit 0: the upper half in s, bit 1:
  // in t), so that a tile can draw some of its quadrants, then a run for
  // the whole tile. Grid: two triangles per quad, both containing the
  // diagonal (i, j)-(i+1, j+1). Skirts: a quadrant's along its four sides,
  // two on the tile's edges (cube_sphere.hpp: 0 at s = 0, 1 at s = 1, 2 at
  // t = 0, 3 at t = 1) and two on its midlines, which close the gap rounding
  // leaves between the quadrant and a finer tile drawn in the neighbouring
  // one; the whole tile's along its four edges.
  //
  // Winding (the globe culls back faces): every face's axes satisfy
  // U x V = N (cube_sphere.cpp), so a grid triangle (i, j), (i + 1, j),
  // (i + 1, j + 1), whose normal is U x (U + V) = N, is counter-clockwise
  // seen from outside the planet. A skirt's triangle a, b, b_low (b after a
  // along the line, b_low below b) has the normal (b - a) x (b_low - a),
  // -U for a line along t and +V for a line along s; each skirt is wound to
  // face away from the area it bounds. A crack's wall is seen from the
  // lower side of the step, through the other tile's surface: there the
  // neighbour's skirt, facing this way, closes it.
  const auto quad = [&](int i, int j) {
    const std::uint32_t a = std::uint32_t(grid_index(i, j)), b = std::uint32_t(grid_index(i + 1, j)),
                        c = std::uint32_t(grid_index(i + 1, j + 1)), d = std::uint32_t(grid_index(i, j + 1));
    indices_.insert(indices_.end(), {a, b, c, a, c, d});
  };
  // Skirt line e from vertex `first` on; `area_above`: the area it bounds
  // lies at larger s (lines along t: 0, 1, 4) or larger t (lines along s).
  const auto skirt = [&](int e, int first, int count, bool area_above) {
    const bool along_t = e == 0 || e == 1 || e == 4;
    const bool as_wound = along_t == area_above;  // -U faces away from s above; +V from t below
    for (int k = first; k < first + count; ++k) {
      const std::uint32_t a = std::uint32_t(edge_grid_index(e, k)), b = std::uint32_t(edge_grid_index(e, k + 1));
      const std::uint32_t a_low = std::uint32_t(kGridVertices + e * kTileSide + k), b_low = a_low + 1;
      if (as_wound)
        indices_.insert(indices_.end(), {a, b, b_low, a, b_low, a_low});
      else
        indices_.insert(indices_.end(), {a, b_low, b, a, a_low, b_low});
    }
  };
  constexpr int half = kTileQuads / 2;
  for (int q = 0; q < 4; ++q) {
    const int qi = (q & 1) * half, qj = (q >> 1) * half;
    const bool upper_s = (q & 1) != 0, upper_t = (q >> 1) != 0;
    for (int j = qj; j < qj + half; ++j)
      for (int i = qi; i < qi + half; ++i) quad(i, j);
    skirt(upper_s ? 1 : 0, qj, half, !upper_s);  // the tile edge along t
    skirt(4, qj, half, upper_s);                 // the midline s = 1/2
    skirt(upper_t ? 3 : 2, qi, half, !upper_t);  // the tile edge along s
    skirt(5, qi, half, upper_t);                 // the midline t = 1/2
  }
  quadrant_run_ = indices_.size() / 4;
  for (int j = 0; j < kTileQuads; ++j)
    for (int i = 0; i < kTileQuads; ++i) quad(i, j);
  for (int e = 0; e < 4; ++e) skirt(e, 0, kTileQuads, e == 0 || e == 2);
}

void MeshBuilder::measure_level_errors() {
  // For each level, kCells cells of the level's mean spacing s, each a
  // square on the tangent plane of a pseudo-random point of the sphere
  // (a fixed linear congruential sequence: the same sample on every run),
  // split into two triangles along its diagonal as the tiles' quads are.
  // The cell's deviation is the largest |h - (triangle interpolation of the
  // corner heights)| over a 4 x 4 lattice inside it; the level's error is
  // kMargin times the largest over the cells. Gradient-noise relief is
  // statistically the same everywhere a style places it, so a few hundred
  // cells see its steepest terrain; with elevation data, half the cells lie
  // inside the data's extent.
  constexpr int kLevels = 30;
  constexpr int kCells = 256;
  constexpr double kMargin = 1.5;
  level_errors_m_.assign(kLevels, 0.0);
  std::vector<glm::dvec3> points(kCells), tangent_a(kCells), tangent_b(kCells);
  std::uint64_t state = 0x9e3779b97f4a7c15ull;
  const auto uniform = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return double(state >> 11) * 0x1.0p-53;
  };
  for (int c = 0; c < kCells; ++c) {
    const double u = uniform(), v = uniform();
    points[size_t(c)] = glm::normalize(surface_.sample_direction(u, v, double(c % 2) * 0.75));
    const glm::dvec3 helper = std::abs(points[size_t(c)].z) < 0.9 ? glm::dvec3(0, 0, 1) : glm::dvec3(1, 0, 0);
    tangent_a[size_t(c)] = glm::normalize(glm::cross(helper, points[size_t(c)]));
    tangent_b[size_t(c)] = glm::cross(points[size_t(c)], tangent_a[size_t(c)]);
  }
  tbb::parallel_for(0, kLevels, [&](int level) {
    const double s = spacing_m(level);
    double worst = 0.0;
    for (int c = 0; c < kCells; ++c) {
      const glm::dvec3 origin = points[size_t(c)] * radius_m_;
      const auto h = [&](double x, double y) {
        return surface_height_m(
            glm::normalize(origin + tangent_a[size_t(c)] * (x * s) + tangent_b[size_t(c)] * (y * s)));
      };
      const double h00 = h(0, 0), h10 = h(1, 0), h01 = h(0, 1), h11 = h(1, 1);
      for (int j = 0; j < 4; ++j)
        for (int i = 0; i < 4; ++i) {
          const double x = (i + 0.5) / 4.0, y = (j + 0.5) / 4.0;
          const double mesh = x >= y ? h00 + x * (h10 - h00) + y * (h11 - h10) : h00 + y * (h01 - h00) + x * (h11 - h01);
          worst = std::max(worst, std::abs(h(x, y) - mesh));
        }
    }
    level_errors_m_[size_t(level)] = kMargin * worst;
  });
  // A finer mesh is never less accurate: make the errors non-increasing.
  for (int level = kLevels - 2; level >= 0; --level)
    level_errors_m_[size_t(level)] = std::max(level_errors_m_[size_t(level)], level_errors_m_[size_t(level + 1)]);
}

double MeshBuilder::measured_error_m(double spacing) const {
  // Between the measured levels, log-linear in the spacing; coarser than
  // level 0 and finer than the last level, proportional to the spacing.
  const double s0 = spacing_m(0);
  const int last = int(level_errors_m_.size()) - 1;
  if (!(spacing > 0.0)) return 0.0;
  const double level = std::log2(s0 / spacing);
  if (level <= 0.0) return level_errors_m_[0] * (spacing / s0);
  if (level >= last) return level_errors_m_[size_t(last)] * spacing / spacing_m(last);
  const int below = int(std::floor(level));
  const double f = level - below;
  const double a = std::max(level_errors_m_[size_t(below)], 1e-12);
  const double b = std::max(level_errors_m_[size_t(below + 1)], 1e-12);
  return std::exp(std::log(a) + f * (std::log(b) - std::log(a)));
}

std::vector<glm::vec3> MeshBuilder::vertex_albedos(const TileKey& key) const {
  const double scale = 1.0 / double(kTileQuads);
  const double spacing = spacing_m(key.level);
  // Where the vertices are farther apart than the albedo's finest features,
  // the albedo is averaged over the vertex's cell (a 3 x 3 box filter of
  // samples of the surface prefiltered to a third of the spacing; Heckbert
  // 1989 on prefiltering), not sampled at one point: point samples of a
  // pattern finer than the grid alias into blocks.
  const int taps = spacing < kAlbedoFilterSpacing_m ? 1 : 3;
  std::vector<glm::dvec3> directions;
  directions.reserve(std::size_t(kGridVertices * taps * taps));
  for (int j = 0; j < kTileSide; ++j)
    for (int i = 0; i < kTileSide; ++i)
      for (int b = 0; b < taps; ++b)
        for (int a = 0; a < taps; ++a) {
          const double da = taps == 1 ? 0.0 : (a - 1) / 3.0, db = taps == 1 ? 0.0 : (b - 1) / 3.0;
          directions.push_back(tile_direction(key, (double(i) + da) * scale, (double(j) + db) * scale));
        }
  std::vector<glm::vec3> samples(directions.size());
  surface_.albedos(directions.data(), directions.size(), spacing / double(taps), samples.data());
  std::vector<glm::vec3> albedo(std::size_t(kGridVertices), glm::vec3(0.0f));
  for (std::size_t k = 0; k < samples.size(); ++k) albedo[k / std::size_t(taps * taps)] += samples[k];
  for (glm::vec3& a : albedo) a /= float(taps * taps);
  return albedo;
}

double MeshBuilder::spacing_m(int level) const {
  return radius_m_ * (0.5 * std::numbers::pi) / (std::ldexp(1.0, level) * double(kTileQuads));
}

double MeshBuilder::skirt_depth_m(int level) const {
  // Deeper than the largest step between this level's surface and a
  // neighbour's one level coarser (each within its error of the true
  // surface), plus a margin of 1 % of the tile for the rounding of the two
  // tiles' morphs.
  const double coarser = spacing_m(std::max(level - 1, 0));
  return 2.0 * bounds_.error_m(coarser) + 0.01 * spacing_m(level) * kTileQuads;
}

LodSettings MeshBuilder::lod_settings(double max_screen_error_px) const {
  LodSettings s;
  s.max_screen_error_px = max_screen_error_px;
  s.tile_quads = kTileQuads;
  return s;
}

TileMesh MeshBuilder::build(const TileKey& key) const {
  TileMesh mesh;
  mesh.origin = tile_direction(key, 0.5, 0.5) * radius_m_;
  const double scale = 1.0 / double(kTileQuads);

  // Positions on the extended grid, planet-centred m. Inside the tile the
  // directions come from tile_direction (canonical on shared edges); the
  // ring outside it only feeds the normals.
  std::vector<glm::dvec3> p(size_t(kExtended * kExtended));
  std::vector<glm::dvec3> up(size_t(kExtended * kExtended));
  mesh.min_height_m = INFINITY;
  mesh.max_height_m = -INFINITY;
  for (int j = -kRing; j < kTileSide + kRing; ++j)
    for (int i = -kRing; i < kTileSide + kRing; ++i)
      up[size_t((j + kRing) * kExtended + (i + kRing))] = tile_direction(key, double(i) * scale, double(j) * scale);
  std::vector<double> heights(up.size());
  surface_.heights_m(up.data(), up.size(), heights.data());
  for (int j = -kRing; j < kTileSide + kRing; ++j)
    for (int i = -kRing; i < kTileSide + kRing; ++i) {
      const size_t n = size_t((j + kRing) * kExtended + (i + kRing));
      const double h = heights[n];
      p[n] = up[n] * (radius_m_ + h);
      if (i >= 0 && i < kTileSide && j >= 0 && j < kTileSide) {
        mesh.min_height_m = std::min(mesh.min_height_m, h);
        mesh.max_height_m = std::max(mesh.max_height_m, h);
      }
    }
  const auto at = [&](int i, int j) -> const glm::dvec3& { return p[size_t((j + kRing) * kExtended + (i + kRing))]; };
  const auto up_at = [&](int i, int j) -> const glm::dvec3& {
    return up[size_t((j + kRing) * kExtended + (i + kRing))];
  };
  // The normal of the mesh at (i, j) from central differences over `step`
  // cells (1: this level; 2: the parent's), turned outwards.
  const auto normal = [&](int i, int j, int step) {
    glm::dvec3 n = glm::cross(at(i + step, j) - at(i - step, j), at(i, j + step) - at(i, j - step));
    if (glm::dot(n, up_at(i, j)) < 0.0) n = -n;
    const double length = glm::length(n);
    return length > 0.0 ? n / length : up_at(i, j);
  };

  const std::vector<glm::vec3> albedos = vertex_albedos(key);
  mesh.vertices.resize(vertex_count());
  const bool has_parent = key.level > 0;
  for (int j = 0; j < kTileSide; ++j)
    for (int i = 0; i < kTileSide; ++i) {
      const glm::dvec3& position = at(i, j);
      glm::dvec3 parent = position, parent_normal = normal(i, j, 1);
      if (has_parent) {
        const bool odd_i = (i & 1) != 0, odd_j = (j & 1) != 0;
        if (odd_i && odd_j) {
          parent = 0.5 * (at(i - 1, j - 1) + at(i + 1, j + 1));
          parent_normal = 0.5 * (normal(i - 1, j - 1, 2) + normal(i + 1, j + 1, 2));
        } else if (odd_i) {
          parent = 0.5 * (at(i - 1, j) + at(i + 1, j));
          parent_normal = 0.5 * (normal(i - 1, j, 2) + normal(i + 1, j, 2));
        } else if (odd_j) {
          parent = 0.5 * (at(i, j - 1) + at(i, j + 1));
          parent_normal = 0.5 * (normal(i, j - 1, 2) + normal(i, j + 1, 2));
        } else {
          parent_normal = normal(i, j, 2);
        }
      }
      TileVertex& v = mesh.vertices[size_t(grid_index(i, j))];
      store(v.position, position - mesh.origin);
      store(v.morph_offset, parent - position);
      store(v.normal, normal(i, j, 1));
      store(v.parent_normal, parent_normal);
      const glm::vec3& albedo = albedos[size_t(grid_index(i, j))];
      v.albedo[0] = albedo.x;
      v.albedo[1] = albedo.y;
      v.albedo[2] = albedo.z;
    }

  // Skirts: each vertex of the edges and midlines again, lowered along the
  // vertical; it keeps the grid vertex's morph, normal and albedo so that it
  // follows it.
  const double depth = skirt_depth_m(key.level);
  for (int e = 0; e < 6; ++e)
    for (int k = 0; k < kTileSide; ++k) {
      const int n = edge_grid_index(e, k);
      const int i = n % kTileSide, j = n / kTileSide;
      TileVertex v = mesh.vertices[size_t(n)];
      store(v.position, at(i, j) - depth * up_at(i, j) - mesh.origin);
      mesh.vertices[size_t(kGridVertices + e * kTileSide + k)] = v;
    }
  return mesh;
}

}  // namespace atmos::planet
