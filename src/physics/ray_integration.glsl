// atmos — integrals along a ray: quadrature nodes placed by an importance
// density (the extinction, or the single-scattering integrand itself), single
// scattering summed over them with the moons' shadows, and the dimming of the
// diffuse light under an eclipse. The precomputation and the renderers'
// low-sun path build on it.
//
// Needs: eclipse.glsl, table_lookups.glsl (and the parts it needs).

// Number of Simpson intervals along a ray for single scattering (whose
// integrand has the sharp edge of the planet's shadow) and for multiple
// scattering (smooth).
#define SINGLE_SCATTERING_INTERVALS 32
#define MULTIPLE_SCATTERING_INTERVALS 16
#define MAX_RAY_NODES 41
// Cells of the piecewise-linear importance density that places the nodes.
#define RAY_MAP_CELLS 128
// The run-time integration of single scattering (scattering_along_ray):
// fewer nodes, placed by the integrand itself (sunlit_ray_map).
#define RUNTIME_SINGLE_SCATTERING_INTERVALS 16
#define RUNTIME_RAY_MAP_CELLS 32
// Array capacities of RayMap and RayNodes: the precomputation's sizes, unless
// RAY_ARRAYS_FOR_RUNTIME is defined (the shaders, which only run the run-time
// integration: every fragment holds these arrays in private memory, and a
// software rasteriser spends more time on 129-element arrays than on the
// integration itself). The integration does not depend on the capacity.
#ifdef RAY_ARRAYS_FOR_RUNTIME
#define RAY_MAP_CAPACITY RUNTIME_RAY_MAP_CELLS
#define RAY_NODES_CAPACITY (RUNTIME_SINGLE_SCATTERING_INTERVALS + 1)
#else
#define RAY_MAP_CAPACITY RAY_MAP_CELLS
#define RAY_NODES_CAPACITY MAX_RAY_NODES
#endif
// Share of the nodes of the sunlit map spread uniformly (see sunlit_ray_map).
#ifndef SUNLIT_FLOOR_FRACTION
#define SUNLIT_FLOOR_FRACTION 0.1f
#endif

// Simpson's rule weight of node i of n intervals of width dt (n even).
INLINE float simpson_weight(int i, int n, float dt) {
  float w = (i == 0 || i == n) ? 1.0f : ((i % 2 == 1) ? 4.0f : 2.0f);
  return w * dt / 3.0f;
}

// Quadrature nodes of an integral along the ray (r, mu) from its start to
// distance d, with the transmittance from the start folded into the weights:
//   ∫ T(x, x + t v) f(t) dt ≈ Σ_i weight_i f(t_i).
// Uniform nodes would waste most of their samples: the scattering medium can
// be much thinner than the ray (a 1.2 km aerosol layer under a 100 km
// atmosphere: Simpson's rule on 40 uniform intervals overestimates it by
// 6 %), and in twilight only a short, high stretch of the ray is sunlit. So
// the nodes are placed at equal steps of the cumulative integral of an
// importance density w(t) plus a uniform floor: with t = t(s) and
// dt/ds = W / w(t), the integrand in s is f / w, which is smooth wherever f
// follows w. w is piecewise linear on `cells` (<= RAY_MAP_CAPACITY) equal cells,
// and t(s) inverts its exact (piecewise quadratic) integral, so that dt/ds is
// the true derivative of the map. Two importance densities:
//  - extinction_ray_map: the extinction times the transmittance from the
//    start, for integrands that follow the medium whatever the sun (the
//    precomputation, which shares the nodes of a view ray between all sun
//    directions);
//  - sunlit_ray_map: the single-scattering integrand itself (scattering
//    coefficient x transmittance from the start x transmittance to the sun),
//    which follows the planet's shadow and the reddened grazing sunlight.
//    Its transmittance to the sun is transmittance_to_sun_estimate (one
//    lookup per cell instead of one per point of the solar disc): the
//    density's shape is what places the nodes, and the nodes weigh the
//    exact transmittance_to_sun.
struct RayNodes {
  int count;
  float t[RAY_NODES_CAPACITY];
  vec3 weight[RAY_NODES_CAPACITY];
};

struct RayMap {
  int cells;
  float cell;  // cell length, m
  float w[RAY_MAP_CAPACITY + 1];
  // The extinction at the cell boundaries and the optical depth from the
  // start to them (exponential_segment_integral), which give the
  // transmittance at the nodes too.
  vec3 extinction[RAY_MAP_CAPACITY + 1];
  vec3 optical_depth[RAY_MAP_CAPACITY + 1];
};

