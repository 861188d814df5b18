#include "scene.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace engine {

namespace {

struct Preset {
  const char* name;
  // Camera: on the valley's axis (plus an eastward offset) at a north
  // coordinate of the patch, some height above the terrain; or, for the
  // orbit, placed so that its view's centre falls on the patch's centre.
  double camera_north_km;
  double camera_east_of_valley_km;
  bool aim_at_patch_centre;
  double aim_elevation_deg;  // aim_at_patch_centre: the elevation under which the camera sees the patch centre
  double camera_altitude_m;
  double look_azimuth_deg, look_elevation_deg;
  double sun_azimuth_deg, sun_elevation_deg;
  double fov_deg;
  double exposure_ev;
};

constexpr Preset kPresets[] = {
    // Looking north along the valley at the range that closes it, ~55 km
    // away, sun high in the south-east: haze on the far mountains.
    {"noon-valley", -30.0, 0.0, false, 0.0, 300.0, 18.0, 2.0, 150.0, 55.0, 60.0, 13.0},
    // The same valley at sunset from 800 m, looking up it into the sun,
    // 2.5° high, setting behind the foot of the western ridge: the ridge's
    // shadow and the towers' shadows as dark shafts in the sunlit haze, rays
    // from the ridge's edge, and no Mie halo through the mountain.
    {"sunset-shafts", -30.0, 0.0, false, 0.0, 800.0, 15.0, 3.0, 10.0, 2.5, 60.0, 10.0},
    // The patch from 400 km, looking down obliquely towards it (from the
    // south-south-west): the patch in the lower half of the image (seen 32°
    // below the horizontal), the limb (20° below) and space above it.
    {"orbit-400km", 0.0, 0.0, true, -32.0, 400e3, 20.0, -25.0, 110.0, 25.0, 22.0, 13.0},
};

// Objects on the valley floor and its slopes, in front of the noon and
// sunset cameras: where they stand (north, east of the valley's axis),
// shape, size (km) and colour.
struct Placement {
  double north_km, east_of_valley_km;
  SceneObject::Shape shape;
  double width_km, height_km;  // boxes: footprint side and height; spheres: width = height = diameter
  double yaw_deg;
  glm::vec3 albedo;
};

constexpr glm::vec3 kConcrete(0.45f, 0.43f, 0.40f);
constexpr glm::vec3 kRed(0.50f, 0.08f, 0.05f);
constexpr glm::vec3 kWhite(0.75f, 0.75f, 0.75f);
constexpr glm::vec3 kDark(0.05f, 0.06f, 0.08f);

constexpr Placement kPlacements[] = {
    {-25.5, -0.8, SceneObject::Shape::box, 0.12, 0.45, 10.0, kConcrete},
    {-24.8, 0.9, SceneObject::Shape::box, 0.10, 0.30, 35.0, kRed},
    {-23.5, 0.2, SceneObject::Shape::sphere, 0.30, 0.30, 0.0, kWhite},
    {-21.0, -1.0, SceneObject::Shape::box, 0.15, 0.60, 60.0, kConcrete},
    {-18.0, 1.3, SceneObject::Shape::sphere, 0.50, 0.50, 0.0, kWhite},
    {-14.0, 0.0, SceneObject::Shape::box, 0.20, 0.90, 20.0, kDark},
    {-6.0, -1.5, SceneObject::Shape::box, 0.12, 0.40, 45.0, kRed},
    {-4.0, -0.5, SceneObject::Shape::sphere, 0.40, 0.40, 0.0, kWhite},
};

SceneObject place(const Placement& p, const World& world, const Terrain& terrain) {
  const glm::dvec2 patch(terrain.valley_centre_km(p.north_km) + p.east_of_valley_km, p.north_km);
  const LocalFrame frame = world.local_frame(patch);
  // Stand on the lowest point under the footprint: on a slope the object
  // sinks into the ground on the uphill side rather than floating.
  double ground_km = terrain.height_km(patch);
  for (const double de : {-0.5, 0.5})
    for (const double dn : {-0.5, 0.5})
      ground_km = std::min(ground_km, terrain.height_km(patch + p.width_km * glm::dvec2(de, dn)));

  SceneObject object;
  object.shape = p.shape;
  object.albedo = p.albedo;
  // Object axes: x east, y up (radial), z south, as the world's axes at the
  // patch centre; then a turn about the vertical and the size.
  glm::dvec3 base = world.surface_point(patch, ground_km);
  glm::dvec3 size = kUnitsPerKm * glm::dvec3(p.width_km, p.height_km, p.width_km);
  if (p.shape == SceneObject::Shape::sphere) {
    size *= 0.5;                        // the unit sphere's radius is 1
    base += frame.up * (0.8 * size.y);  // sunk by a fifth of its radius
  }
  const glm::dmat4 to_world(glm::dvec4(frame.east, 0.0), glm::dvec4(frame.up, 0.0), glm::dvec4(-frame.north, 0.0),
                            glm::dvec4(base, 1.0));
  object.model = glm::scale(glm::rotate(to_world, glm::radians(p.yaw_deg), glm::dvec3(0.0, 1.0, 0.0)), size);
  return object;
}

}  // namespace

