#include "scene.hpp"

#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace atmos_view {

namespace {

atmos::GlobeSettings globe_settings(bool complete_tiles) {
  atmos::GlobeSettings s;
  s.complete_every_frame = complete_tiles;
  return s;
}

// The pass's input for a frame, without its textures.
atmos::FrameInput frame_input(const SceneFrame& f, int width, int height, const glm::dmat4& view,
                              const glm::dmat4& projection) {
  atmos::FrameInput input;
  input.width = width;
  input.height = height;
  input.depth_encoding = atmos::DepthEncoding::reversed_z;
  input.view = view;
  input.projection = projection;
  input.sun_direction = f.sun;
  input.nits_per_unit = Scene::kNitsPerUnit;
  input.stars = f.stars;
  input.moons = f.moons;
  input.timed = f.timed;
  return input;
}

// The pass of the tables, exact or instant.
std::unique_ptr<atmos::AtmospherePass> make_pass(const PlanetTables& t, atmos::PassPrograms programs) {
  if (t.instant) return std::make_unique<atmos::AtmospherePass>(t.air, *t.instant, atmos::PlanetFrame{}, programs);
  return std::make_unique<atmos::AtmospherePass>(t.air, t.tables, atmos::PlanetFrame{}, programs);
}

// Whether the tables respond to the ground's albedo (the instant mode's do not).
bool has_ground_response(const PlanetTables& t) { return !t.instant && !t.tables.ground_response.empty(); }

glm::dmat4 view_of(const SceneFrame& f) {
  return glm::lookAt(f.pose.position, f.pose.position + f.pose.forward, f.pose.up);
}

glm::dmat4 projection_of(const SceneFrame& f) {
  return atmos::reversed_z_projection(f.fov_deg * M_PI / 180.0, double(f.width) / double(f.height), Scene::kNearM);
}

}  // namespace

Scene::Scene(const PlanetTables& t, bool globe, bool regional_albedo, bool complete_tiles, atmos::PassPrograms programs,
             const EarlyLink* early)
    : params_(t.params), planet_(t.planet), surface_(t.surface), terrain_ms_(std::numeric_limits<double>::quiet_NaN()) {
  pass_ = make_pass(t, programs);
  if (early) start_linker(*pass_, *early, false);
  try {
    if (globe) globe_ = std::make_unique<atmos::Globe>(t.planet, t.surface, *pass_, globe_settings(complete_tiles));
  } catch (...) {
    if (linker_.joinable()) linker_.join();
    throw;
  }
  regional_albedo_requested_ = globe && regional_albedo;
  regional_albedo_ = regional_albedo_requested_ && has_ground_response(t);
  glCreateQueries(GL_TIME_ELAPSED, kQueries, queries_.data());
}

void Scene::start_linker(atmos::AtmospherePass& pass, const EarlyLink& early, bool globe_programs) {
  join_linker();
  // The frame's targets first (this thread is the GL one), so that the
  // programs are compiled for their formats.
  ensure_targets(targets_[0], early.frame.width, early.frame.height);
  const atmos::FrameInput input = link_input(early.frame);
  linking_ = true;
  atmos::Globe* globe = globe_programs ? globe_.get() : nullptr;
  linker_ = std::thread([this, &pass, globe, make_current = early.make_current, input] {
    make_current(true);
    try {
      pass.link_programs(input);
      if (globe) globe->link_rebind_programs(pass);
    } catch (...) {
      linker_error_ = std::current_exception();
    }
    make_current(false);
    linking_ = false;
  });
}

bool Scene::programs_linked(const SceneFrame& f) const {
  const atmos::AtmospherePass& pass = next_pass_ ? *next_pass_ : *pass_;
  return pass.programs_linked(frame_input(f, f.width, f.height, view_of(f), projection_of(f)));
}

bool Scene::prepare_rebind(const PlanetTables& t, const EarlyLink* early) {
  if (!globe_ || !(t.surface == surface_) || t.planet.bottom_radius_m != planet_.bottom_radius_m) return false;
  next_pass_ = make_pass(t, early ? atmos::PassPrograms::none : atmos::PassPrograms::common);
  if (early) start_linker(*next_pass_, *early, true);
  next_params_ = t.params;
  next_planet_ = t.planet;
  next_regional_albedo_ = regional_albedo_requested_ && has_ground_response(t);
  return true;
}