// The integral over [0, h] of the exponential through (0, a) and (h, b),
// per component: h (b - a) / ln(b / a). Exact for extinctions and
// single-scattering integrands along a steep ray, where the density of each
// constituent falls exponentially with the distance; for grazing rays the
// exponent bends with the ray's curvature (relative error ~h² / (8 R H) in
// the exponent: 0.5 % over 18 km for a 1.2 km scale height). Used by the
// ray maps below and by the plugin's aerial-perspective march
// (gpu/composite.glsl). Where a and b are nearly equal
// (the limit, without 0 / 0) or one is zero (the edge of the planet's
// shadow: no exponential passes through a zero), the trapezoid.
INLINE vec3 exponential_segment_integral(vec3 a, vec3 b, float h) {
  vec3 trapezoid = 0.5f * h * (a + b);
  vec3 q = log(max(b, vec3(1e-30f)) / max(a, vec3(1e-30f)));
  vec3 exponential = h * (b - a) / max(abs(q), vec3(1e-3f)) * sign(q);
  vec3 use = vec3(greaterThan(abs(q), vec3(1e-3f))) * vec3(greaterThan(min(a, b), vec3(1e-30f)));
  return mix(trapezoid, exponential, use);
}

// The exponential through (0, a) and (1, b) at f in [0, 1], per component
// (linear where an end is zero, as exponential_segment_integral).
INLINE vec3 exponential_interpolation(vec3 a, vec3 b, float f) {
  vec3 ratio = max(b, vec3(1e-30f)) / max(a, vec3(1e-30f));
  vec3 use = vec3(greaterThan(min(a, b), vec3(1e-30f)));
  return mix(mix(a, b, f), a * pow(ratio, vec3(f)), use);
}

// The ray maps take the extinction as exponential within a cell, not linear:
// along a slanted ray the altitude grows about linearly and the constituents
// fall off exponentially with altitude. A cell of the run time's maps spans
// kilometres of altitude on a ray a few degrees up (22 km of ray, 2.3 km of
// altitude at 6°: a whole scale height of a continental aerosol), where the
// trapezoid overestimates the optical depth by 11 % and dims everything
// beyond it (single scattering 7-10 % low at 6-15° elevation).

INLINE RayMap extinction_ray_map(IN(AtmosphereParams) atmosphere, float r, float mu, float d, int cells,
                                 float flat_depth) {
  RayMap map;
  map.cells = cells;
  map.cell = d / float(cells);
  vec3 optical_depth = vec3(0.0f);
  for (int k = 0; k <= cells; ++k) {
    vec3 e = extinction_at(atmosphere, clamp_radius(atmosphere, radius_along_ray(r, mu, float(k) * map.cell)));
    if (k > 0) optical_depth += exponential_segment_integral(map.extinction[k - 1], e, map.cell);
    map.extinction[k] = e;
    map.optical_depth[k] = optical_depth;
    // The extinction that the start of the ray still sees: in a dense medium
    // the light scattered towards the start comes from its first optical
    // depths only, and nodes spread over the rest (each holding many optical
    // depths) would make the quadrature overestimate it by orders of
    // magnitude — energy created at every scattering order. Over the first
    // `flat_depth` optical depths the density is the extinction alone
    // (nodes uniform in optical depth), then it falls as the transmittance.
    vec3 visible = e * exp(-max(optical_depth - vec3(flat_depth), vec3(0.0f)));
    map.w[k] = visible.x + visible.y + visible.z;
  }
  return map;
}

INLINE RayMap sunlit_ray_map(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r, float mu,
                             float mu_s, float nu, float d, int cells, IN(Moons) moons, vec3 origin, vec3 view_ray,
                             vec3 sun_direction) {
  RayMap map;
  map.cells = cells;
  map.cell = d / float(cells);
  vec3 optical_depth = vec3(0.0f);
  vec3 previous_extinction = vec3(0.0f);
  for (int k = 0; k <= cells; ++k) {
    float t = float(k) * map.cell;
    float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, t));
    vec3 beta_rayleigh;
    vec3 beta_aerosol;
    vec3 extinction;
    medium_at(atmosphere, r_t, beta_rayleigh, beta_aerosol, extinction);
    if (k > 0) optical_depth += exponential_segment_integral(previous_extinction, extinction, map.cell);
    previous_extinction = extinction;
    map.extinction[k] = extinction;
    map.optical_depth[k] = optical_depth;
    vec3 f = (beta_rayleigh + beta_aerosol) * exp(-optical_depth) *
             transmittance_to_sun_estimate(atmosphere, transmittance_texture, r_t,
                                           clamp_cosine(mu_s_along_ray(r, mu_s, nu, t, r_t))) *
             uniform_sunlight_visible_fraction(moons, atmosphere.sun_angular_radius, origin + view_ray * t,
                                               sun_direction);
    map.w[k] = f.x + f.y + f.z;
  }
  return map;
}

