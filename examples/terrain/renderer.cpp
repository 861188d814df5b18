#include "renderer.hpp"

#include <glm/geometric.hpp>
#include <glm/gtc/matrix_inverse.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <glm/mat3x3.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

#include "terrain_shaders.hpp"  // generated from shaders/*.glsl (see examples/CMakeLists.txt)

namespace engine {

namespace {

// Rounds a double matrix to the float matrix the GPU gets. Only matrices
// whose entries are already small (camera- or patch-relative) go through
// here: that is the whole trick of camera-relative rendering.
glm::mat4 to_float(const glm::dmat4& m) { return glm::mat4(m); }

void set_uniform(GLuint program, const char* name, const glm::dmat4& m) {
  const glm::mat4 f = to_float(m);
  glProgramUniformMatrix4fv(program, gl::uniform(program, name), 1, GL_FALSE, glm::value_ptr(f));
}
void set_uniform(GLuint program, const char* name, const glm::dmat3& m) {
  const glm::mat3 f(m);
  glProgramUniformMatrix3fv(program, gl::uniform(program, name), 1, GL_FALSE, glm::value_ptr(f));
}
void set_uniform(GLuint program, const char* name, const glm::dvec3& v) {
  glProgramUniform3f(program, gl::uniform(program, name), float(v.x), float(v.y), float(v.z));
}
void set_uniform(GLuint program, const char* name, const glm::vec3& v) {
  glProgramUniform3f(program, gl::uniform(program, name), v.x, v.y, v.z);
}
void set_uniform(GLuint program, const char* name, double x) {
  glProgramUniform1f(program, gl::uniform(program, name), float(x));
}
void set_uniform(GLuint program, const char* name, int x) {
  glProgramUniform1i(program, gl::uniform(program, name), x);
}

// Perspective projections for each depth encoding (OpenGL conventions: the
// camera looks along -z; clip w = -z_view in all of them, so all three
// rasterise exactly the same pixels).
glm::dmat4 projection_for(const RenderSettings& settings, const Camera& camera) {
  const double fovy = glm::radians(camera.fov_deg);
  const double aspect = double(settings.width) / double(settings.height);
  switch (settings.depth) {
    case atmos::DepthEncoding::standard:
      return settings.infinite_far ? glm::infinitePerspective(fovy, aspect, camera.near)
                                   : glm::perspective(fovy, aspect, camera.near, camera.far);
    case atmos::DepthEncoding::reversed_z: {
      // Infinite reversed-Z for glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE):
      // depth = near / distance, 1 on the near plane, 0 at infinity. Float
      // depth then has about the same relative precision at every distance.
      const double f = 1.0 / std::tan(0.5 * fovy);
      glm::dmat4 p(0.0);
      p[0][0] = f / aspect;
      p[1][1] = f;
      p[3][2] = camera.near;  // column 3, row 2: z_clip = near
      p[2][3] = -1.0;         // column 2, row 3: w_clip = -z_view
      return p;
    }
    case atmos::DepthEncoding::logarithmic:
      // The fragment shader writes the depth; the projection only places the
      // pixels (and clips at the near plane).
      return glm::infinitePerspective(fovy, aspect, camera.near);
  }
  return glm::dmat4(1.0);
}

}  // namespace

SceneRenderer::SceneRenderer(const RenderSettings& settings, const World& world, const Terrain& terrain,
                             const std::string& atmosphere_glsl)
    : settings_(settings), world_(world), terrain_(terrain) {
  terrain_mesh_ = upload(terrain.mesh());
  box_mesh_ = upload(box_mesh());
  sphere_mesh_ = upload(sphere_mesh(48, 24));

  // The fragment shader: "#version", the engine's switch, atmos's library
  // (textures and atmos_* functions), then the engine's own code, which
  // calls them.
  const bool log_depth = settings.depth == atmos::DepthEncoding::logarithmic;
  const std::array scene_stages = {
      gl::ShaderStage{GL_VERTEX_SHADER, std::string(shaders::scene_vert)},
      gl::ShaderStage{GL_FRAGMENT_SHADER, std::string("#version 450 core\n#define LOG_DEPTH ") +
                                              (log_depth ? "1" : "0") + "\n#define ECLIPSE " +
                                              (settings.eclipse ? "1" : "0") + "\n" + atmosphere_glsl + "\n" +
                                              std::string(shaders::scene_frag)},
  };
  scene_program_ = gl::create_program("scene shader", scene_stages);
  const std::array shadow_stages = {
      gl::ShaderStage{GL_VERTEX_SHADER, std::string(shaders::shadow_vert)},
      gl::ShaderStage{GL_FRAGMENT_SHADER, std::string(shaders::shadow_frag)},
  };
  shadow_program_ = gl::create_program("shadow shader", shadow_stages);

  // The main framebuffer: HDR colour (and in G-buffer mode albedo and
  // normals) plus a 32-bit float depth texture, all readable by the plugin.
  const int w = settings.width, h = settings.height;
  framebuffer_ = gl::create_framebuffer();
  colour_ = gl::create_texture_2d(GL_RGBA16F, w, h);
  depth_ = gl::create_texture_2d(GL_DEPTH_COMPONENT32F, w, h);
  glNamedFramebufferTexture(framebuffer_.get(), GL_COLOR_ATTACHMENT0, colour_.get(), 0);
  glNamedFramebufferTexture(framebuffer_.get(), GL_DEPTH_ATTACHMENT, depth_.get(), 0);
  if (settings.surfaces == atmos::SurfaceMode::gbuffer) {
    albedo_ = gl::create_texture_2d(GL_RGBA16F, w, h);
    normal_ = gl::create_texture_2d(GL_RGBA16F, w, h);
    glNamedFramebufferTexture(framebuffer_.get(), GL_COLOR_ATTACHMENT1, albedo_.get(), 0);
    glNamedFramebufferTexture(framebuffer_.get(), GL_COLOR_ATTACHMENT2, normal_.get(), 0);
    const GLenum buffers[] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
    glNamedFramebufferDrawBuffers(framebuffer_.get(), 3, buffers);
  } else {
    glNamedFramebufferDrawBuffer(framebuffer_.get(), GL_COLOR_ATTACHMENT0);
  }
  gl::check_framebuffer(framebuffer_.get(), "scene");

  if (settings.shadow_map_size > 0) {
    const int s = settings.shadow_map_size;
    shadow_map_ = gl::create_texture_2d(GL_DEPTH_COMPONENT32F, s, s);
    shadow_framebuffer_ = gl::create_framebuffer();
    glNamedFramebufferTexture(shadow_framebuffer_.get(), GL_DEPTH_ATTACHMENT, shadow_map_.get(), 0);
    glNamedFramebufferDrawBuffer(shadow_framebuffer_.get(), GL_NONE);
    glNamedFramebufferReadBuffer(shadow_framebuffer_.get(), GL_NONE);
    gl::check_framebuffer(shadow_framebuffer_.get(), "shadow map");
    // Depth comparison lives in a sampler object, not in the texture: the
    // texture stays a plain depth texture that the plugin can read with its
    // own samplers.
    shadow_sampler_ = gl::create_sampler();
    glSamplerParameteri(shadow_sampler_.get(), GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
    glSamplerParameteri(shadow_sampler_.get(), GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
    glSamplerParameteri(shadow_sampler_.get(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);  // 2x2 PCF in hardware
    glSamplerParameteri(shadow_sampler_.get(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glSamplerParameteri(shadow_sampler_.get(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glSamplerParameteri(shadow_sampler_.get(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
}

SceneRenderer::Mesh SceneRenderer::upload(const MeshData& data) const {
  Mesh mesh;
  mesh.vertices = gl::create_buffer(std::as_bytes(std::span(data.vertices)));
  mesh.indices = gl::create_buffer(std::as_bytes(std::span(data.indices)));
  mesh.index_count = static_cast<GLsizei>(data.indices.size());
  mesh.vertex_array = gl::create_vertex_array();
  const GLuint vao = mesh.vertex_array.get();
  glVertexArrayVertexBuffer(vao, 0, mesh.vertices.get(), 0, sizeof(Vertex));
  glVertexArrayElementBuffer(vao, mesh.indices.get());
  const std::array<GLuint, 3> offsets = {offsetof(Vertex, position), offsetof(Vertex, normal),
                                         offsetof(Vertex, albedo)};
  for (GLuint attribute = 0; attribute < 3; ++attribute) {
    glEnableVertexArrayAttrib(vao, attribute);
    glVertexArrayAttribFormat(vao, attribute, 3, GL_FLOAT, GL_FALSE, offsets[attribute]);
    glVertexArrayAttribBinding(vao, attribute, 0);
  }
  return mesh;
}

const SceneRenderer::Mesh& SceneRenderer::mesh_of(const SceneObject& object) const {
  return object.shape == SceneObject::Shape::box ? box_mesh_ : sphere_mesh_;
}

void SceneRenderer::render_shadow_map(const Scene& scene) {
  if (!shadow_map_.get()) return;
  const glm::dvec3 origin = world_.patch_centre();
  const glm::dvec3 sun = glm::normalize(scene.sun_direction);

  // The sun's view: looking down -sun at the patch centre. An orthographic
  // box fitted to the terrain's bounding box (plus 1 km of headroom for the
  // objects) seen from the sun: every caster is inside, and texels are not
  // wasted — with a low sun the patch is only a few km tall in the map.
  const glm::dvec3 up_hint = std::abs(sun.y) < 0.99 ? glm::dvec3(0.0, 1.0, 0.0) : glm::dvec3(0.0, 0.0, -1.0);
  const glm::dmat4 light_view = glm::lookAt(origin + sun, origin, up_hint);
  const glm::dvec3 lo = terrain_.bounds_min(), hi = terrain_.bounds_max() + glm::dvec3(0.0, kUnitsPerKm, 0.0);
  glm::dvec3 box_min(std::numeric_limits<double>::max()), box_max(std::numeric_limits<double>::lowest());
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 p =
        origin + glm::dvec3((corner & 1) ? hi.x : lo.x, (corner & 2) ? hi.y : lo.y, (corner & 4) ? hi.z : lo.z);
    const glm::dvec3 q(light_view * glm::dvec4(p, 1.0));
    box_min = glm::min(box_min, q);
    box_max = glm::max(box_max, q);
  }
  // In view space the box spans z in [box_min.z, box_max.z] (the sun looks
  // along -z). Its far side reaches 50 km beyond the last caster: the
  // mountains' shadows continue through the air past the patch's edge,
  // where the plugin's light shafts sample them. Not much more: the depth
  // range is also the scale of the shadow tests' depth bias (the plugin
  // compares depths with a bias relative to the map's range).
  const double margin = kUnitsPerKm;
  const double shadow_reach = 50.0 * kUnitsPerKm;
  const glm::dmat4 light_projection =
      glm::ortho(box_min.x, box_max.x, box_min.y, box_max.y, -box_max.z - margin, -box_min.z + shadow_reach);
  shadow_matrix_ = light_projection * light_view;
  shadow_texel_ = std::max(box_max.x - box_min.x, box_max.y - box_min.y) / settings_.shadow_map_size;

  const GLuint program = shadow_program_.get();
  glBindFramebuffer(GL_FRAMEBUFFER, shadow_framebuffer_.get());
  glViewport(0, 0, settings_.shadow_map_size, settings_.shadow_map_size);
  glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);  // the plugin expects a standard [-1, 1] light clip cube
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDepthMask(GL_TRUE);
  glDisable(GL_CULL_FACE);  // the terrain is a single-sided sheet: both sides cast
  glDisable(GL_BLEND);
  // Slope-scaled bias against shadow acne on slopes grazed by a low sun.
  glEnable(GL_POLYGON_OFFSET_FILL);
  glPolygonOffset(2.0f, 2.0f);
  const float clear_depth = 1.0f;
  glClearNamedFramebufferfv(shadow_framebuffer_.get(), GL_DEPTH, 0, &clear_depth);
  glUseProgram(program);

  auto draw = [&](const Mesh& mesh, const glm::dmat4& model) {
    // shadow_matrix x model in double: the light view's translation cancels
    // the object's, leaving patch-sized numbers for the float GPU.
    set_uniform(program, "u_shadow_from_model", shadow_matrix_ * model);
    glBindVertexArray(mesh.vertex_array.get());
    glDrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr);
  };
  draw(terrain_mesh_, glm::translate(glm::dmat4(1.0), origin));
  for (const SceneObject& object : scene.objects) draw(mesh_of(object), object.model);
  glDisable(GL_POLYGON_OFFSET_FILL);
}

void SceneRenderer::render_scene(const Scene& scene, const atmos::AtmospherePass& atmosphere) {
  const Camera& camera = scene.camera;
  const bool reversed = settings_.depth == atmos::DepthEncoding::reversed_z;
  const bool logarithmic = settings_.depth == atmos::DepthEncoding::logarithmic;
  view_ = glm::lookAt(camera.position, camera.position + camera.forward, camera.up);
  projection_ = projection_for(settings_, camera);
  log_depth_far_ = logarithmic ? camera.far : 0.0;
  triangles_ = terrain_mesh_.index_count / 3;
  for (const SceneObject& object : scene.objects) triangles_ += mesh_of(object).index_count / 3;

  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
  glViewport(0, 0, settings_.width, settings_.height);
  glClipControl(GL_LOWER_LEFT, reversed ? GL_ZERO_TO_ONE : GL_NEGATIVE_ONE_TO_ONE);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(reversed ? GL_GREATER : GL_LESS);
  glDepthMask(GL_TRUE);
  glEnable(GL_CULL_FACE);
  glCullFace(GL_BACK);
  glDisable(GL_BLEND);
  // Cleared colour: black, alpha 0 (the plugin decides "sky" from depth
  // alone). Depth: the encoding's far value, which the plugin reads as sky.
  const float black[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  const int attachments = settings_.surfaces == atmos::SurfaceMode::gbuffer ? 3 : 1;
  for (int i = 0; i < attachments; ++i) glClearNamedFramebufferfv(framebuffer_.get(), GL_COLOR, i, black);
  const float clear_depth = reversed ? 0.0f : 1.0f;
  glClearNamedFramebufferfv(framebuffer_.get(), GL_DEPTH, 0, &clear_depth);

  const GLuint program = scene_program_.get();
  glUseProgram(program);
  const glm::dvec3 origin = world_.patch_centre();
  // Per frame. Lighting runs in "patch-relative" world coordinates (world
  // minus the patch centre: small numbers); atmos's functions want
  // planet-centred metres, which are these plus one constant offset.
  set_uniform(program, "u_projection", projection_);
  set_uniform(program, "u_sun_direction", glm::normalize(scene.sun_direction));
  set_uniform(program, "u_patch_centre_planet_m", (origin - world_.planet_centre()) / kUnitsPerMetre);
  set_uniform(program, "u_metres_per_unit", 1.0 / kUnitsPerMetre);
  set_uniform(program, "u_units_per_nit", 1.0 / settings_.nits_per_unit);
  set_uniform(program, "u_log_depth_far", log_depth_far_);
  set_uniform(program, "u_shadows", shadow_map_.get() ? 1 : 0);
  if (settings_.eclipse) {
    // The moons in planet-centred metres, as the plugin gets them
    // (FrameInput::moons); at most atmos::kMaxMoons (the plugin checks).
    const int count = static_cast<int>(std::min<size_t>(scene.moons.size(), atmos::kMaxMoons));
    std::array<float, 4 * atmos::kMaxMoons> spheres{};
    for (int i = 0; i < count; ++i) {
      const atmos::Moon& moon = scene.moons[static_cast<size_t>(i)];
      spheres[4 * i + 0] = static_cast<float>(moon.centre_m.x);
      spheres[4 * i + 1] = static_cast<float>(moon.centre_m.y);
      spheres[4 * i + 2] = static_cast<float>(moon.centre_m.z);
      spheres[4 * i + 3] = static_cast<float>(moon.radius_m);
    }
    set_uniform(program, "u_moon_count", count);
    glProgramUniform4fv(program, gl::uniform(program, "u_moon_spheres"), atmos::kMaxMoons, spheres.data());
  }
  if (shadow_map_.get()) {
    set_uniform(program, "u_shadow_from_patch", shadow_matrix_ * glm::translate(glm::dmat4(1.0), origin));
    // Look the shadow map up 1.5 texels off the surface along its normal:
    // with the polygon offset this removes acne without detaching shadows.
    set_uniform(program, "u_shadow_normal_offset", 1.5 * shadow_texel_);
    glBindTextureUnit(kShadowMapUnit, shadow_map_.get());
    glBindSampler(kShadowMapUnit, shadow_sampler_.get());
  }
  atmosphere.bind_textures(kAtmosphereFirstUnit);

  const glm::dmat4 to_patch = glm::translate(glm::dmat4(1.0), -origin);
  auto draw = [&](const Mesh& mesh, const glm::dmat4& model, const glm::vec3& tint, double detail) {
    // Camera-relative rendering: view x model in double, then float. The
    // translation left is the object's offset from the camera, so vertices
    // near the camera keep sub-millimetre precision wherever the camera is.
    set_uniform(program, "u_model_view", view_ * model);
    set_uniform(program, "u_model_patch", to_patch * model);
    set_uniform(program, "u_normal_matrix", glm::inverseTranspose(glm::dmat3(model)));
    set_uniform(program, "u_tint", tint);
    set_uniform(program, "u_detail", detail);
    glBindVertexArray(mesh.vertex_array.get());
    glDrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr);
  };
  draw(terrain_mesh_, glm::translate(glm::dmat4(1.0), origin), glm::vec3(1.0f), 1.0);
  for (const SceneObject& object : scene.objects) draw(mesh_of(object), object.model, object.albedo, 0.0);

  // Back to GL's default clip control, and the shadow sampler unbound: the
  // state the next user of the context (here: the plugin) assumes.
  glClipControl(GL_LOWER_LEFT, GL_NEGATIVE_ONE_TO_ONE);
  glBindSampler(kShadowMapUnit, 0);
}

}  // namespace engine
