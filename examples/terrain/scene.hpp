// The example's scenes: where the camera is and looks, where the sun is, and
// the objects standing on the terrain.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <optional>
#include <string>
#include <vector>

#include <atmos/eclipse.hpp>

#include "terrain.hpp"
#include "world.hpp"

namespace engine {

struct Camera {
  glm::dvec3 position{0.0};  // world, engine units (double: never sent to the GPU as is)
  glm::dvec3 forward{0.0, 0.0, -1.0};
  glm::dvec3 up{0.0, 1.0, 0.0};  // orthogonal to forward
  double fov_deg = 60.0;         // vertical
  double near = 0.1;             // engine units
  double far = 1000.0;           // engine units: beyond all geometry (finite projections, log depth)
};

struct SceneObject {
  enum class Shape { box, sphere };
  Shape shape = Shape::box;
  glm::dmat4 model{1.0};  // object -> world (double)
  glm::vec3 albedo{1.0f};
};

struct Scene {
  std::string name;
  Camera camera;
  glm::dvec3 sun_direction{0.0, 1.0, 0.0};  // world frame, unit, towards the sun
  std::vector<SceneObject> objects;
  double exposure_ev = 13.0;  // default exposure of the PNG output
  // Moons that may eclipse the sun (--moon), as atmos wants them: spheres in
  // planet-centred metres (the world's axes), not engine units.
  std::vector<atmos::Moon> moons;
};

// Command-line overrides of a scene's defaults (angles in degrees, in the
// local east-north-up frame: azimuth from north towards east).
struct SceneOverrides {
  std::optional<double> camera_altitude_m;  // above the terrain below the camera
  std::optional<double> look_azimuth_deg;
  std::optional<double> look_elevation_deg;
  std::optional<double> sun_elevation_deg;
  std::optional<double> sun_azimuth_deg;
  std::optional<double> fov_deg;
};

// "noon-valley", "sunset-shafts", "orbit-400km".
std::vector<std::string> scene_names();

// Throws std::invalid_argument for an unknown name.
Scene make_scene(const std::string& name, const SceneOverrides& overrides, const World& world, const Terrain& terrain);

}  // namespace engine
