#include "terrain.hpp"

#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

namespace engine {

namespace {

double smoothstep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}

// Runs body(row) for rows [0, count) on all cores. Terrain generation is the
// slowest part of start-up (a million samples of ~25 noise octaves each).
template <typename Body>
void parallel_rows(int count, const Body& body) {
  const int threads = std::max(1, std::min(count, static_cast<int>(std::thread::hardware_concurrency())));
  std::vector<std::jthread> workers;
  for (int t = 0; t < threads; ++t)
    workers.emplace_back([=, &body] {
      for (int row = t; row < count; row += threads) body(row);
    });
}  // the jthreads join here

// Reflectances (linear sRGB, roughly: the diffuse albedo of real surfaces).
constexpr glm::dvec3 kForest(0.045, 0.075, 0.035);
constexpr glm::dvec3 kMeadow(0.11, 0.12, 0.07);
constexpr glm::dvec3 kRock(0.15, 0.14, 0.13);
constexpr glm::dvec3 kSnow(0.80, 0.82, 0.86);
constexpr glm::dvec3 kWater(0.02, 0.03, 0.04);

}  // namespace

Terrain::Terrain(const World& world, const TerrainSettings& settings, glm::vec3 planet_albedo)
    : noise_(settings.seed), cells_(settings.cells) {
  if (cells_ < 2 || cells_ > 4096) throw std::invalid_argument("terrain cells must be in [2, 4096]");
  const int n = cells_ + 1;
  const double half = 0.5 * World::kPatchSizeKm;
  const double step = World::kPatchSizeKm / cells_;
  auto patch_at = [&](int i, int j) { return glm::dvec2(-half + i * step, -half + j * step); };

  heights_km_.resize(static_cast<size_t>(n) * n);
  parallel_rows(n, [&](int j) {
    for (int i = 0; i < n; ++i) {
      const glm::dvec2 p = patch_at(i, j);
      heights_km_[static_cast<size_t>(j) * n + i] = generated_height_km(p.x, p.y);
    }
  });

  // Vertices on the sphere, in double, then relative to the patch centre in
  // float: within ±40 km a float resolves a few millimetres.
  const glm::dvec3 origin = world.patch_centre();
  std::vector<glm::dvec3> points(heights_km_.size());
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const size_t k = static_cast<size_t>(j) * n + i;
      points[k] = world.surface_point(patch_at(i, j), heights_km_[k]) - origin;
    }

  mesh_.vertices.resize(points.size());
  parallel_rows(n, [&](int j) {
    for (int i = 0; i < n; ++i) {
      const size_t k = static_cast<size_t>(j) * n + i;
      auto at = [&](int ii, int jj) {
        return points[static_cast<size_t>(std::clamp(jj, 0, n - 1)) * n + std::clamp(ii, 0, n - 1)];
      };
      // Normal from central differences of the displaced sphere points: it
      // includes the planet's curvature, and matches the mesh's shape.
      const glm::dvec3 normal = glm::normalize(glm::cross(at(i + 1, j) - at(i - 1, j), at(i, j + 1) - at(i, j - 1)));
      const glm::dvec2 p = patch_at(i, j);
      const LocalFrame frame = world.local_frame(p);
      const double h = heights_km_[k];
      const double flatness = glm::dot(normal, frame.up);  // 1 on flat ground

      // Albedo: forest in the valleys, meadows higher up, rock on steep
      // slopes, snow above a ragged snow line where it can lie, water on the
      // lake. Smooth transitions: no hard material borders.
      const double variation = noise_.fbm(p.x / 1.5 + 40.0, p.y / 1.5, 4);
      // Forest and clearings below ~1.4 km, meadows above.
      const double clearings = smoothstep(0.1, 0.4, noise_.fbm(p.x / 0.8 - 13.0, p.y / 0.8 + 29.0, 5));
      glm::dvec3 albedo = glm::mix(kForest, kMeadow, std::max(clearings, smoothstep(1.0, 1.8, h + 0.3 * variation)));
      albedo = glm::mix(albedo, kRock, smoothstep(0.86, 0.72, flatness));
      const double snow_line = 2.7 + 0.3 * variation;
      albedo = glm::mix(albedo, kSnow, smoothstep(snow_line, snow_line + 0.2, h) * smoothstep(0.6, 0.75, flatness));
      const double edge = std::max(std::abs(p.x), std::abs(p.y));
      if (h <= kLakeLevelKm + 1e-9 && edge < 33.0) albedo = kWater;
      // Towards the edge, fade into the plugin's planet colour.
      albedo = glm::mix(albedo, glm::dvec3(planet_albedo), smoothstep(33.0, 39.0, edge));

      mesh_.vertices[k] = {glm::vec3(points[k]), glm::vec3(normal), glm::vec3(albedo)};
    }
  });

  bounds_min_ = bounds_max_ = points.front();
  for (const glm::dvec3& p : points) {
    bounds_min_ = glm::min(bounds_min_, p);
    bounds_max_ = glm::max(bounds_max_, p);
  }

  // Two triangles per cell, counter-clockwise seen from above: i runs east
  // and j north, and east x north = up.
  mesh_.indices.reserve(static_cast<size_t>(cells_) * cells_ * 6);
  for (int j = 0; j < cells_; ++j)
    for (int i = 0; i < cells_; ++i) {
      const auto k = static_cast<std::uint32_t>(j * n + i);
      const auto north = k + static_cast<std::uint32_t>(n);
      mesh_.indices.insert(mesh_.indices.end(), {k, k + 1, north + 1, k, north + 1, north});
    }
}

