// atmos — fragment shader of the renderer (GLSL only, appended by
// gpu/shader_source.cpp after the definitions, the parameter block, the
// physics up to radiance_to_camera.glsl (kRenderPhysics), table_bindings.glsl
// and camera.glsl). One full-screen triangle; each fragment is one pixel of
// the image: its view ray, the radiance reaching the camera along
// it, and that radiance converted to linear sRGB (cd/m² scale).

// The tables and the sky-view table: table_bindings.glsl. SKY_VIEW_CAMERA
// (true or false, defined by gpu/shader_source.cpp) selects the program
// variant: true for cameras in the atmosphere (camera_uses_sky_view), which
// read the sky-view table.

layout(location = 0) uniform vec3 camera;           // m, planet-centred
layout(location = 1) uniform vec3 camera_right;
layout(location = 2) uniform vec3 camera_up;
layout(location = 3) uniform vec3 camera_forward;
layout(location = 4) uniform float fov_deg;
layout(location = 5) uniform int projection;        // PROJECTION_* of camera.glsl
layout(location = 6) uniform vec2 image_size;       // pixels
layout(location = 7) uniform vec3 sun_direction;    // unit vector towards the sun
// The image is drawn in tiles: image coordinates (x right, y down from the
// top-left corner) of the bottom-left corner of the current tile.
layout(location = 8) uniform vec2 tile_origin;
// atmos::radiance_to_srgb_matrix; a mat3 takes locations 9 to 11.
layout(location = 9) uniform mat3 radiance_to_srgb;
// The star field (stars.glsl): on or off, and the width of a star's image.
layout(location = 12) uniform bool stars_enabled;
layout(location = 13) uniform float star_sigma;
// The perspective's lens shift (camera.glsl: an off-axis frustum).
layout(location = 14) uniform vec2 lens_shift;
// A star catalogue instead of the procedural field: stars.glsl's uniforms
// (locations 60-63) and buffers.
// The moons (eclipse.glsl): uniform_moons() of table_bindings.glsl in the
// variant RENDER_ECLIPSE 1 (with moons), none in RENDER_ECLIPSE 0; and
// whether they may hide the sun from the atmosphere this frame
// (moons_may_eclipse: if not, they are drawn and eclipse nothing).
layout(location = 50) uniform bool moons_eclipse;

layout(location = 0) out vec4 frag_color;

void main() {
  // gl_FragCoord is the pixel centre in the tile with y up from its bottom
  // row; the image has y down from its top row (the read-back flips the rows
  // to match). Exact in float: integers plus 0.5, far below 2^24.
  vec2 pixel = vec2(tile_origin.x + gl_FragCoord.x, tile_origin.y - gl_FragCoord.y);
  bool valid;
  vec3 view_ray = camera_view_ray(pixel, image_size, camera_right, camera_up, camera_forward, fov_deg, lens_shift,
                                  projection, valid);
  if (!valid) {
    frag_color = vec4(0.0, 0.0, 0.0, 1.0);
    return;
  }
#if RENDER_ECLIPSE
  Moons moons = uniform_moons();
#else
  Moons moons = no_moons();
#endif
  vec3 radiance = radiance_along_view_ray(ATMOSPHERE, SPECTRAL, spectral_transmittance_texture, scattering_texture,
                                          single_aerosol_texture, multiple_scattering_texture, irradiance_texture,
                                          sky_view_rayleigh_texture, sky_view_aerosol_texture,
                                          sky_view_surface_texture, SKY_VIEW_CAMERA, uniform_sky_view_frame(), camera,
                                          view_ray, sun_direction, true, StarField(stars_enabled, star_sigma),
                                          moons, moons_eclipse);
  frag_color = vec4(radiance_to_srgb * radiance, 1.0);
}