INLINE RayNodes ray_integration_nodes_from_map(float d, IN(RayMap) map, float floor_fraction, int intervals) {
  RayNodes nodes;
  nodes.count = intervals + 1;
  if (!(d > 0.0f)) {
    // A ray of zero length (leaving the top straight away): nothing to integrate.
    for (int i = 0; i < RAY_NODES_CAPACITY; ++i) {
      nodes.t[i] = 0.0f;
      nodes.weight[i] = vec3(0.0f);
    }
    return nodes;
  }
  int cells = map.cells;
  float cell = map.cell;
  float w[RAY_MAP_CAPACITY + 1];
  float cumulative[RAY_MAP_CAPACITY + 1];
  float mean = 0.0f;
  for (int k = 0; k <= cells; ++k) mean += map.w[k] * ((k == 0 || k == cells) ? 0.5f : 1.0f) / float(cells);
  float floor_density = floor_fraction * mean + 1e-30f;
  cumulative[0] = 0.0f;
  for (int k = 0; k <= cells; ++k) {
    w[k] = map.w[k] + floor_density;
    if (k > 0) cumulative[k] = cumulative[k - 1] + 0.5f * (w[k - 1] + w[k]) * cell;
  }
  float total = cumulative[cells];
  int k = 0;
  for (int i = 0; i <= intervals; ++i) {
    float target = total * float(i) / float(intervals);
    while (k < cells - 1 && cumulative[k + 1] < target) ++k;
    // Solve cumulative[k] + w_k x + a x² / 2 = target for x in the cell.
    float a = (w[k + 1] - w[k]) / cell;
    float c = max(target - cumulative[k], 0.0f);
    float x = min(2.0f * c / (w[k] + safe_sqrt(w[k] * w[k] + 2.0f * a * c)), cell);
    float t = i == intervals ? d : float(k) * cell + x;
    float density = w[k] + a * x;
    nodes.t[i] = t;
    // The optical depth from the cells (nodes can be many cells apart where
    // w is small, e.g. the dense, dark bottom of a ray in the planet's
    // shadow: the transmittance keeps the resolution of the cells).
    vec3 e = exponential_interpolation(map.extinction[k], map.extinction[k + 1], x / cell);
    vec3 optical_depth = map.optical_depth[k] + exponential_segment_integral(map.extinction[k], e, x);
    float weight = simpson_weight(i, intervals, 1.0f / float(intervals)) * total / density;
    nodes.weight[i] = exp(-optical_depth) * weight;
  }
  return nodes;
}

// Extinction-placed nodes from the start of the ray to the nearest atmosphere
// boundary, with the full resolution of the precomputation. The floor (a
// quarter of the mean) keeps a share of the nodes where the air is thin.
INLINE RayNodes ray_integration_nodes(IN(AtmosphereParams) atmosphere, float r, float mu,
                                      bool ray_r_mu_intersects_ground, int intervals) {
  float d = distance_to_nearest_atmosphere_boundary(atmosphere, r, mu, ray_r_mu_intersects_ground);
  return ray_integration_nodes_from_map(d, extinction_ray_map(atmosphere, r, mu, d, RAY_MAP_CELLS, 0.0f), 0.25f,
                                        intervals);
}

