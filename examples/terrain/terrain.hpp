// The example's geometry: a fractal heightfield terrain on an 80 km x 80 km
// patch of the planet, and the unit box and sphere its objects are made of.
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <vector>

#include "noise.hpp"
#include "world.hpp"

namespace engine {

// One vertex of every mesh of the engine (interleaved, 36 bytes).
struct Vertex {
  glm::vec3 position;  // object space, engine units
  glm::vec3 normal;    // object space, unit length
  glm::vec3 albedo;    // linear reflectance
};

struct MeshData {
  std::vector<Vertex> vertices;
  std::vector<std::uint32_t> indices;  // triangles, counter-clockwise seen from outside
};

struct TerrainSettings {
  std::uint32_t seed = 7;
  int cells = 512;  // grid cells per side of the patch (vertices: (cells + 1)^2)
};

// A valley winding from south to north through the patch between ridged
// mountain ranges of up to ~3.5 km, closed by a range at its northern end,
// with a lake on its floor; the heights fade to sea level over the last
// 7 km before the patch's edge, where the plugin's sphere takes over.
class Terrain {
 public:
  static constexpr double kLakeLevelKm = 0.22;
  static constexpr double kLakeNorthKm = 6.0;  // the lake's centre, north of the patch centre

  // `planet_albedo`: the plugin's ground colour (Atmosphere::ground_albedo),
  // which the terrain's albedo blends into near the edge, so the patch does
  // not end on a sharp colour border.
  Terrain(const World& world, const TerrainSettings& settings, glm::vec3 planet_albedo);

  // Height above sea level of the rendered surface (bilinear in the grid,
  // the same surface as the mesh up to the triangulation), for placing the
  // camera and the objects.
  double height_km(glm::dvec2 patch_km) const;

  // East coordinate of the valley's axis at a north coordinate.
  double valley_centre_km(double north_km) const;

  // The mesh: vertices relative to World::patch_centre(), in engine units.
  const MeshData& mesh() const { return mesh_; }
  // Its bounding box, in the same frame.
  glm::dvec3 bounds_min() const { return bounds_min_; }
  glm::dvec3 bounds_max() const { return bounds_max_; }

 private:
  double generated_height_km(double east_km, double north_km) const;

  Noise noise_;
  int cells_;
  std::vector<double> heights_km_;  // (cells + 1)^2 grid samples, row by row from south to north
  MeshData mesh_;
  glm::dvec3 bounds_min_{0.0}, bounds_max_{0.0};
};

// An axis-aligned unit box: x and z in [-0.5, 0.5], y in [0, 1] (standing on
// its base at the origin), white albedo, flat-shaded.
MeshData box_mesh();

// A unit sphere around the origin, white albedo, smooth-shaded.
MeshData sphere_mesh(int slices, int stacks);

}  // namespace engine
