// atmos — the engine plugin's per-pixel view ray before the depth is known.
// Shared by the pass's vertex shader (atmosphere_pass.vert.glsl), its
// fragment shaders (through composite.glsl, which follows this file) and the
// CPU twin (gpu/composite_cpp.hpp), in the GLSL / C++ subset of
// physics/definitions.glsl; it needs nothing else, so that the vertex shader
// stays small.
//
// The engine's view-space point of NDC (x, y, z) is p / p.w with
// p = inverse_projection (x, y, z, 1) = base + z inverse_projection[2],
// base = inverse_projection (x, y, 0, 1). A PixelRay holds base with its xyz
// turned to the world's axes and metres (view_to_world: see PassFrame in
// composite.glsl) in `world`, and base.z in view space in `view_z`
// (logarithmic depth needs it). Both are affine in the pixel's position: the
// vertex shader computes them at the corners of the full-screen triangle and
// the rasteriser interpolates them (exactly, but for rounding), which spares
// every pixel a 4x4 and a 3x3 matrix product.
struct PixelRay {
  vec4 world;
  float view_z;
};

INLINE PixelRay pixel_ray(IN(mat4) inverse_projection, IN(mat3) view_to_world, vec2 ndc) {
  vec4 base = inverse_projection * vec4(ndc.x, ndc.y, 0.0f, 1.0f);
  PixelRay ray;
  ray.world = vec4(view_to_world * vec3(base), base.w);
  ray.view_z = base.z;
  return ray;
}
