#include "planet/tile_selection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "atmos/atmosphere.hpp"

namespace atmos::planet {
namespace {

constexpr double kUnbounded = std::numeric_limits<double>::infinity();

bool finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

double dot(const glm::dvec3& a, const glm::dvec3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

glm::dvec3 to_vec(const std::array<int, 3>& a) { return glm::dvec3(double(a[0]), double(a[1]), double(a[2])); }

void validate(const LodCamera& camera, const LodSettings& settings, const ReliefBounds& bounds) {
  if (!finite(camera.position)) throw Error("select_tiles: the camera position is not finite");
  if (!finite(camera.view_projection)) throw Error("select_tiles: the view-projection matrix is not finite");
  if (!std::isfinite(camera.viewport_height_px) || camera.viewport_height_px <= 0.0)
    throw Error("select_tiles: the viewport height must be a positive number of pixels");
  if (!std::isfinite(camera.tan_half_fov_y) || camera.tan_half_fov_y <= 0.0)
    throw Error("select_tiles: tan_half_fov_y must be positive and finite");
  if (!std::isfinite(settings.max_screen_error_px) || settings.max_screen_error_px <= 0.0)
    throw Error("select_tiles: max_screen_error_px must be positive and finite");
  const int q = settings.tile_quads;
  if (q < 2 || q > 4096 || (q & (q - 1)) != 0)
    throw Error("select_tiles: tile_quads must be a power of two in 2..4096, not " + std::to_string(q));
  if (settings.max_level < 0 || settings.max_level > kMaxTileLevel)
    throw Error("select_tiles: max_level must be in 0.." + std::to_string(kMaxTileLevel));
  if (!std::isfinite(settings.finest_spacing_m) || settings.finest_spacing_m < 0.0)
    throw Error("select_tiles: finest_spacing_m must be finite and not negative");
  if (!(settings.morph_start_fraction > 0.0 && settings.morph_start_fraction < 1.0))
    throw Error("select_tiles: morph_start_fraction must be in (0, 1)");
  if (!std::isfinite(settings.max_tile_relief_ratio) || settings.max_tile_relief_ratio < 0.0)
    throw Error("select_tiles: max_tile_relief_ratio must be finite and not negative");
  if (!std::isfinite(bounds.radius_m) || bounds.radius_m <= 0.0)
    throw Error("select_tiles: the planet radius must be positive and finite");
  if (!std::isfinite(bounds.min_height_m) || !std::isfinite(bounds.max_height_m) ||
      bounds.min_height_m > bounds.max_height_m || bounds.radius_m + bounds.min_height_m <= 0.0)
    throw Error("select_tiles: the planet's height range must be finite, ordered and above the centre");
  if (!bounds.error_m) throw Error("select_tiles: ReliefBounds::error_m is not set");
}

double checked_error(const ReliefBounds& bounds, double spacing_m) {
  const double e = bounds.error_m(spacing_m);
  if (!std::isfinite(e) || e < 0.0) throw Error("select_tiles: ReliefBounds::error_m returned a negative or non-finite error");
  return e;
}

double highest_radius(const ReliefBounds& b) { return b.radius_m + std::max(b.max_height_m, 0.0); }

// The tile's footprint: corner directions (s, t) = (0,0), (1,0), (1,1),
// (0,1), tan of its equal-angle bounds on the face, the face's axes N, U, V
// and the unit normals of its edges' great-circle planes: the edge u = u0
// lies in the plane of normal U - tan(a0) N (it holds V and
// N + tan(a0) U), likewise for u1, v0 (V - tan(b0) N) and v1.
struct Footprint {
  glm::dvec3 corner[4];
  // The normalised sum of the corners: the axis of its bounding sphere
  // and occludee point (any direction inside the footprint serves; the
  // farthest point of the footprint from it in angle is a corner).
  glm::dvec3 centre;
  double tan_u0, tan_u1, tan_v0, tan_v1;
  glm::dvec3 n, u, v;
  glm::dvec3 edge_u0, edge_u1, edge_v0, edge_v1;
};

glm::dvec3 unit(const glm::dvec3& a) { return a / std::sqrt(dot(a, a)); }

Footprint footprint(const TileKey& key) {
  Footprint f;
  const double scale = std::ldexp(1.0, -key.level);
  f.tan_u0 = equal_angle_tan(2.0 * (double(key.x) * scale) - 1.0);
  f.tan_u1 = equal_angle_tan(2.0 * (double(key.x + 1) * scale) - 1.0);
  f.tan_v0 = equal_angle_tan(2.0 * (double(key.y) * scale) - 1.0);
  f.tan_v1 = equal_angle_tan(2.0 * (double(key.y + 1) * scale) - 1.0);
  const FaceFrame& frame = face_frame(key.face);
  f.n = to_vec(frame.normal);
  f.u = to_vec(frame.u_axis);
  f.v = to_vec(frame.v_axis);
  // The equal-angle cube's direction at gnomonic coordinates (x, y) on the
  // face: N + x U + y V, normalised (tile_direction, to rounding).
  f.corner[0] = unit(f.n + f.tan_u0 * f.u + f.tan_v0 * f.v);
  f.corner[1] = unit(f.n + f.tan_u1 * f.u + f.tan_v0 * f.v);
  f.corner[2] = unit(f.n + f.tan_u1 * f.u + f.tan_v1 * f.v);
  f.corner[3] = unit(f.n + f.tan_u0 * f.u + f.tan_v1 * f.v);
  f.centre = unit(f.corner[0] + f.corner[1] + f.corner[2] + f.corner[3]);
  f.edge_u0 = unit(f.u - f.tan_u0 * f.n);
  f.edge_u1 = unit(f.u - f.tan_u1 * f.n);
  f.edge_v0 = unit(f.v - f.tan_v0 * f.n);
  f.edge_v1 = unit(f.v - f.tan_v1 * f.n);
  return f;
}

// Squared chord, on the unit sphere, from the unit vector `c` to the
// nearest point of the footprint. Inside the footprint (c.N > 0, its
// gnomonic coordinates x = c.U / c.N, y = c.V / c.N within the tile's tan
// bounds) the chord is 0; outside, the nearest point is a corner or the
// projection of c on an edge's plane (unit normal m) when that falls within
// the edge, where |c - p/|p||^2 = 2 - 2|p| = 2 (c.m)^2 / (1 + sqrt(1 - (c.m)^2)).
double nearest_chord_squared(const glm::dvec3& c, const Footprint& f) {
  const double cn = dot(c, f.n), cu = dot(c, f.u), cv = dot(c, f.v);
  if (cn > 0.0) {
    const double x = cu / cn, y = cv / cn;
    if (x >= f.tan_u0 && x <= f.tan_u1 && y >= f.tan_v0 && y <= f.tan_v1) return 0.0;
  }
  double best = kUnbounded;
  for (const glm::dvec3& corner : f.corner) {
    const glm::dvec3 d = c - corner;
    best = std::min(best, dot(d, d));
  }
  // Edges at constant u (along v) and at constant v (along u).
  const auto edge = [&](const glm::dvec3& m, const glm::dvec3& along, double lo, double hi) {
    const double cm = dot(c, m);
    const glm::dvec3 p = c - cm * m;
    const double pn = dot(p, f.n);
    if (pn <= 0.0) return;
    const double t = dot(p, along) / pn;
    if (t < lo || t > hi) return;
    const double sin2 = std::min(cm * cm, 1.0);
    best = std::min(best, 2.0 * sin2 / (1.0 + std::sqrt(1.0 - sin2)));
  };
  edge(f.edge_u0, f.v, f.tan_v0, f.tan_v1);
  edge(f.edge_u1, f.v, f.tan_v0, f.tan_v1);
  edge(f.edge_v0, f.u, f.tan_u0, f.tan_u1);
  edge(f.edge_v1, f.u, f.tan_u0, f.tan_u1);
  return best;
}

// The camera (distance rho from the centre) to the nearest point at the
// angle whose chord is chi (chi^2 = 2 - 2 cos theta) between the radii
// [s_lo, s_hi]: d^2 = rho^2 + s^2 - 2 rho s cos theta = (rho - s)^2 +
// rho s chi^2, smallest at s = clamp(rho cos theta, s_lo, s_hi); written
// without the cancellation of 1 - cos theta at small angles.
double distance_at_chord(double rho, double chi2, double s_lo, double s_hi) {
  const double s = std::clamp(rho * (1.0 - 0.5 * chi2), s_lo, s_hi);
  return std::sqrt((rho - s) * (rho - s) + rho * s * chi2);
}

glm::dvec3 unit_or_pole(const glm::dvec3& p, double& length) {
  length = std::sqrt(dot(p, p));
  return length > 0.0 ? p / length : glm::dvec3(0.0, 0.0, 1.0);
}

// Ring 2013's occludee point in the space scaled by 1/r (the occluder a unit
// sphere), for points of magnitude rho at the corners: the point on the
// centre direction n at the magnitude 1 / cos(alpha + beta), alpha the
// angle of a corner from n, cos beta = 1 / rho (Cesium's
// EllipsoidalOccluder.computeHorizonCullingPoint). The farthest corner in
// angle gives the largest magnitude; every other point of the tile at that
// radius is nearer n in angle (the quad is the gnomonic image of a convex
// polygon, on which the cosine to n is quasi-concave), points below it have
// a smaller beta.
bool occludee(const glm::dvec3& centre, const Footprint& f, double max_radius_m, double occluder_radius_m,
              glm::dvec3& point) {
  const double rho = std::max(max_radius_m / occluder_radius_m, 1.0);
  const double cos_beta = 1.0 / rho, sin_beta = std::sqrt(std::max(1.0 - cos_beta * cos_beta, 0.0));
  double min_cos_alpha = 1.0;
  for (const glm::dvec3& corner : f.corner) min_cos_alpha = std::min(min_cos_alpha, dot(corner, centre));
  const double cos_alpha = std::clamp(min_cos_alpha, -1.0, 1.0);
  const double sin_alpha = std::sqrt(std::max(1.0 - cos_alpha * cos_alpha, 0.0));
  const double cos_sum = cos_alpha * cos_beta - sin_alpha * sin_beta;  // cos(alpha + beta)
  if (cos_sum <= 1e-9) return false;
  point = centre * (occluder_radius_m / cos_sum);
  return true;
}

// The largest n.p + w over the tile's points p = s u between the radii
// (u in the footprint, s in [s_lo, s_hi]), for a plane with |n| = 1: with
// m = max_u n.u = 1 - chi^2 / 2 (chi the chord from n to the footprint,
// nearest_chord_squared), s m is largest at s_hi when m >= 0 and at s_lo
// otherwise. The mesh's triangles are convex combinations of such points,
// so no point of them lies farther on the plane's positive side.
double plane_max(const glm::dvec4& plane, const Footprint& f, double s_lo, double s_hi) {
  const glm::dvec3 n(plane);
  const double m = 1.0 - 0.5 * nearest_chord_squared(n, f);
  return (m >= 0.0 ? s_hi : s_lo) * m + plane.w;
}

// `within`, when given, is set to whether the tile's bounding sphere lies
// wholly on the inner side of every plane (then so does every part of it).
bool culled(const glm::dvec3& camera, const std::array<glm::dvec4, 4>& planes, const Footprint& f, double s_lo,
            double s_hi, double occluder_radius, bool* within = nullptr) {
  const glm::dvec3& centre = f.centre;
  // Bounding sphere on the centre ray: the farthest points from it are
  // the corners (largest angle from the centre) at the lowest or highest
  // radius. A plane the sphere lies wholly outside culls the tile; one it
  // straddles is decided by the tile's own extent (plane_max), which the
  // sphere overstates most for tiles near the camera, whose planes pass
  // through it.
  const glm::dvec3 middle = centre * (0.5 * (s_lo + s_hi));
  double radius2 = 0.0;
  for (const glm::dvec3& corner : f.corner)
    for (const double s : {s_lo, s_hi}) {
      const glm::dvec3 d = corner * s - middle;
      radius2 = std::max(radius2, dot(d, d));
    }
  const double radius = std::sqrt(radius2) * (1.0 + 1e-12);
  if (within != nullptr) *within = true;
  for (const glm::dvec4& plane : planes) {
    const double centre_distance = dot(glm::dvec3(plane), middle) + plane.w;
    if (centre_distance < radius && within != nullptr) *within = false;
    if (centre_distance < -radius) return true;
    // Rounding of n.p and w, each up to about s_hi and |w|.
    const double tolerance = 1e-9 * (s_hi + std::abs(plane.w));
    if (centre_distance < radius && dot(glm::dvec3(plane), glm::dvec3(plane)) > 0.5 &&
        plane_max(plane, f, s_lo, s_hi) < -tolerance)
      return true;
  }
  glm::dvec3 point;
  if (occludee(centre, f, s_hi, occluder_radius, point) && horizon_hides(camera, occluder_radius, point)) return true;
  return false;
}

struct Traversal {
  glm::dvec3 camera;
  glm::dvec3 camera_direction;
  double camera_radius = 0.0;
  std::array<glm::dvec4, 4> planes;
  double occluder_radius = 0.0;
  std::vector<double> ranges;
  int finest = 0;
  double fraction = 0.7;
  const ReliefBounds* bounds = nullptr;
  const TileHeightRange* known = nullptr;
  Selection* out = nullptr;

  double far_distance(const Footprint& f, double s_lo, double s_hi) const {
    double far = 0.0;
    for (const glm::dvec3& corner : f.corner)
      for (const double s : {s_lo, s_hi}) far = std::max(far, std::sqrt(dot(corner * s - camera, corner * s - camera)));
    return far;
  }

  // The height range of child c of a tile of range [h_lo, h_hi].
  void child_range(const TileKey& c, double h_lo, double h_hi, double& lo, double& hi) const {
    lo = h_lo;
    hi = h_hi;
    if (*known && (*known)(c, lo, hi)) {
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi || bounds->radius_m + lo <= 0.0)
        throw Error("select_tiles: the height range of a tile is not finite and ordered");
    } else {
      lo = h_lo;
      hi = h_hi;
    }
  }

  double nearest(const Footprint& f, double s_lo, double s_hi) const {
    return distance_at_chord(camera_radius, nearest_chord_squared(camera_direction, f), s_lo, s_hi);
  }

  // CDLOD (Strugar 2009): a node nearer than the finer level's range is
  // refined, and each of its children is either in that range itself (it is
  // visited) or drawn as a quadrant of the node at the node's level. So a
  // selected tile of level L lies within r_L + D_L of the camera, the
  // bound the ranges' seam inequality is built on (level_ranges_m).
  // `f`: the tile's footprint, which the caller has already made.
  void visit(const TileKey& key, const Footprint& f, double h_lo, double h_hi) {
    ++out->nodes_visited;
    const double s_lo = bounds->radius_m + h_lo, s_hi = bounds->radius_m + h_hi;
    bool within = false;
    if (culled(camera, planes, f, s_lo, s_hi, occluder_radius, &within)) return;
    unsigned quadrants = 0xFu;
    if (key.level < finest && nearest(f, s_lo, s_hi) < ranges[std::size_t(key.level + 1)]) {
      quadrants = 0u;
      for (int q = 0; q < 4; ++q) {
        const TileKey c = child(key, q);
        double lo = 0.0, hi = 0.0;
        child_range(c, h_lo, h_hi, lo, hi);
        const Footprint cf = footprint(c);
        const double c_lo = bounds->radius_m + lo, c_hi = bounds->radius_m + hi;
        if (nearest(cf, c_lo, c_hi) < ranges[std::size_t(key.level + 1)]) {
          visit(c, cf, lo, hi);
        } else {
          // The quadrant shows this node's mesh: culled with its height range.
          ++out->nodes_visited;
          if (!culled(camera, planes, cf, s_lo, s_hi, occluder_radius)) quadrants |= 1u << q;
        }
      }
      if (quadrants == 0u) return;
    } else if (!within && key.level < kMaxTileLevel) {
      // Not refined, and a side plane crosses its bounding sphere: its
      // quadrants culled as a refined node's are, so that a tile the
      // frustum's edge crosses draws only the areas inside.
      quadrants = 0u;
      for (int q = 0; q < 4; ++q) {
        const TileKey c = child(key, q);
        if (!culled(camera, planes, footprint(c), s_lo, s_hi, occluder_radius)) quadrants |= 1u << q;
      }
      if (quadrants == 0u) return;
    }
    SelectedTile tile;
    tile.key = key;
    tile.min_height_m = h_lo;
    tile.max_height_m = h_hi;
    tile.quadrants = quadrants;
    if (key.level == 0) {
      tile.morph_start_m = tile.morph_end_m = kUnbounded;
    } else {
      tile.morph_end_m = ranges[std::size_t(key.level)];
      tile.morph_start_m = fraction * tile.morph_end_m;
      if (key.level >= 2 && far_distance(f, s_lo, s_hi) > fraction * ranges[std::size_t(key.level - 1)])
        ++out->tiles_beyond_morph_bound;
    }
    out->tiles.push_back(tile);
  }
};

}  // namespace

double level_spacing_m(int level, const LodSettings& settings, const ReliefBounds& bounds) {
  return highest_radius(bounds) * max_grid_edge_angle(level) / double(settings.tile_quads);
}

int finest_level(const LodSettings& settings, const ReliefBounds& bounds) {
  int level = 0;
  while (level < settings.max_level && level_spacing_m(level, settings, bounds) > settings.finest_spacing_m) ++level;
  return level;
}

double level_diameter_m(int level, const LodSettings& settings, const ReliefBounds& bounds) {
  // Two points of the tile at radii s1, s2 in [s_lo, s_hi] and an angle
  // whose chord is chi: |p1 - p2|^2 = (s1 - s2)^2 + s1 s2 chi^2
  // <= H^2 + (s_hi chi)^2, H the tile's relief.
  const double angle = std::min(max_tile_diagonal_angle(level), 3.14159265358979323846);
  const double footprint = highest_radius(bounds) * 2.0 * std::sin(0.5 * angle);
  const double relief =
      std::min(bounds.max_height_m - bounds.min_height_m, settings.max_tile_relief_ratio * footprint);
  return std::sqrt(footprint * footprint + relief * relief);
}

std::vector<double> level_ranges_m(const LodCamera& camera, const LodSettings& settings, const ReliefBounds& bounds) {
  validate(camera, settings, bounds);
  const int finest = finest_level(settings, bounds);
  const double k = camera.viewport_height_px / (2.0 * camera.tan_half_fov_y);
  const double f = settings.morph_start_fraction;
  std::vector<double> r(std::size_t(finest + 1), kUnbounded);
  double finer = 0.0;  // r_{L+1}, none below the finest level
  for (int level = finest; level >= 1; --level) {
    const double coarser = checked_error(bounds, level_spacing_m(level - 1, settings, bounds));
    const double own = checked_error(bounds, level_spacing_m(level, settings, bounds));
    const double by_error = std::max(coarser, own / f) * k / settings.max_screen_error_px;
    const double by_morph = level == finest ? 0.0 : (finer + level_diameter_m(level + 1, settings, bounds)) / f;
    r[std::size_t(level)] = std::max(by_error, by_morph);
    finer = r[std::size_t(level)];
  }
  return r;
}

double nearest_distance_m(const glm::dvec3& camera_m, const TileKey& key, double min_radius_m, double max_radius_m) {
  validate(key);
  double rho = 0.0;
  const glm::dvec3 dir = unit_or_pole(camera_m, rho);
  return distance_at_chord(rho, nearest_chord_squared(dir, footprint(key)), min_radius_m, max_radius_m);
}

std::array<glm::dvec4, 4> frustum_side_planes(const glm::dmat4& m) {
  // Row i of the matrix: (m[0][i], m[1][i], m[2][i], m[3][i]) (glm is
  // column-major). Inside: -w <= x <= w and -w <= y <= w.
  const auto row = [&](int i) { return glm::dvec4(m[0][i], m[1][i], m[2][i], m[3][i]); };
  std::array<glm::dvec4, 4> planes = {row(3) + row(0), row(3) - row(0), row(3) + row(1), row(3) - row(1)};
  for (glm::dvec4& p : planes) {
    const double n = std::sqrt(p.x * p.x + p.y * p.y + p.z * p.z);
    if (n > 0.0) p /= n;
  }
  return planes;
}

bool horizon_hides(const glm::dvec3& camera_m, double occluder_radius_m, const glm::dvec3& point) {
  // Ring 2013, in the space scaled by 1/r: v_h^2 = |c|^2 - 1 (the squared
  // distance to the horizon); the point q is hidden when it lies beyond the
  // horizon plane, -(q - c).c > v_h^2, and inside the horizon cone,
  // ((q - c).c)^2 / |q - c|^2 > v_h^2.
  const glm::dvec3 c = camera_m / occluder_radius_m;
  const double vh2 = dot(c, c) - 1.0;
  if (!(vh2 > 0.0)) return false;
  const glm::dvec3 vt = point / occluder_radius_m - c;
  const double vt_dot_vc = -dot(vt, c);
  return vt_dot_vc > vh2 && vt_dot_vc * vt_dot_vc / dot(vt, vt) > vh2;
}

bool horizon_occludee_point(const TileKey& key, double max_radius_m, double occluder_radius_m, glm::dvec3& point) {
  validate(key);
  const Footprint f = footprint(key);
  return occludee(f.centre, f, max_radius_m, occluder_radius_m, point);
}

double tile_plane_max_m(const glm::dvec4& plane, const TileKey& key, double min_radius_m, double max_radius_m) {
  validate(key);
  return plane_max(plane, footprint(key), min_radius_m, max_radius_m);
}

bool tile_culled(const glm::dvec3& camera_m, const std::array<glm::dvec4, 4>& planes, const TileKey& key,
                 double min_radius_m, double max_radius_m, double occluder_radius_m) {
  validate(key);
  return culled(camera_m, planes, footprint(key), min_radius_m, max_radius_m, occluder_radius_m);
}

Selection select_tiles(const LodCamera& camera, const LodSettings& settings, const ReliefBounds& bounds,
                       const TileHeightRange& known_range) {
  Selection selection;
  Traversal t;
  t.ranges = level_ranges_m(camera, settings, bounds);  // validates
  t.finest = int(t.ranges.size()) - 1;
  t.camera = camera.position;
  t.camera_direction = unit_or_pole(camera.position, t.camera_radius);
  t.planes = frustum_side_planes(camera.view_projection);
  t.occluder_radius = bounds.radius_m + bounds.min_height_m;
  t.fraction = settings.morph_start_fraction;
  t.bounds = &bounds;
  t.known = &known_range;
  t.out = &selection;
  for (int face = 0; face < 6; ++face) {
    const TileKey root{face, 0, 0, 0};
    double lo = bounds.min_height_m, hi = bounds.max_height_m;
    if (known_range && known_range(root, lo, hi)) {
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi || bounds.radius_m + lo <= 0.0)
        throw Error("select_tiles: the height range of a tile is not finite and ordered");
    } else {
      lo = bounds.min_height_m;
      hi = bounds.max_height_m;
    }
    t.visit(root, footprint(root), lo, hi);
  }
  return selection;
}

}  // namespace atmos::planet