void Scene::finish_rebind() {
  try {
    join_linker();
  } catch (...) {
    next_pass_.reset();
    throw;
  }
  std::unique_ptr<atmos::AtmospherePass> pass = std::move(next_pass_);
  globe_->rebind(next_planet_, *pass);
  pass_ = std::move(pass);
  params_ = next_params_;
  planet_ = next_planet_;
  regional_albedo_ = next_regional_albedo_;
}

void Scene::join_linker() {
  if (linker_.joinable()) linker_.join();
  if (linker_error_) {
    const std::exception_ptr error = linker_error_;
    linker_error_ = nullptr;
    std::rethrow_exception(error);
  }
}

Scene::~Scene() {
  if (linker_.joinable()) linker_.join();
  for (Targets& t : targets_) release_targets(t);
  glDeleteQueries(kQueries, queries_.data());
}

void Scene::release_targets(Targets& t) {
  if (t.framebuffer) glDeleteFramebuffers(1, &t.framebuffer);
  const GLuint textures[] = {t.colour, t.depth, t.output};
  if (t.colour) glDeleteTextures(3, textures);
  t = Targets{};
}

void Scene::ensure_targets(Targets& t, int width, int height) {
  if (width == t.width && height == t.height) return;
  release_targets(t);
  glCreateTextures(GL_TEXTURE_2D, 1, &t.colour);
  glTextureStorage2D(t.colour, 1, GL_RGBA32F, width, height);
  glCreateTextures(GL_TEXTURE_2D, 1, &t.depth);
  glTextureStorage2D(t.depth, 1, GL_DEPTH_COMPONENT32F, width, height);
  glCreateTextures(GL_TEXTURE_2D, 1, &t.output);
  glTextureStorage2D(t.output, 1, GL_RGBA32F, width, height);
  glCreateFramebuffers(1, &t.framebuffer);
  glNamedFramebufferTexture(t.framebuffer, GL_COLOR_ATTACHMENT0, t.colour, 0);
  glNamedFramebufferTexture(t.framebuffer, GL_DEPTH_ATTACHMENT, t.depth, 0);
  t.width = width;
  t.height = height;
}

double Scene::ground_height_m(const glm::dvec3& position) const {
  return globe_ ? globe_->height_m(position) : 0.0;
}

const atmos::GlobeStats* Scene::globe_stats() const { return globe_ ? &globe_->last_stats() : nullptr; }

const atmos::PassTimings& Scene::pass_timings() const { return pass_->last_timings(); }

GLuint Scene::next_query() {
  // The oldest query of the ring: issued kQueries - 1 frames ago.
  GLuint query = queries_[size_t(query_next_)];
  if (query_pending_[size_t(query_next_)]) {
    GLint available = 0;
    glGetQueryObjectiv(query, GL_QUERY_RESULT_AVAILABLE, &available);
    if (available) {
      GLuint64 ns = 0;
      glGetQueryObjectui64v(query, GL_QUERY_RESULT, &ns);
      terrain_ms_ = double(ns) * 1e-6;
    }
  }
  query_pending_[size_t(query_next_)] = true;
  query_next_ = (query_next_ + 1) % kQueries;
  return query;
}

namespace {

void clear(GLuint framebuffer) {
  const float clear_colour[4] = {0, 0, 0, 0};
  const float clear_depth = 0.0f;
  glClearNamedFramebufferfv(framebuffer, GL_COLOR, 0, clear_colour);
  glClearNamedFramebufferfv(framebuffer, GL_DEPTH, 0, &clear_depth);
}

atmos::GlobeView globe_view(const SceneFrame& f, const glm::dmat4& view, const glm::dmat4& projection, int width,
                            int height) {
  atmos::GlobeView gv;
  gv.view = view;
  gv.projection = projection;
  gv.width = width;
  gv.height = height;
  gv.sun_direction = f.sun;
  gv.nits_per_unit = Scene::kNitsPerUnit;
  gv.moons = f.moons;
  return gv;
}

}  // namespace

GLuint Scene::composite(const SceneFrame& f, Targets& t, const glm::dmat4& view, const glm::dmat4& projection) {
  atmos::FrameInput input = frame_input(f, t.width, t.height, view, projection);
  input.colour = t.colour;
  input.depth = t.depth;
  input.output = t.output;
  return pass_->render(input);
}

void Scene::link_programs(const SceneFrame& f) const { link_programs(link_input(f)); }