// A documented approximation for the multiple-scattered light under an
// eclipse (eclipse.glsl). The tables hold multiple scattering for a fully
// lit planet; under a moon's shadow the light scattered more than once at a
// point was first scattered (or reflected) elsewhere, so it is dimmed by how
// much sunlight reaches the point's surroundings, not the point itself.
// Model: the light reaching `point` comes from the air around it along
// horizontal lines (the atmosphere is a layer far wider than thick). Light
// scattered at distance s along such a line arrives with a weight per
// octave of distance (a ring of area 2 pi s ds, spread over 4 pi s²) times
// the scattering coefficient there relative to the point's (the line rises
// above the curved ground: s²/2R) times the transmittance back along it.
// The visible fraction of the diffuse light is then the mean of
// uniform_sunlight_visible_fraction over the point itself (weight 1, the
// light from within the first ring) and over rings of radii
// DIFFUSE_RING_FIRST x 2^k, k < DIFFUSE_RINGS (8 to 512 km), 4 points each
// along and across the sun's azimuth, with those weights. What it gets
// right: nothing inside the umbra's core receives diffuse light from its
// surroundings at first hand, light reaches into the umbra from the
// penumbra around it over the horizontal transmittance, which is longer
// higher up, and the ground and the lower sky of a wide umbra stay lit from
// hundreds of kilometres away. What it leaves out: the direction the diffuse
// light comes from (it is dimmed as a whole, the tables' angular shape is
// kept) and the light from above and below the point's horizontal plane
// (folded into the point's own weight). Against the brute-force reference
// with moons (tests/eclipse_accuracy.cpp: Earth, totality under a 0.28°
// moon, the sun 40° up), the eclipsed sky of all orders comes out within
// -27..+13 %: the zenith +5 % (4e-4 of the daylight zenith), the horizon
// ring 12-27 % too dark.
#define DIFFUSE_RINGS 7
#define DIFFUSE_RING_FIRST 8000.0f
INLINE float diffuse_light_visible_fraction(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                            IN(Moons) moons, vec3 point, vec3 sun_direction) {
  if (moons.count == 0) return 1.0f;
  float a = atmosphere.sun_angular_radius;
  float r = clamp_radius(atmosphere, length(point));
  vec3 up = point / length(point);
  vec3 along = sun_direction - up * dot(sun_direction, up);
  if (dot(along, along) < 1e-8f) along = abs(up.x) < 0.9f ? cross(up, vec3(1.0f, 0.0f, 0.0f))
                                                          : cross(up, vec3(0.0f, 1.0f, 0.0f));
  along = normalize(along);
  vec3 across = cross(up, along);
  vec3 beta_rayleigh;
  vec3 beta_aerosol;
  vec3 extinction;
  medium_at(atmosphere, r, beta_rayleigh, beta_aerosol, extinction);
  vec3 scattering = beta_rayleigh + beta_aerosol;
  float source = scattering.x + scattering.y + scattering.z;
  float total = uniform_sunlight_visible_fraction(moons, a, point, sun_direction);
  float weights = 1.0f;
  float s = DIFFUSE_RING_FIRST;
  for (int ring = 0; ring < DIFFUSE_RINGS; ++ring) {
    float r_ring = sqrt(r * r + s * s);
    vec3 transmittance = r_ring < atmosphere.top_radius
                             ? transmittance_along_ray(atmosphere, transmittance_texture, r, 0.0f, s, false)
                             : vec3(0.0f);
    medium_at(atmosphere, clamp_radius(atmosphere, r_ring), beta_rayleigh, beta_aerosol, extinction);
    scattering = (beta_rayleigh + beta_aerosol) * transmittance;
    float weight = source > 0.0f ? (scattering.x + scattering.y + scattering.z) / source : 0.0f;
    float ring_sum = 0.0f;
    for (int j = 0; j < 4; ++j) {
      vec3 direction = j == 0 ? along : j == 1 ? -along : j == 2 ? across : -across;
      ring_sum += uniform_sunlight_visible_fraction(moons, a, point + direction * s, sun_direction);
    }
    total += weight * 0.25f * ring_sum;
    weights += weight;
    s *= 2.0f;
  }
  return total / weights;
}

