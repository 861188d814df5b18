#include "planet/globe_shadows.hpp"

#include <glm/geometric.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace atmos::planet {

namespace {

// x rounded down (up) to a power of 2^(1/steps).
double quantise_down(double x, int steps) { return std::exp2(std::floor(std::log2(x) * steps) / steps); }
double quantise_up(double x, int steps) { return std::exp2(std::ceil(std::log2(x) * steps) / steps); }

}  // namespace

ShadowLight shadow_light(const glm::dvec3& sun) {
  ShadowLight light;
  light.z = glm::normalize(sun);
  // Any axis not too close to the sun's: the planet's z, else its x. The
  // frame turns only with the sun, never with the camera.
  const glm::dvec3 reference = std::abs(light.z.z) < 0.9 ? glm::dvec3(0.0, 0.0, 1.0) : glm::dvec3(1.0, 0.0, 0.0);
  light.x = glm::normalize(glm::cross(reference, light.z));
  light.y = glm::cross(light.z, light.x);
  return light;
}

std::vector<double> practical_splits(double near_m, double far_m, int count, double lambda) {
  std::vector<double> c(std::size_t(count + 1));
  for (int i = 0; i <= count; ++i) {
    const double s = double(i) / double(count);
    const double logarithmic = near_m * std::pow(far_m / near_m, s);
    const double uniform = near_m + (far_m - near_m) * s;
    c[std::size_t(i)] = lambda * logarithmic + (1.0 - lambda) * uniform;
  }
  c.front() = near_m;
  c.back() = far_m;
  return c;
}

std::vector<ShadowCascade> fit_shadow_cascades(const ShadowView& view, const ShadowLight& light, int count,
                                               int map_size) {
  std::vector<ShadowCascade> cascades;
  const double near = quantise_down(std::max(view.nearest_depth_m, 1e-3), 4);
  const double far = view.shadow_distance_m;
  if (!(near < far) || count < 1) return cascades;
  const std::vector<double> splits = practical_splits(near, far, count, kSplitLambda);
  // The frustum's axis (through the centres of its cross-sections) and the
  // half-widths of a cross-section, per unit of depth.
  const double cx = 0.5 * (view.x_min + view.x_max), cy = 0.5 * (view.y_min + view.y_max);
  const double ax = 0.5 * (view.x_max - view.x_min), ay = 0.5 * (view.y_max - view.y_min);
  const double k2 = ax * ax + ay * ay;
  double previous_blend_start = near;
  for (int i = 0; i < count; ++i) {
    ShadowCascade c;
    c.near_depth_m = i == 0 ? near : previous_blend_start;
    c.far_depth_m = splits[std::size_t(i + 1)];
    c.blend_start_m = c.far_depth_m - kCascadeBlendFraction * (c.far_depth_m - splits[std::size_t(i)]);
    previous_blend_start = c.blend_start_m;
    // The slice's bounding sphere, centred on the axis at depth t. For a
    // symmetric frustum (cx = cy = 0) the sphere through the corners of
    // both cross-sections, (t - a)^2 + a^2 k^2 = (t - b)^2 + b^2 k^2,
    // is centred at t = (a + b)(1 + k^2) / 2; beyond b the far section's
    // circumscribed circle is smaller. The radius is measured to all
    // eight corners, which also covers a skewed frustum; it depends on the
    // slice alone, not on where the camera looks (Valient 2008).
    const double a = c.near_depth_m, b = c.far_depth_m;
    const double t = std::min(b, 0.5 * (a + b) * (1.0 + k2));
    double radius2 = 0.0;
    for (const double d : {a, b})
      for (const double sx : {view.x_min, view.x_max})
        for (const double sy : {view.y_min, view.y_max}) {
          const glm::dvec3 e(sx * d - cx * t, sy * d - cy * t, d - t);
          radius2 = std::max(radius2, glm::dot(e, e));
        }
    c.radius_m = quantise_up(std::sqrt(radius2), 16);
    c.centre = view.camera + view.right * (cx * t) + view.up * (cy * t) + view.forward * t;
    // The box: the sphere plus a margin of one texel, so that the box's
    // centre can move to the nearest texel corner and still hold the
    // sphere: h = r + 2 h / size.
    c.half_size_m = c.radius_m / (1.0 - 2.0 / double(map_size));
    c.texel_m = 2.0 * c.half_size_m / double(map_size);
    // Snapped to whole texels of the light frame (map_size is even, so the
    // box's corner is a whole number of texels from the planet's centre
    // too): a camera that moves by less than a texel moves no texel.
    const glm::dvec2 centre_light(glm::dot(c.centre, light.x), glm::dot(c.centre, light.y));
    c.box_centre = glm::dvec2(std::round(centre_light.x / c.texel_m), std::round(centre_light.y / c.texel_m)) *
                   c.texel_m;
    const double z = glm::dot(c.centre, light.z);
    c.z_far_m = z - c.half_size_m;
    c.z_near_m = z + c.half_size_m;
    cascades.push_back(c);
  }
  return cascades;
}

double sun_shell_distance_m(const glm::dvec3& centre, double radius_m, const glm::dvec3& sun, double inner_radius_m,
                            double outer_radius_m) {
  // Along p + t s from a point p at radius rho with b = p.s, the radius is
  // sqrt(rho^2 + 2 b t + t^2); it is below outer radius R up to
  // t = -b + sqrt(b^2 + R^2 - rho^2), which decreases with b and with rho:
  // the smallest b and rho of the sphere bound it.
  const double b = glm::dot(centre, sun) - radius_m;
  const double rho = std::max(glm::length(centre) - radius_m, inner_radius_m);
  const double k = (outer_radius_m - rho) * (outer_radius_m + rho);  // R^2 - rho^2, without cancellation
  const double discriminant = b * b + k;
  if (discriminant < 0.0) return 0.0;
  const double root = std::sqrt(discriminant);
  // -b + root, written without cancellation when b > 0.
  const double t = b > 0.0 ? k / (b + root) : root - b;
  return std::max(t, 0.0);
}

