#include "scene.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <cmath>
#include <limits>

namespace atmos_view {

namespace {

// Near plane of the reversed-Z projection, m: the camera may stand half a
// metre above the ground (Flight::kMinClearanceM); reversed-Z float depth
// keeps the far field exact.
constexpr double kNearM = 0.05;

atmos::GlobeSettings globe_settings(bool complete_tiles) {
  atmos::GlobeSettings s;
  s.complete_every_frame = complete_tiles;
  return s;
}

}  // namespace

Scene::Scene(const PlanetTables& t, bool globe, bool regional_albedo, bool complete_tiles)
    : params_(t.params), planet_(t.planet), surface_(t.surface), terrain_ms_(std::numeric_limits<double>::quiet_NaN()) {
  pass_ = std::make_unique<atmos::AtmospherePass>(t.air, t.tables, atmos::PlanetFrame{});
  if (globe) globe_ = std::make_unique<atmos::Globe>(t.planet, t.surface, *pass_, globe_settings(complete_tiles));
  regional_albedo_requested_ = globe && regional_albedo;
  regional_albedo_ = regional_albedo_requested_ && !t.tables.ground_response.empty();
  glCreateQueries(GL_TIME_ELAPSED, kQueries, queries_.data());
}

bool Scene::prepare_rebind(const PlanetTables& t) {
  if (!globe_ || !(t.surface == surface_) || t.planet.bottom_radius_m != planet_.bottom_radius_m) return false;
  next_pass_ = std::make_unique<atmos::AtmospherePass>(t.air, t.tables, atmos::PlanetFrame{});
  next_params_ = t.params;
  next_planet_ = t.planet;
  next_regional_albedo_ = regional_albedo_requested_ && !t.tables.ground_response.empty();
  return true;
}

void Scene::finish_rebind() {
  std::unique_ptr<atmos::AtmospherePass> pass = std::move(next_pass_);
  globe_->rebind(next_planet_, *pass);
  pass_ = std::move(pass);
  params_ = next_params_;
  planet_ = next_planet_;
  regional_albedo_ = next_regional_albedo_;
}

Scene::~Scene() {
  release_targets();
  glDeleteQueries(kQueries, queries_.data());
}

void Scene::release_targets() {
  if (framebuffer_) glDeleteFramebuffers(1, &framebuffer_);
  const GLuint textures[] = {colour_, depth_, output_};
  if (colour_) glDeleteTextures(3, textures);
  framebuffer_ = colour_ = depth_ = output_ = 0;
  width_ = height_ = 0;
}

void Scene::ensure_targets(int width, int height) {
  if (width == width_ && height == height_) return;
  release_targets();
  glCreateTextures(GL_TEXTURE_2D, 1, &colour_);
  glTextureStorage2D(colour_, 1, GL_RGBA32F, width, height);
  glCreateTextures(GL_TEXTURE_2D, 1, &depth_);
  glTextureStorage2D(depth_, 1, GL_DEPTH_COMPONENT32F, width, height);
  glCreateTextures(GL_TEXTURE_2D, 1, &output_);
  glTextureStorage2D(output_, 1, GL_RGBA32F, width, height);
  glCreateFramebuffers(1, &framebuffer_);
  glNamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, colour_, 0);
  glNamedFramebufferTexture(framebuffer_, GL_DEPTH_ATTACHMENT, depth_, 0);
  width_ = width;
  height_ = height;
}

double Scene::ground_height_m(const glm::dvec3& position) const {
  return globe_ ? globe_->height_m(position) : 0.0;
}

const atmos::GlobeStats* Scene::globe_stats() const { return globe_ ? &globe_->last_stats() : nullptr; }

const atmos::PassTimings& Scene::pass_timings() const { return pass_->last_timings(); }

GLuint Scene::render(const SceneFrame& f) {
  ensure_targets(f.width, f.height);
  const double fov = f.fov_deg * M_PI / 180.0;
  const glm::dmat4 view = glm::lookAt(f.pose.position, f.pose.position + f.pose.forward, f.pose.up);
  const glm::dmat4 projection = atmos::reversed_z_projection(fov, double(f.width) / double(f.height), kNearM);

  const float clear_colour[4] = {0, 0, 0, 0};
  const float clear_depth = 0.0f;
  glClearNamedFramebufferfv(framebuffer_, GL_COLOR, 0, clear_colour);
  glClearNamedFramebufferfv(framebuffer_, GL_DEPTH, 0, &clear_depth);
  if (globe_) {
    // The oldest query of the ring: issued kQueries - 1 frames ago.
    GLuint& query = queries_[size_t(query_next_)];
    if (query_pending_[size_t(query_next_)]) {
      GLint available = 0;
      glGetQueryObjectiv(query, GL_QUERY_RESULT_AVAILABLE, &available);
      if (available) {
        GLuint64 ns = 0;
        glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
        terrain_ms_ = double(ns) * 1e-6;
      }
    }
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
    glViewport(0, 0, f.width, f.height);
    // The air lit by the ground around the camera, before the globe's draw
    // (which lights its ground with the pass's sky light).
    if (regional_albedo_) pass_->set_ground_albedo(globe_->regional_albedo(f.pose.position));
    atmos::GlobeView gv;
    gv.view = view;
    gv.projection = projection;
    gv.width = f.width;
    gv.height = f.height;
    gv.sun_direction = f.sun;
    gv.nits_per_unit = kNitsPerUnit;
    gv.moons = f.moons;
    glBeginQuery(GL_TIME_ELAPSED, query);
    globe_->draw(gv);
    glEndQuery(GL_TIME_ELAPSED);
    query_pending_[size_t(query_next_)] = true;
    query_next_ = (query_next_ + 1) % kQueries;
  }

  atmos::FrameInput input;
  input.colour = colour_;
  input.depth = depth_;
  input.width = f.width;
  input.height = f.height;
  input.depth_encoding = atmos::DepthEncoding::reversed_z;
  input.view = view;
  input.projection = projection;
  input.sun_direction = f.sun;
  input.nits_per_unit = kNitsPerUnit;
  input.stars = f.stars;
  input.moons = f.moons;
  input.timed = f.timed;
  input.output = output_;
  return pass_->render(input);
}

}  // namespace atmos_view
