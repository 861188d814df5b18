// Pixel rays of a GlobeView (world = planet-centred metres) and whether they
// meet a sphere: where a ray meets a sphere below all of the relief, the
// globe must have drawn something (the hole tests of globe_test.cpp and
// globe_streaming_test.cpp).
#pragma once

#include <glm/geometric.hpp>
#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include "atmos/globe.hpp"

namespace atmos_test {

// The ray through pixel (x, y) of `view` (world = planet-centred metres here).
inline glm::dvec3 pixel_ray(const atmos::GlobeView& view, int x, int y) {
  const glm::dmat4 inverse = glm::inverse(view.projection * view.view);
  const double nx = (x + 0.5) / view.width * 2.0 - 1.0, ny = (y + 0.5) / view.height * 2.0 - 1.0;
  const glm::dvec4 near = inverse * glm::dvec4(nx, ny, 1.0, 1.0), far = inverse * glm::dvec4(nx, ny, 0.5, 1.0);
  return glm::normalize(glm::dvec3(far) / far.w - glm::dvec3(near) / near.w);
}

// Whether the ray from `origin` along the unit `ray` meets the sphere of
// `radius` about the origin of the frame (always, from inside it).
inline bool ray_hits_sphere(const glm::dvec3& origin, const glm::dvec3& ray, double radius) {
  const double b = glm::dot(origin, ray);
  const double c = glm::dot(origin, origin) - radius * radius;
  if (c < 0.0) return true;
  return b < 0.0 && b * b - c >= 0.0;
}

}  // namespace atmos_test
