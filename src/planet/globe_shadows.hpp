// Cascaded shadow maps (Williams 1978; Dimitrov 2007) of the sun for the
// globe: the view frustum near the camera cut into slices at the practical
// split scheme's distances (Zhang et al. 2006), each slice seen from the
// sun through an orthographic projection fitted to the slice's bounding
// sphere, its box snapped to whole texels of a light frame fixed to the
// planet and the sun (Valient 2008), so that the texel grid neither
// rotates nor swims with the camera. CPU only, double precision,
// planet-centred metres.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>

#include <vector>

namespace atmos::planet {

inline constexpr int kMaxShadowCascades = 4;

// The fraction of each cascade's depth range, at its far end, over which
// it hands over to the next one (or fades out, for the last).
inline constexpr double kCascadeBlendFraction = 0.1;

// The weight of the logarithmic split in the practical split scheme (Zhang
// et al. 2006): 1 is the logarithmic split (constant texels per pixel
// for surfaces facing the camera), 0 the uniform one. Close to 1: the
// shadows reach tens of kilometres from a camera that may be a metre above
// the ground.
inline constexpr double kSplitLambda = 0.98;

// The view the cascades serve.
struct ShadowView {
  glm::dvec3 camera{0.0};            // planet-centred m
  glm::dvec3 right{1.0, 0.0, 0.0};   // the view's axes in the planet's axes (unit, orthogonal)
  glm::dvec3 up{0.0, 1.0, 0.0};
  glm::dvec3 forward{0.0, 0.0, -1.0};  // the view axis (view depth d = dot(p - camera, forward))
  // The frustum's side planes as slopes: x / d in [x_min, x_max] and
  // y / d in [y_min, y_max] (x, y along right and up).
  double x_min = -1.0, x_max = 1.0, y_min = -1.0, y_max = 1.0;
  glm::dvec3 sun{0.0, 0.0, 1.0};  // unit, towards the sun
  // View depth where the first cascade starts: nothing drawn is nearer
  // (m, > 0); quantised down by fit_shadow_cascades.
  double nearest_depth_m = 1.0;
  double shadow_distance_m = 20e3;  // view depth where shadows end, m
};

// The sun's frame, the same for every cascade and every camera: z towards
// the sun, x and y across it, origin at the planet's centre.
struct ShadowLight {
  glm::dvec3 x{1.0, 0.0, 0.0}, y{0.0, 1.0, 0.0}, z{0.0, 0.0, 1.0};
};
ShadowLight shadow_light(const glm::dvec3& sun);

struct ShadowCascade {
  // The view depths it serves, m: from near_depth_m (which includes the
  // previous cascade's hand-over band) to far_depth_m; from blend_start_m
  // on it hands over to the next cascade (or fades out).
  double near_depth_m = 0.0, blend_start_m = 0.0, far_depth_m = 0.0;
  glm::dvec3 centre{0.0};  // the slice's bounding sphere: planet-centred m
  double radius_m = 0.0;   // quantised up to a step of 2^(1/16)
  double half_size_m = 0.0;     // half the side of the light box, m
  double texel_m = 0.0;         // 2 half_size / map size
  glm::dvec2 box_centre{0.0};   // in the light's x and y, m: a whole number of texels
  // The light box's depth along the light's z (towards the sun), m:
  // z_far_m (away from the sun) < z_near_m.
  double z_far_m = 0.0, z_near_m = 0.0;
};

// The cascades of a view: `count` (1..kMaxShadowCascades) slices of the
// view depths [nearest, shadow distance], the nearest depth quantised down
// to a step of 2^(1/4) (so that the splits, and with them the boxes' sizes,
// change only in steps as the camera moves). Empty when the nearest depth
// is at or beyond the shadow distance. The boxes' depth ranges span the
// slices' spheres; extend_towards_sun extends them to the casters.
std::vector<ShadowCascade> fit_shadow_cascades(const ShadowView& view, const ShadowLight& light, int count,
                                               int map_size);

// The split distances of the practical split scheme (Zhang et al. 2006):
// C_i = lambda n (f / n)^(i / N) + (1 - lambda) (n + (f - n) i / N),
// i = 0..N.
std::vector<double> practical_splits(double near_m, double far_m, int count, double lambda);

// How far towards the sun from any point of the sphere (centre, radius)
// above inner_radius_m the sun's ray may still meet ground no higher than
// outer_radius_m (planet-centred m): the depth a caster may lie in front of
// the slice.
double sun_shell_distance_m(const glm::dvec3& centre, double radius_m, const glm::dvec3& sun, double inner_radius_m,
                            double outer_radius_m);

// Moves the box's near plane (towards the sun) to caster_top_z_m, the
// light-z of the highest caster over the box, within [the slice's own
// near plane, the slice's sphere + shell_m].
void extend_towards_sun(ShadowCascade& cascade, double caster_top_z_m, double shell_m);

// What of the light's box can shadow a part of the view frustum: the
// frustum between two view depths seen along the sun (the convex hull of
// its eight corners in the light's x and y), and the corners' lowest and
// highest light z (towards the sun).
struct ShadowFootprint {
  std::vector<glm::dvec2> hull;  // counter-clockwise
  double min_z_m = 0.0, max_z_m = 0.0;
};
ShadowFootprint shadow_footprint(const ShadowView& view, const ShadowLight& light, double near_depth_m,
                                 double far_depth_m);

// The same for spheres (xyz: planet-centred centre, m; w: radius, m)
// holding the receivers, e.g. the drawn tiles of a frustum part: the hull
// of the squares around their discs across the sun.
ShadowFootprint sphere_footprint(const ShadowLight& light, const std::vector<glm::dvec4>& spheres);

// Whether a sphere (centre in planet-centred m) may hold a caster of the
// footprint's frustum part: it overlaps the hull across the sun, within
// margin_m, and lies between the part's lowest point and shell_m beyond its
// highest, along the sun. Conservative: false only when no ray from a point
// of the part towards the sun, up to shell_m past the part, meets the
// sphere (within margin_m across it).
bool may_cast_onto(const ShadowFootprint& footprint, const ShadowLight& light, const glm::dvec3& centre,
                   double radius_m, double margin_m, double shell_m);

// Planet-centred metres -> the cascade's clip space: x, y in [-1, 1] over
// the box, z from -1 at the near plane (towards the sun) to +1 at the far
// plane (OpenGL's standard depth, window depth 0.5 z + 0.5). Affine.
glm::dmat4 cascade_clip_from_planet(const ShadowLight& light, const ShadowCascade& cascade);

}  // namespace atmos::planet
