// atmos — the stars behind the atmosphere: a procedural star field, or the
// stars of a catalogue.
//
// Needs: definitions.glsl. radiance_to_camera.glsl adds the stars to what
// a view ray sees beyond the atmosphere.
//
// The procedural field, without a catalogue: the sky is divided into the cells of a cube map,
// STAR_CELLS x STAR_CELLS per face, and each cell holds one star placed and
// scaled by a hash of the cell's index. The magnitudes follow the counts of
// the real sky: the number of stars brighter than V is N(V) = 10^(0.5 V +
// 0.7) over the whole sky — 8900 brighter than 6.5 (the Yale Bright Star
// Catalogue lists 9110 to about 6.5: Hoffleit & Warren 1991), about 50
// brighter than 2 and 5 brighter than 0 — so the 6 x 48² = 13 824 stars reach
// V = 6.9, the naked eye's limit under a dark sky; the brightest is expected
// near V = -1.4 (Sirius: -1.46; this field's, drawn at random: -2.4). Each star is placed at least 15 % of a cell
// (0.28°) from the cell's edges, so that a pixel finds any star that lights
// it in its own cell. Stars are white (the Sun's spectrum) and do not move
// with time: the field is fixed in the planet's frame, a backdrop, not an
// ephemeris.
#define STAR_CELLS 48
// V magnitude of the Sun (Willmer 2018, ApJS 236, 47, Table 3: -26.76; the
// commonly used -26.74 here): a star of magnitude V gives
// 10^(-0.4 (V - SUN_V_MAGNITUDE)) of the Sun's irradiance at 1 au.
#define SUN_V_MAGNITUDE -26.74f
// The Sun's angular radius at 1 au (IAU 2015 nominal solar radius 695 700
// km over 1 au = 149 597 870.7 km): the planet's distance from its sun
// follows from the preset's angular radius, the stars' brightness does not.
#define SUN_ANGULAR_RADIUS_AT_1_AU 4.65047e-3f

// How the stars are drawn: on or off, and the angular width (Gaussian sigma,
// radians) of a star's image. A star is a point; its image is spread over a
// pixel or two (sigma ~ 0.6 of the pixel's angular size, see the renderers),
// so that it neither falls between pixel centres nor flickers, and its
// radiance integrates over the image to its irradiance.
// In C++ the field also carries the catalogue (STAR_CATALOGUE_MEMBER, see
// physics/stars_cpp.hpp); in GLSL the catalogue is the program's (below).
#ifndef STAR_CATALOGUE_MEMBER
#define STAR_CATALOGUE_MEMBER
#endif
struct StarField {
  bool enabled;
  float sigma;
  STAR_CATALOGUE_MEMBER
};

// A 32-bit integer hash (C. Wellons' "lowbias32", 2018): well mixed, the same
// in GLSL and C++ (unsigned wrap-around arithmetic in both).
INLINE uint star_hash(uint x) {
  x ^= x >> 16u;
  x *= 0x7feb352du;
  x ^= x >> 15u;
  x *= 0x846ca68bu;
  x ^= x >> 16u;
  return x;
}

// A number in [0, 1) from a hash (24 bits: exact in float).
INLINE float star_random(uint x) { return float(star_hash(x) >> 8u) * (1.0f / 16777216.0f); }

// The direction (not normalised) of point uv in [-1, 1]² of cube face
// `face`: 0/1 +x/-x, 2/3 +y/-y, 4/5 +z/-z.
INLINE vec3 star_cube_direction(int face, vec2 uv) {
  float s = (face % 2 == 0) ? 1.0f : -1.0f;
  if (face < 2) return vec3(s, uv.x, uv.y);
  if (face < 4) return vec3(uv.y, s, uv.x);
  return vec3(uv.x, uv.y, s);
}