void extend_towards_sun(ShadowCascade& cascade, double caster_top_z_m, double shell_m) {
  // The far plane stays where the fit put it, half a box below the
  // sphere's centre.
  const double own = cascade.z_far_m + 2.0 * cascade.half_size_m;
  const double limit = cascade.z_far_m + cascade.half_size_m + cascade.radius_m + shell_m;
  cascade.z_near_m = std::max(own, std::min(caster_top_z_m, limit));
}

namespace {

// The convex hull of points, counter-clockwise (Andrew's monotone chain:
// the lower hull left to right, then the upper one back).
std::vector<glm::dvec2> convex_hull(std::vector<glm::dvec2> points) {
  if (points.size() < 3) return points;
  std::sort(points.begin(), points.end(),
            [](const glm::dvec2& a, const glm::dvec2& b) { return a.x < b.x || (a.x == b.x && a.y < b.y); });
  const auto cross = [](const glm::dvec2& o, const glm::dvec2& a, const glm::dvec2& b) {
    return (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x);
  };
  std::vector<glm::dvec2> hull(2 * points.size());
  size_t k = 0;
  for (size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  for (size_t i = points.size() - 1, lower = k + 1; i-- > 0;) {
    while (k >= lower && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k > 1 ? k - 1 : k);
  return hull;
}

}  // namespace

ShadowFootprint shadow_footprint(const ShadowView& view, const ShadowLight& light, double near_depth_m,
                                 double far_depth_m) {
  ShadowFootprint f;
  std::vector<glm::dvec2> points;
  f.min_z_m = INFINITY;
  f.max_z_m = -INFINITY;
  for (const double d : {near_depth_m, far_depth_m})
    for (const double sx : {view.x_min, view.x_max})
      for (const double sy : {view.y_min, view.y_max}) {
        const glm::dvec3 p = view.camera + view.forward * d + view.right * (sx * d) + view.up * (sy * d);
        points.emplace_back(glm::dot(p, light.x), glm::dot(p, light.y));
        const double z = glm::dot(p, light.z);
        f.min_z_m = std::min(f.min_z_m, z);
        f.max_z_m = std::max(f.max_z_m, z);
      }
  f.hull = convex_hull(points);
  return f;
}

ShadowFootprint sphere_footprint(const ShadowLight& light, const std::vector<glm::dvec4>& spheres) {
  ShadowFootprint f;
  std::vector<glm::dvec2> points;
  f.min_z_m = INFINITY;
  f.max_z_m = -INFINITY;
  for (const glm::dvec4& s : spheres) {
    const glm::dvec3 c(s);
    const glm::dvec2 xy(glm::dot(c, light.x), glm::dot(c, light.y));
    for (const double dx : {-s.w, s.w})
      for (const double dy : {-s.w, s.w}) points.push_back(xy + glm::dvec2(dx, dy));
    const double z = glm::dot(c, light.z);
    f.min_z_m = std::min(f.min_z_m, z - s.w);
    f.max_z_m = std::max(f.max_z_m, z + s.w);
  }
  f.hull = convex_hull(points);
  return f;
}

bool may_cast_onto(const ShadowFootprint& footprint, const ShadowLight& light, const glm::dvec3& centre,
                   double radius_m, double margin_m, double shell_m) {
  const double z = glm::dot(centre, light.z);
  if (z + radius_m < footprint.min_z_m || z - radius_m > footprint.max_z_m + shell_m) return false;
  const glm::dvec2 c(glm::dot(centre, light.x), glm::dot(centre, light.y));
  const double reach = radius_m + margin_m;
  const std::vector<glm::dvec2>& h = footprint.hull;
  if (h.size() < 3) return true;  // a degenerate hull: keep everything
  bool inside = true;
  for (size_t i = 0; i < h.size(); ++i) {
    const glm::dvec2 a = h[i], b = h[(i + 1) % h.size()];
    const glm::dvec2 edge = b - a, to = c - a;
    if (edge.x * to.y - edge.y * to.x < 0.0) inside = false;
    // The distance from the centre to the edge's segment.
    const double t = std::clamp(glm::dot(to, edge) / std::max(glm::dot(edge, edge), 1e-300), 0.0, 1.0);
    if (glm::length(to - edge * t) <= reach) return true;
  }
  return inside;
}

glm::dmat4 cascade_clip_from_planet(const ShadowLight& light, const ShadowCascade& cascade) {
  // x_clip = (p.x_l - box_x) / h, y_clip likewise, and
  // z_clip = (z_near + z_far - 2 p.z_l) / (z_near - z_far).
  const double h = cascade.half_size_m;
  const double depth = cascade.z_near_m - cascade.z_far_m;
  glm::dmat4 m(0.0);
  for (int j = 0; j < 3; ++j) {
    m[j][0] = light.x[j] / h;
    m[j][1] = light.y[j] / h;
    m[j][2] = -2.0 * light.z[j] / depth;
  }
  m[3][0] = -cascade.box_centre.x / h;
  m[3][1] = -cascade.box_centre.y / h;
  m[3][2] = (cascade.z_near_m + cascade.z_far_m) / depth;
  m[3][3] = 1.0;
  return m;
}

}  // namespace atmos::planet
