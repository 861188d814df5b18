// The sun's disc in a stereo eye's image: where the eye's four angles put a
// direction, and where the disc's light centres (stereo_test.cpp,
// xr_test.cpp).
#pragma once

#include <glm/geometric.hpp>
#include <glm/vec2.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "atmos/image.hpp"
#include "atmos/stereo.hpp"

namespace atmos_test {

// Where a direction falls in an eye's image: x to the right, y down from the
// top-left corner, in pixels (pixel centres at half-integers), from the
// eye's four angles alone.
inline glm::dvec2 image_position(const atmos::Eye& eye, const glm::dvec3& direction, int width, int height) {
  const glm::dvec3 forward = glm::normalize(eye.forward);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, eye.up));
  const glm::dvec3 up = glm::cross(right, forward);
  const double x = glm::dot(direction, right) / glm::dot(direction, forward);
  const double y = glm::dot(direction, up) / glm::dot(direction, forward);
  const double l = std::tan(eye.fov.left_rad), r = std::tan(eye.fov.right_rad);
  const double d = std::tan(eye.fov.down_rad), u = std::tan(eye.fov.up_rad);
  return {(x - l) / (r - l) * width, (u - y) / (u - d) * height};
}

// The centre of the sun's disc in an image (rows top first): the centroid
// of the luminance above 1 % of the brightest pixel's, less that 1 % (the
// disc is ~1e4 times brighter than the sky around it).
inline glm::dvec2 disc_centre(const std::vector<double>& luminance, int width, int height) {
  double peak = 0.0;
  for (double v : luminance) peak = std::max(peak, v);
  const double floor = 0.01 * peak;
  double sum = 0.0, sx = 0.0, sy = 0.0;
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const double w = luminance[size_t(y) * size_t(width) + size_t(x)] - floor;
      if (w <= 0.0) continue;
      sum += w;
      sx += w * (x + 0.5);
      sy += w * (y + 0.5);
    }
  return sum > 0.0 ? glm::dvec2(sx / sum, sy / sum) : glm::dvec2(-1.0);
}

// The luminance of a linear sRGB image (Rec. 709 weights), rows as the image's.
inline std::vector<double> luminance_of(const atmos::Image& image) {
  std::vector<double> l(size_t(image.width) * size_t(image.height));
  for (size_t i = 0; i < l.size(); ++i)
    l[i] = 0.2126 * image.rgb[3 * i] + 0.7152 * image.rgb[3 * i + 1] + 0.0722 * image.rgb[3 * i + 2];
  return l;
}

}  // namespace atmos_test