atmos::FrameInput Scene::link_input(const SceneFrame& f) const {
  atmos::FrameInput input = frame_input(f, f.width, f.height, view_of(f), projection_of(f));
  const Targets& t = targets_[0];
  if (t.width == f.width && t.height == f.height) {
    input.colour = t.colour;
    input.depth = t.depth;
    input.output = t.output;
  }
  return input;
}

void Scene::link_programs(const atmos::FrameInput& input) const { pass_->link_programs(input); }

GLuint Scene::render(const SceneFrame& f) {
  Targets& t = targets_[0];
  ensure_targets(t, f.width, f.height);
  const glm::dmat4 view = view_of(f);
  const glm::dmat4 projection = projection_of(f);
  clear(t.framebuffer);
  if (globe_) {
    const GLuint query = next_query();
    glBindFramebuffer(GL_FRAMEBUFFER, t.framebuffer);
    glViewport(0, 0, f.width, f.height);
    // The air lit by the ground around the camera, before the globe's draw
    // (which lights its ground with the pass's sky light).
    if (regional_albedo_) pass_->set_ground_albedo(globe_->regional_albedo(f.pose.position));
    glBeginQuery(GL_TIME_ELAPSED, query);
    globe_->draw(globe_view(f, view, projection, f.width, f.height));
    glEndQuery(GL_TIME_ELAPSED);
  }
  return composite(f, t, view, projection);
}

std::array<GLuint, 2> Scene::render_eyes(const SceneFrame& f, const std::array<atmos::Eye, 2>& eyes) {
  std::array<glm::dmat4, 2> views, projections;
  for (size_t i = 0; i < 2; ++i) {
    ensure_targets(targets_[i], f.width, f.height);
    clear(targets_[i].framebuffer);
    views[i] = atmos::view_matrix(eyes[i]);
    projections[i] = atmos::reversed_z_projection(eyes[i].fov, kNearM);
  }
  if (globe_) {
    // The tiles of both eyes from one frustum that holds both, at the
    // eyes' finest pixel density (pixels per unit of tangent).
    const atmos::Eye cover = atmos::covering_eye(eyes);
    const auto span = [](double a, double b) { return std::tan(b) - std::tan(a); };
    double per_tangent_x = 0.0, per_tangent_y = 0.0;
    for (const atmos::Eye& e : eyes) {
      per_tangent_x = std::max(per_tangent_x, f.width / span(e.fov.left_rad, e.fov.right_rad));
      per_tangent_y = std::max(per_tangent_y, f.height / span(e.fov.down_rad, e.fov.up_rad));
    }
    const int lod_width = int(std::ceil(per_tangent_x * span(cover.fov.left_rad, cover.fov.right_rad)));
    const int lod_height = int(std::ceil(per_tangent_y * span(cover.fov.down_rad, cover.fov.up_rad)));
    const atmos::GlobeView lod = globe_view(f, atmos::view_matrix(cover),
                                            atmos::reversed_z_projection(cover.fov, kNearM), lod_width, lod_height);
    const std::vector<atmos::GlobeView> eye_views = {globe_view(f, views[0], projections[0], f.width, f.height),
                                                     globe_view(f, views[1], projections[1], f.width, f.height)};
    const GLuint query = next_query();
    if (regional_albedo_) pass_->set_ground_albedo(globe_->regional_albedo(0.5 * (eyes[0].position + eyes[1].position)));
    glBeginQuery(GL_TIME_ELAPSED, query);
    globe_->draw_views(lod, eye_views,
                       [this](std::size_t i) { glBindFramebuffer(GL_FRAMEBUFFER, targets_[i].framebuffer); });
    glEndQuery(GL_TIME_ELAPSED);
  }
  return {composite(f, targets_[0], views[0], projections[0]), composite(f, targets_[1], views[1], projections[1])};
}

atmos::Image read_hdr(GLuint texture, int width, int height) {
  atmos::Image image = atmos::read_linear_image(texture, width, height);
  flip_rows(image.rgb, width, height);
  for (float& v : image.rgb) v = float(double(v) * Scene::kNitsPerUnit);
  return image;
}

atmos::DisplayImage read_display(GLuint texture, int width, int height) {
  atmos::DisplayImage image = atmos::read_display_image(texture, width, height);
  flip_rows(image.rgb, width, height);
  return image;
}

}  // namespace atmos_view