std::vector<std::string> scene_names() {
  std::vector<std::string> names;
  for (const Preset& p : kPresets) names.emplace_back(p.name);
  return names;
}

Scene make_scene(const std::string& name, const SceneOverrides& overrides, const World& world, const Terrain& terrain) {
  const auto preset =
      std::find_if(std::begin(kPresets), std::end(kPresets), [&](const Preset& p) { return name == p.name; });
  if (preset == std::end(kPresets)) throw std::invalid_argument("unknown scene \"" + name + "\"");

  Scene scene;
  scene.name = name;
  scene.exposure_ev = preset->exposure_ev;
  const double altitude_m = overrides.camera_altitude_m.value_or(preset->camera_altitude_m);
  const double look_azimuth = overrides.look_azimuth_deg.value_or(preset->look_azimuth_deg);
  const double look_elevation = overrides.look_elevation_deg.value_or(preset->look_elevation_deg);

  // The sun's direction is given in the local frame of the patch centre.
  const LocalFrame centre_frame = world.local_frame({0.0, 0.0});
  scene.sun_direction = centre_frame.direction(overrides.sun_azimuth_deg.value_or(preset->sun_azimuth_deg),
                                               overrides.sun_elevation_deg.value_or(preset->sun_elevation_deg));

  Camera& camera = scene.camera;
  camera.fov_deg = overrides.fov_deg.value_or(preset->fov_deg);
  const double altitude = altitude_m * kUnitsPerMetre;
  if (preset->aim_at_patch_centre) {
    // Solve the triangle (planet centre O, camera C, patch centre P): the
    // ray from C to P leaves C at angle a from the nadir (the preset's aim
    // elevation, towards its look azimuth) and meets the sphere of radius R
    // at P; the law of sines gives the angle at P, hence the central angle
    // between C and P. If that ray would miss the planet (a higher camera
    // from --camera-altitude), the camera stands right above the patch.
    // --look then only turns the camera.
    const double R = world.planet_radius(), rc = R + altitude;
    const double a = glm::radians(90.0 + preset->aim_elevation_deg);
    const double s = rc * std::sin(a) / R;
    double central_angle = 0.0;
    if (s <= 1.0) central_angle = std::asin(s) - a;  // = pi - a - (pi - asin(s))
    // Back from the patch centre, opposite to the aim's azimuth.
    const glm::dvec3 back = centre_frame.direction(preset->look_azimuth_deg + 180.0, 0.0);
    const glm::dvec3 radial = std::cos(central_angle) * centre_frame.up + std::sin(central_angle) * back;
    camera.position = world.planet_centre() + rc * radial;
  } else {
    const glm::dvec2 patch(terrain.valley_centre_km(preset->camera_north_km) + preset->camera_east_of_valley_km,
                           preset->camera_north_km);
    camera.position = world.surface_point(patch, terrain.height_km(patch)) + world.local_frame(patch).up * altitude;
  }
  // The look direction in the local frame of the point below the camera.
  const glm::dvec3 up = glm::normalize(camera.position - world.planet_centre());
  const glm::dvec3 east_hint = std::abs(up.x) < 0.99 ? glm::dvec3(1.0, 0.0, 0.0) : glm::dvec3(0.0, 0.0, 1.0);
  LocalFrame camera_frame;
  camera_frame.up = up;
  camera_frame.east = glm::normalize(east_hint - glm::dot(east_hint, up) * up);
  camera_frame.north = glm::cross(up, camera_frame.east);
  camera.forward = camera_frame.direction(look_azimuth, look_elevation);
  // Looking straight up or down the image's top is towards the look azimuth.
  const glm::dvec3 up_hint = std::abs(look_elevation) > 89.9 ? camera_frame.direction(look_azimuth, 0.0) : up;
  camera.up = glm::normalize(glm::cross(glm::cross(camera.forward, up_hint), camera.forward));

  for (const Placement& p : kPlacements) scene.objects.push_back(place(p, world, terrain));

  // Near plane: a quarter of the height above the ground, so that nothing
  // in view is clipped while standard depth keeps its precision; far plane:
  // just beyond the farthest corner of the terrain's bounding box (objects
  // included: they stand within it and are lower than 1 km). Beyond it only
  // the plugin's sphere, sky and space remain.
  camera.near = std::clamp(0.25 * altitude, 0.1 * kUnitsPerMetre, 100e3 * kUnitsPerMetre);
  const glm::dvec3 lo = world.patch_centre() + terrain.bounds_min();
  const glm::dvec3 hi = world.patch_centre() + terrain.bounds_max() + glm::dvec3(0.0, kUnitsPerKm, 0.0);
  double farthest = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 p((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z);
    farthest = std::max(farthest, glm::length(p - camera.position));
  }
  camera.far = std::max(1.1 * farthest, 2.0 * camera.near);
  return scene;
}

}  // namespace engine