// The star of cell `cell` (face * STAR_CELLS² + row * STAR_CELLS + column):
// its unit direction and V magnitude.
INLINE vec3 star_of_cell(int cell, OUT(float) magnitude) {
  int face = cell / (STAR_CELLS * STAR_CELLS);
  int row = (cell / STAR_CELLS) % STAR_CELLS;
  int column = cell % STAR_CELLS;
  uint seed = uint(cell) * 3u;
  vec2 in_cell = vec2(0.15f + 0.7f * star_random(seed), 0.15f + 0.7f * star_random(seed + 1u));
  vec2 uv = (vec2(float(column), float(row)) + in_cell) * (2.0f / float(STAR_CELLS)) - 1.0f;
  // The cell's rank in brightness, uniform in (0, 1]: N(V) = 10^(0.5 V + 0.7).
  float rank = 1.0f - star_random(seed + 2u);
  float total = 6.0f * float(STAR_CELLS * STAR_CELLS);
  magnitude = (log(total * rank) / log(10.0f) - 0.7f) / 0.5f;
  return normalize(star_cube_direction(face, uv));
}

// The cell of direction `view_ray` (unit) in a cube map of `cells` x `cells`
// cells per face: face * cells² + row * cells + column.
INLINE int star_cube_cell(vec3 view_ray, int cells) {
  vec3 a = abs(view_ray);
  int face;
  vec2 uv;
  if (a.x >= a.y && a.x >= a.z) {
    face = view_ray.x > 0.0f ? 0 : 1;
    uv = vec2(view_ray.y, view_ray.z) / a.x;
  } else if (a.y >= a.z) {
    face = view_ray.y > 0.0f ? 2 : 3;
    uv = vec2(view_ray.z, view_ray.x) / a.y;
  } else {
    face = view_ray.z > 0.0f ? 4 : 5;
    uv = vec2(view_ray.x, view_ray.y) / a.z;
  }
  int column = clamp(int(floor((0.5f * uv.x + 0.5f) * float(cells))), 0, cells - 1);
  int row = clamp(int(floor((0.5f * uv.y + 0.5f) * float(cells))), 0, cells - 1);
  return (face * cells + row) * cells + column;
}

// The cell whose star can light direction `view_ray` (unit).
INLINE int star_cell(vec3 view_ray) { return star_cube_cell(view_ray, STAR_CELLS); }

// The stars of a catalogue (atmos::Star, set by Renderer::set_star_catalogue
// and AtmospherePass::set_star_catalogue): each star's direction in the
// catalogue's frame and its irradiance in the tables' channels above the
// atmosphere. They are binned on the CPU (gpu/star_catalogue_bins.cpp) into
// the STAR_CATALOGUE_CELLS² cells of each face of a cube map in that frame:
// a cell lists every star whose image can reach into it (every star closer
// to the cell than the bins' radius, at least five image widths), so that
// a pixel sums the stars of its own cell alone. A cell's stars are records
// first .. end - 1 (star_catalogue_cell_first of the cell and of the next
// one); record 2 i holds the star's unit direction (xyz), 2 i + 1 its
// irradiance (xyz). The view ray is turned into the catalogue's frame by
// catalogue_from_world, so that the stars of a date turn with the sky
// without new bins.
#define STAR_CATALOGUE_CELLS 64
// The buffers' binding points, within the 8 that every OpenGL 4.3+
// implementation has (GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS).
#define STAR_CATALOGUE_CELLS_BINDING 6
#define STAR_CATALOGUE_RECORDS_BINDING 7