double Terrain::valley_centre_km(double north_km) const {
  // Meanders of a few km over a few tens of km.
  return 12.0 * noise_.fbm(0.5, north_km / 30.0, 3);
}

double Terrain::generated_height_km(double east_km, double north_km) const {
  const double e = east_km, n = north_km;
  // Distance from the valley's axis, against a half width that varies along it.
  const double half_width = 1.2 + 1.5 * (0.5 + 0.5 * noise_.fbm(3.7, n / 15.0, 2));
  const double distance = std::abs(e - valley_centre_km(n));
  // 0 on the valley floor, 1 in the mountains; a range closes the valley's
  // northern end (the noon view looks along the valley at it).
  const double mountains = std::max(smoothstep(half_width, half_width + 6.0, distance), smoothstep(20.0, 32.0, n));

  // The floor: gentle moraine hills of ±80 m.
  const double valley_floor = 0.30 + 0.08 * noise_.fbm(e / 2.0, n / 2.0, 6);
  const double ranges = 4.6 * std::pow(noise_.ridged(e / 22.0 + 5.3, n / 22.0 - 2.1, 10), 2.2);
  const double hills = 0.5 * (0.5 + 0.5 * noise_.fbm(e / 6.0 - 9.2, n / 6.0 + 4.4, 7));
  double h = valley_floor + mountains * (ranges + hills);

  // The lake: a shallow basin on the valley floor, filled to a flat level.
  const double lake_e = (e - valley_centre_km(kLakeNorthKm)) / 3.0, lake_n = (n - kLakeNorthKm) / 5.0;
  h -= 0.15 * std::exp(-(lake_e * lake_e + lake_n * lake_n));
  h = std::max(h, kLakeLevelKm);

  // Down to sea level over the last 7 km before the edge.
  return h * smoothstep(0.5 * World::kPatchSizeKm, 0.5 * World::kPatchSizeKm - 7.0, std::max(std::abs(e), std::abs(n)));
}

double Terrain::height_km(glm::dvec2 patch_km) const {
  const double half = 0.5 * World::kPatchSizeKm;
  const double step = World::kPatchSizeKm / cells_;
  const double x = std::clamp((patch_km.x + half) / step, 0.0, double(cells_));
  const double y = std::clamp((patch_km.y + half) / step, 0.0, double(cells_));
  const int i = std::min(static_cast<int>(x), cells_ - 1), j = std::min(static_cast<int>(y), cells_ - 1);
  const double fx = x - i, fy = y - j;
  const int n = cells_ + 1;
  auto h = [&](int ii, int jj) { return heights_km_[static_cast<size_t>(jj) * n + ii]; };
  return glm::mix(glm::mix(h(i, j), h(i + 1, j), fx), glm::mix(h(i, j + 1), h(i + 1, j + 1), fx), fy);
}

MeshData box_mesh() {
  MeshData mesh;
  // Each face: its outward normal and two tangent axes u, v with u x v = normal.
  struct Face {
    glm::vec3 normal, u, v;
  };
  const Face faces[] = {
      {{1, 0, 0}, {0, 0, -1}, {0, 1, 0}}, {{-1, 0, 0}, {0, 0, 1}, {0, 1, 0}}, {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
      {{0, -1, 0}, {1, 0, 0}, {0, 0, 1}}, {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},  {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
  };
  const glm::vec3 centre(0.0f, 0.5f, 0.0f);
  for (const Face& f : faces) {
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    for (const auto& [su, sv] : {std::pair{-1.0f, -1.0f}, {1.0f, -1.0f}, {1.0f, 1.0f}, {-1.0f, 1.0f}})
      mesh.vertices.push_back({centre + 0.5f * (f.normal + su * f.u + sv * f.v), f.normal, glm::vec3(1.0f)});
    mesh.indices.insert(mesh.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
  }
  return mesh;
}

MeshData sphere_mesh(int slices, int stacks) {
  MeshData mesh;
  constexpr double kPi = 3.14159265358979323846;
  for (int j = 0; j <= stacks; ++j) {
    const double theta = kPi * j / stacks;  // from the south pole (-y) to the north pole (+y)
    for (int i = 0; i <= slices; ++i) {
      const double phi = 2.0 * kPi * i / slices;
      const glm::vec3 p(
          glm::dvec3(std::sin(theta) * std::cos(phi), -std::cos(theta), -std::sin(theta) * std::sin(phi)));
      mesh.vertices.push_back({p, p, glm::vec3(1.0f)});
    }
  }
  const auto row = static_cast<std::uint32_t>(slices + 1);
  for (int j = 0; j < stacks; ++j)
    for (int i = 0; i < slices; ++i) {
      const auto k = static_cast<std::uint32_t>(j) * row + static_cast<std::uint32_t>(i);
      mesh.indices.insert(mesh.indices.end(), {k, k + 1, k + row + 1, k, k + row + 1, k + row});
    }
  return mesh;
}

}  // namespace engine
