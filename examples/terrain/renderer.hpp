// The example engine's renderer: its own framebuffer, shaders and shadow
// map. It knows nothing of the atmosphere except the GLSL library it pastes
// into its fragment shader to light surfaces with the atmosphere's sun and
// sky (AtmospherePass::glsl_library / bind_textures).
#pragma once

#include <glm/mat4x4.hpp>

#include <string>
#include <vector>

#include <atmos/plugin.hpp>

#include "gl.hpp"
#include "scene.hpp"
#include "terrain.hpp"
#include "world.hpp"

namespace engine {

struct RenderSettings {
  int width = 1280;
  int height = 720;
  atmos::SurfaceMode surfaces = atmos::SurfaceMode::lit_colour;
  atmos::DepthEncoding depth = atmos::DepthEncoding::standard;
  bool infinite_far = false;   // standard depth: infinite far plane
  int shadow_map_size = 2048;  // texels per side; 0: no shadow map
  // The scene shader dims its sun and sky light by the scene's moons (an
  // eclipse; compiled in only then, so that other frames pay nothing).
  bool eclipse = false;
  // cd/m² per unit of the colour buffer. Half floats stop at 65504: a
  // sunlit snowfield reaches ~35 000 cd/m², so the buffer is pre-exposed.
  double nits_per_unit = 16.0;
};

// The texture unit of the shadow map, and the first of the five units of
// the atmosphere library's textures (any free units would do).
inline constexpr int kShadowMapUnit = 0;
inline constexpr int kAtmosphereFirstUnit = 1;

class SceneRenderer {
 public:
  // Creates the render targets and compiles the shaders; `atmosphere_glsl`
  // is AtmospherePass::glsl_library(kAtmosphereFirstUnit).
  SceneRenderer(const RenderSettings& settings, const World& world, const Terrain& terrain,
                const std::string& atmosphere_glsl);

  // Pass 1: the terrain's and the objects' depth seen from the sun (skipped
  // without a shadow map). Sets shadow_matrix().
  void render_shadow_map(const Scene& scene);
  // Pass 2: the scene into the colour (or G-buffer) and depth textures.
  // `atmosphere` binds the textures of the lighting library.
  void render_scene(const Scene& scene, const atmos::AtmospherePass& atmosphere);

  // The engine's render targets (GL texture names), width x height.
  GLuint colour_texture() const { return colour_.get(); }  // RGBA16F, lit colour / nits_per_unit
  GLuint albedo_texture() const { return albedo_.get(); }  // RGBA16F (G-buffer mode only, else 0)
  GLuint normal_texture() const { return normal_.get(); }  // RGBA16F world normals (G-buffer mode only)
  GLuint depth_texture() const { return depth_.get(); }    // DEPTH_COMPONENT32F
  GLuint shadow_map() const { return shadow_map_.get(); }  // DEPTH_COMPONENT32F, 0 without shadows

  // The matrices of the last frame, in the engine's world frame (double).
  const glm::dmat4& view() const { return view_; }
  const glm::dmat4& projection() const { return projection_; }
  const glm::dmat4& shadow_matrix() const { return shadow_matrix_; }  // world -> the sun's clip space
  double log_depth_far() const { return log_depth_far_; }

  const RenderSettings& settings() const { return settings_; }
  long long triangles() const { return triangles_; }  // drawn by the last render_scene()

 private:
  struct Mesh {
    gl::Handle vertex_array, vertices, indices;
    GLsizei index_count = 0;
  };
  Mesh upload(const MeshData& data) const;
  const Mesh& mesh_of(const SceneObject& object) const;

  RenderSettings settings_;
  const World& world_;
  const Terrain& terrain_;
  Mesh terrain_mesh_, box_mesh_, sphere_mesh_;
  long long triangles_ = 0;

  gl::Handle scene_program_, shadow_program_;
  gl::Handle colour_, albedo_, normal_, depth_, framebuffer_;
  gl::Handle shadow_map_, shadow_framebuffer_, shadow_sampler_;

  glm::dmat4 view_{1.0}, projection_{1.0}, shadow_matrix_{1.0};
  double log_depth_far_ = 0.0;
  double shadow_texel_ = 0.0;  // world size of a shadow-map texel, engine units
};

}  // namespace engine