// Single scattering summed over quadrature nodes along the ray (r, mu) with
// the sun at (mu_s, nu), without phase functions (see
// compute_single_scattering). With moons (eclipse.glsl; `origin` and
// `view_ray` place the ray in space, |origin| = r) each node receives the
// fraction of the sun's light they leave it (sunlight_visible_fraction).
INLINE void single_scattering_over_nodes(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                         float r, float mu, float mu_s, float nu, IN(RayNodes) nodes,
                                         IN(Moons) moons, vec3 origin, vec3 view_ray, vec3 sun_direction,
                                         OUT(vec3) rayleigh, OUT(vec3) aerosol) {
  rayleigh = vec3(0.0f);
  aerosol = vec3(0.0f);
  // Read once (C++: the outputs could alias the moons as far as the
  // compiler knows, which would reload the count at every node).
  bool eclipse = moons.count > 0;
  for (int i = 0; i < nodes.count; ++i) {
    float r_t = clamp_radius(atmosphere, radius_along_ray(r, mu, nodes.t[i]));
    float mu_s_t = clamp_cosine(mu_s_along_ray(r, mu_s, nu, nodes.t[i], r_t));
    vec3 beta_rayleigh;
    vec3 beta_aerosol;
    vec3 extinction;
    medium_at(atmosphere, r_t, beta_rayleigh, beta_aerosol, extinction);
    vec3 light = nodes.weight[i] * transmittance_to_sun(atmosphere, transmittance_texture, r_t, mu_s_t);
    if (eclipse) {
      light *= sunlight_visible_fraction(moons, atmosphere.sun_angular_radius, origin + view_ray * nodes.t[i],
                                         sun_direction);
    }
    rayleigh += light * beta_rayleigh;
    aerosol += light * beta_aerosol;
  }
  rayleigh *= atmosphere.solar_irradiance;
  aerosol *= atmosphere.solar_irradiance;
}

// The factor that dims the multiple scattering along a ray under an
// eclipse: the mean of diffuse_light_visible_fraction along it, weighted by
// the light each part of the ray sends towards its start (extinction x
// transmittance, from `map`'s cells, which are uniform along the ray and
// independent of the sunlight). That fraction varies over tens of
// kilometres, so it is evaluated at the weighted centres of the
// DIFFUSE_VISIBILITY_BINS equal runs of cells only. 1 without moons.
#define DIFFUSE_VISIBILITY_BINS 2
INLINE float ray_diffuse_visibility(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture,
                                    IN(RayMap) map, IN(Moons) moons, vec3 origin, vec3 view_ray,
                                    vec3 sun_direction) {
  float total_weight = 0.0f;
  float visible = 0.0f;
  for (int b = 0; b < DIFFUSE_VISIBILITY_BINS && moons.count > 0; ++b) {
    float weight = 0.0f;
    float distance = 0.0f;
    for (int k = b * map.cells / DIFFUSE_VISIBILITY_BINS; k < (b + 1) * map.cells / DIFFUSE_VISIBILITY_BINS; ++k) {
      vec3 sent = map.extinction[k] * exp(-map.optical_depth[k]);
      float w = sent.x + sent.y + sent.z;
      weight += w;
      distance += w * (float(k) + 0.5f) * map.cell;
    }
    float t = weight > 0.0f ? distance / weight : 0.0f;
    visible += weight * diffuse_light_visible_fraction(atmosphere, transmittance_texture, moons,
                                                       origin + view_ray * t, sun_direction);
    total_weight += weight;
  }
  return total_weight > 0.0f ? visible / total_weight : 1.0f;
}

// Single scattering of the ray (r, mu) from its start to distance d, with
// nodes placed by the integrand itself (sunlit_ray_map, `cells` cells,
// `intervals` Simpson intervals): the run-time form, which stays accurate in
// twilight, where the lit part of the ray is short and far and the table's
// interpolation in mu_s is not (the radiance switches on over a fraction of
// a degree of sun elevation there). With moons, as single_scattering_over_nodes
// (the nodes then follow the moons' shadows too), and `diffuse_visibility`
// is ray_diffuse_visibility (1 without moons).
INLINE void integrate_single_scattering(IN(AtmosphereParams) atmosphere, IN(sampler2D) transmittance_texture, float r,
                                        float mu, float mu_s, float nu, float d, int intervals, int cells,
                                        IN(Moons) moons, vec3 origin, vec3 view_ray, vec3 sun_direction,
                                        OUT(vec3) rayleigh, OUT(vec3) aerosol, OUT(float) diffuse_visibility) {
  RayMap map = sunlit_ray_map(atmosphere, transmittance_texture, r, mu, mu_s, nu, d, cells, moons, origin, view_ray,
                              sun_direction);
  RayNodes nodes = ray_integration_nodes_from_map(d, map, SUNLIT_FLOOR_FRACTION, intervals);
  single_scattering_over_nodes(atmosphere, transmittance_texture, r, mu, mu_s, nu, nodes, moons, origin, view_ray,
                               sun_direction, rayleigh, aerosol);
  diffuse_visibility =
      ray_diffuse_visibility(atmosphere, transmittance_texture, map, moons, origin, view_ray, sun_direction);
}
