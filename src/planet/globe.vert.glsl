// The globe's vertex shader (src/planet/globe.cpp). Positions are relative to
// the camera: each tile's vertices are stored in float relative to the
// tile's origin, and the origin's offset from the camera is computed in
// double on the CPU for every draw (Cozzi & Ring 2011, ch. 5), so that no
// large coordinate reaches the GPU.
//
// Continuous level of detail (Strugar 2009): every vertex also stores the
// offset to where the parent tile's mesh passes (its own position on the
// parent's grid points, the midpoint of the parent's edge or diagonal
// otherwise), and moves there as its distance d from the camera goes from
// morph_range.x to morph_range.y: k = clamp((d - x) / (y - x), 0, 1). A tile
// fully morphed is its parent's surface, so a level hands over to the next
// without a visible change, and an edge shared with a coarser neighbour
// (always fully morphed there, tile_selection.hpp) matches it.
//
// Lighting, per vertex (Gouraud 1971), appended after "#version 450 core"
// and AtmospherePass::glsl_library(): a Lambertian surface lit by the sun's
// light transmitted to the vertex's own altitude (zero in the planet's
// shadow) and by the sky's irradiance there, both from the atmosphere's
// tables (Bruneton & Neyret 2008, §4; Collienne 2013, §4.3.3). The mesh's
// vertices are at most 16 error bounds apart on the screen
// (globe_mesh.cpp), and the irradiance varies slowly along the ground, so
// the fragment shader interpolates the vertices' radiance: a software
// rasteriser shades 5-10 times fewer vertices than pixels. The colour
// written is radiance / nits_per_unit; the engine plugin then adds the
// aerial perspective in front of it.
//
// Variants (a #define after the version line):
//  - ATMOS_GLOBE_SHADOWS: the sun's and the sky's parts of the radiance go
//    to the fragment shader separately, with the camera-relative position
//    and the normal, for the terrain's shadow, which dims the sun's part
//    only (globe.frag.glsl);
//  - ATMOS_GLOBE_ECLIPSE: the same separate parts and position, for the
//    moons' factors, which dim the sun's part and the sky's part each by
//    its own (globe.frag.glsl);
//  - ATMOS_GLOBE_DEPTH_ONLY: the same morphed positions through the sun's
//    cascade projection (clip_from_offset), nothing lit: the shadow maps'
//    casters are the very surface that is drawn. Compiled without the
//    atmosphere's library.

layout(location = 0) in vec3 local_position;  // m, from the tile's origin
layout(location = 1) in vec3 morph_offset;    // m, to the parent's surface
#if !defined(ATMOS_GLOBE_DEPTH_ONLY)
layout(location = 2) in vec3 normal;          // unit, this level's mesh
layout(location = 3) in vec3 parent_normal;   // unit, the parent's mesh
layout(location = 4) in vec3 albedo;          // linear reflectance
#endif

uniform vec3 origin_from_camera;  // m, the tile's origin minus the camera (planet axes)
uniform vec2 morph_range;         // m: where the morph starts and ends
uniform mat4 clip_from_offset;    // projection x view rotation x (engine units per metre); the sun's: its clip space
#if !defined(ATMOS_GLOBE_DEPTH_ONLY)
uniform vec3 camera_planet;       // m, planet-centred
uniform vec3 sun_direction;       // unit, planet axes
uniform float light_scale;        // (sun illuminance / the atmosphere's own) / nits_per_unit
#endif

#if defined(ATMOS_GLOBE_DEPTH_ONLY)
#elif defined(ATMOS_GLOBE_SHADOWS) || defined(ATMOS_GLOBE_ECLIPSE)
out vec3 v_sun_radiance;  // the sun's part, linear sRGB, cd/m2 / nits_per_unit
out vec3 v_sky_radiance;  // the sky's part
out vec3 v_offset;        // m, from the camera (planet axes)
#if defined(ATMOS_GLOBE_SHADOWS)
out vec3 v_normal;        // unit at the vertices
#endif
#else
out vec3 v_radiance;  // linear sRGB, cd/m2 / nits_per_unit
#endif

void main() {
  vec3 offset = origin_from_camera + local_position;
  float k = clamp((length(offset) - morph_range.x) / max(morph_range.y - morph_range.x, 1e-30), 0.0, 1.0);
  offset += k * morph_offset;
#if !defined(ATMOS_GLOBE_DEPTH_ONLY)
  vec3 point = camera_planet + offset;
  vec3 n = normalize(mix(normal, parent_normal, k));
  vec3 sky_irradiance;
  vec3 sun_irradiance = atmos_sun_and_sky_irradiance(point, n, sun_direction, sky_irradiance);
#if defined(ATMOS_GLOBE_SHADOWS) || defined(ATMOS_GLOBE_ECLIPSE)
  v_sun_radiance = albedo * (1.0 / 3.14159265358979) * sun_irradiance * light_scale;
  v_sky_radiance = albedo * (1.0 / 3.14159265358979) * sky_irradiance * light_scale;
  v_offset = offset;
#if defined(ATMOS_GLOBE_SHADOWS)
  v_normal = n;
#endif
#else
  v_radiance = albedo * (1.0 / 3.14159265358979) * (sun_irradiance + sky_irradiance) * light_scale;
#endif
#endif
  gl_Position = clip_from_offset * vec4(offset, 1.0);
}