#ifdef __cplusplus
INLINE bool star_catalogue_enabled(IN(StarField) stars) { return stars.catalogue.enabled; }
INLINE mat3 star_catalogue_from_world(IN(StarField) stars) { return stars.catalogue.from_world; }
INLINE uint star_catalogue_cell_first(IN(StarField) stars, int cell) { return stars.catalogue.cell_first[cell]; }
INLINE vec4 star_catalogue_record(IN(StarField) stars, uint i) { return stars.catalogue.records[i]; }
#else
// The program's catalogue: whether it is drawn (else the procedural field),
// the rotation from the world's axes to its frame, and its bins.
layout(location = 60) uniform bool star_catalogue_on;
layout(location = 61) uniform mat3 star_catalogue_rotation;  // 61-63
layout(std430, binding = STAR_CATALOGUE_CELLS_BINDING) readonly buffer StarCatalogueCells {
  uint star_catalogue_cells[];
};
layout(std430, binding = STAR_CATALOGUE_RECORDS_BINDING) readonly buffer StarCatalogueRecords {
  vec4 star_catalogue_records[];
};
bool star_catalogue_enabled(StarField stars) { return star_catalogue_on; }
mat3 star_catalogue_from_world(StarField stars) { return star_catalogue_rotation; }
uint star_catalogue_cell_first(StarField stars, int cell) { return star_catalogue_cells[cell]; }
vec4 star_catalogue_record(StarField stars, uint i) { return star_catalogue_records[i]; }
#endif

// Radiance of the catalogue's stars in direction `view_ray` (unit, world
// axes) above the atmosphere: each star's image a Gaussian of width
// stars.sigma that integrates to its irradiance, as the procedural field's.
INLINE vec3 star_catalogue_radiance(IN(StarField) stars, vec3 view_ray) {
  vec3 ray = star_catalogue_from_world(stars) * view_ray;
  int cell = star_cube_cell(ray, STAR_CATALOGUE_CELLS);
  uint first = star_catalogue_cell_first(stars, cell);
  uint end = star_catalogue_cell_first(stars, cell + 1);
  float inverse_two_sigma2 = 0.5f / (stars.sigma * stars.sigma);
  vec3 sum = vec3(0.0f);
  for (uint i = first; i < end; ++i) {
    vec3 star = vec3(star_catalogue_record(stars, 2u * i));
    vec3 c = cross(ray, star);
    float theta2 = dot(ray, star) > 0.0f ? dot(c, c) : 4.0f;  // sin²: the angle², to 1e-8 over an image
    sum += vec3(star_catalogue_record(stars, 2u * i + 1u)) * exp(-theta2 * inverse_two_sigma2);
  }
  return sum * (inverse_two_sigma2 / PI);
}

// Irradiance of a star of magnitude V in the tables' channels: a fraction of
// the Sun's at 1 au, itself the planet's solar irradiance scaled by the
// square of the angular radii (the planet's sun is assumed to be the Sun).
INLINE vec3 star_irradiance(IN(AtmosphereParams) atmosphere, float magnitude) {
  float distance_factor = SUN_ANGULAR_RADIUS_AT_1_AU / atmosphere.sun_angular_radius;
  return atmosphere.solar_irradiance *
         (distance_factor * distance_factor * pow(10.0f, -0.4f * (magnitude - SUN_V_MAGNITUDE)));
}

// Radiance of the star field in direction `view_ray` (unit), above the
// atmosphere (the caller attenuates it): the star of the ray's cell, its
// image a Gaussian of width stars.sigma that integrates to its irradiance.
INLINE vec3 star_field_radiance(IN(AtmosphereParams) atmosphere, IN(StarField) stars, vec3 view_ray) {
  if (!stars.enabled) return vec3(0.0f);
  if (star_catalogue_enabled(stars)) return star_catalogue_radiance(stars, view_ray);
  float magnitude;
  vec3 star = star_of_cell(star_cell(view_ray), magnitude);
  vec3 c = cross(view_ray, star);
  float theta2 = dot(view_ray, star) > 0.0f ? dot(c, c) : 4.0f;  // sin²: the angle, to 1e-8 over an image
  float sigma2 = stars.sigma * stars.sigma;
  return star_irradiance(atmosphere, magnitude) * (exp(-0.5f * theta2 / sigma2) / (2.0f * PI * sigma2));
}
