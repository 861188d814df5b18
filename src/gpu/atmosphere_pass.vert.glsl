// atmos — vertex shader of the engine plugin's pass (GLSL only, appended by
// gpu/shader_source.cpp after the subset macros and pixel_ray.glsl). One
// triangle that covers the viewport, vertices (-1,-1), (3,-1), (-1,3) in NDC,
// each with its PixelRay, which the rasteriser interpolates linearly to the
// pixels (noperspective; w is 1 anyway).

layout(location = 2) uniform mat4 inverse_projection;  // locations 2-5
layout(location = 6) uniform mat3 view_to_world;       // 6-8

layout(location = 0) noperspective out vec4 ray_world;
layout(location = 1) noperspective out float ray_view_z;

void main() {
  vec2 ndc = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)) * 2.0 - 1.0;
  gl_Position = vec4(ndc, 0.0, 1.0);
  PixelRay ray = pixel_ray(inverse_projection, view_to_world, ndc);
  ray_world = ray.world;
  ray_view_z = ray.view_z;
}
