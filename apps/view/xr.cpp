#include "xr.hpp"

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <fstream>
#include <string>

#include "atmos/atmosphere.hpp"

namespace atmos_view {

atmos::Eye eye_in_planet(const CameraPose& head, const EyeView& view) {
  // Tracking axes in the planet frame: x right, y up, z backwards.
  const glm::dvec3 forward = glm::normalize(head.forward);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, head.up));
  const glm::dvec3 up = glm::cross(right, forward);
  const auto planet = [&](const glm::dvec3& v) { return right * v.x + up * v.y - forward * v.z; };
  const glm::dquat q = glm::normalize(view.orientation);
  atmos::Eye eye;
  eye.position = head.position + planet(view.position_m);
  eye.forward = planet(q * glm::dvec3(0.0, 0.0, -1.0));
  eye.up = planet(q * glm::dvec3(0.0, 1.0, 0.0));
  eye.fov = view.fov;
  return eye;
}

HeadsetRenderer::~HeadsetRenderer() {
  if (display_[0]) glDeleteTextures(2, display_.data());
}

bool HeadsetRenderer::frame(ViewProvider& provider, Scene& scene, atmos::PostProcess& post, const SceneFrame& f,
                            const atmos::PostSettings& settings, double dt_s) {
  const std::optional<HeadsetFrame> views = provider.begin_frame();
  if (!views) return false;
  if (views->render) {
    const int width = provider.eye_width(), height = provider.eye_height();
    if (width != width_ || height != height_) {
      if (display_[0]) glDeleteTextures(2, display_.data());
      glCreateTextures(GL_TEXTURE_2D, 2, display_.data());
      for (GLuint t : display_) glTextureStorage2D(t, 1, GL_RGBA8, width, height);
      width_ = width;
      height_ = height;
    }
    for (size_t i = 0; i < 2; ++i) eyes_[i] = eye_in_planet(f.pose, views->eyes[i]);
    SceneFrame sf = f;
    sf.width = width;
    sf.height = height;
    const std::array<GLuint, 2> hdr = scene.render_eyes(sf, eyes_);
    for (int i = 0; i < 2; ++i) {
      atmos::PostInput in;
      in.colour = hdr[size_t(i)];
      in.width = width;
      in.height = height;
      in.nits_per_unit = Scene::kNitsPerUnit;
      // The eye adaptation advances once a frame, on the left eye; the
      // right eye is exposed as the left.
      in.dt_s = i == 0 ? dt_s : 0.0;
      in.output = display_[size_t(i)];
      post.process(in, settings);
      provider.submit_eye(i, hdr[size_t(i)], display_[size_t(i)]);
    }
  }
  provider.end_frame();
  return true;
}

// ---------------------------------------------------------------------------
// The mock

MockViewProvider::MockViewProvider(const std::array<EyeView, 2>& eyes, int width, int height, int frames)
    : eyes_(eyes), width_(width), height_(height), frames_(frames) {
  if (width < 1 || height < 1 || width > 8192 || height > 8192)
    throw atmos::Error("mock headset: eye size " + std::to_string(width) + "x" + std::to_string(height) +
                       " is not in [1, 8192]");
  if (frames < 1) throw atmos::Error("mock headset: frames must be >= 1, got " + std::to_string(frames));
  for (const EyeView& e : eyes) {
    (void)atmos::reversed_z_projection(e.fov, Scene::kNearM);  // checks the four angles
    const double length = glm::length(e.orientation);
    if (!std::isfinite(glm::length(e.position_m)) || !(std::abs(length - 1.0) < 1e-3))
      throw atmos::Error("mock headset: an eye's position is not finite or its orientation is not a unit quaternion");
  }
}

MockViewProvider MockViewProvider::read(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw atmos::Error("mock headset " + path + ": cannot open the file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw atmos::Error("mock headset " + path + ": not JSON (" + e.what() + ")");
  }
  const auto fail = [&path](const std::string& what) { return atmos::Error("mock headset " + path + ": " + what); };
  const auto number = [&](const nlohmann::json& o, const char* key, const std::string& where) {
    if (!o.is_object() || !o.contains(key) || !o[key].is_number()) throw fail(where + key + " must be a number");
    return o[key].get<double>();
  };
  const auto numbers = [&](const nlohmann::json& o, const char* key, size_t n, const std::string& where) {
    if (!o.contains(key) || !o[key].is_array() || o[key].size() != n)
      throw fail(where + key + " must be an array of " + std::to_string(n) + " numbers");
    std::vector<double> v;
    for (const nlohmann::json& x : o[key]) {
      if (!x.is_number()) throw fail(where + key + " must be an array of " + std::to_string(n) + " numbers");
      v.push_back(x.get<double>());
    }
    return v;
  };
  if (!j.contains("eyes") || !j["eyes"].is_array() || j["eyes"].size() != 2)
    throw fail("eyes must be an array of two eyes (left, right)");
  std::array<EyeView, 2> eyes;
  for (size_t i = 0; i < 2; ++i) {
    const nlohmann::json& e = j["eyes"][i];
    const std::string where = "eyes[" + std::to_string(i) + "].";
    if (!e.is_object()) throw fail("eyes[" + std::to_string(i) + "] must be an object");
    const std::vector<double> p = numbers(e, "position_m", 3, where);
    eyes[i].position_m = {p[0], p[1], p[2]};
    const std::vector<double> q = numbers(e, "orientation_wxyz", 4, where);
    eyes[i].orientation = glm::dquat(q[0], q[1], q[2], q[3]);
    if (!e.contains("fov_deg")) throw fail(where + "fov_deg must be an object with left, right, up, down");
    const std::string fov_where = where + "fov_deg.";
    const auto fov_rad = [&](const char* side) { return number(e["fov_deg"], side, fov_where) * (M_PI / 180.0); };
    eyes[i].fov = {fov_rad("left"), fov_rad("right"), fov_rad("up"), fov_rad("down")};
  }
  const auto integer = [&](const char* key, double fallback) {
    const double v = j.contains(key) ? number(j, key, "") : fallback;
    if (v != std::floor(v) || std::abs(v) > 1e6) throw fail(std::string(key) + " must be an integer");
    return int(v);
  };
  try {
    return MockViewProvider(eyes, integer("width", 0), integer("height", 0), integer("frames", 1));
  } catch (const atmos::Error& e) {
    throw fail(e.what());
  }
}

std::optional<HeadsetFrame> MockViewProvider::begin_frame() {
  if (begun_ >= frames_) return std::nullopt;
  ++begun_;
  HeadsetFrame f;
  f.eyes = eyes_;
  return f;
}

void MockViewProvider::submit_eye(int eye, GLuint hdr, GLuint display) {
  hdr_[size_t(eye)] = read_hdr(hdr, width_, height_);
  display_[size_t(eye)] = read_display(display, width_, height_);
}

void MockViewProvider::end_frame() { ++ended_; }

#ifndef ATMOS_OPENXR
std::unique_ptr<OpenXrProvider> make_openxr_provider() {
  throw atmos::Error(
      "atmos view --xr: atmos was built without OpenXR (libopenxr-dev was missing when it was configured, or "
      "-DATMOS_OPENXR=OFF; bash scripts/setup.sh installs it)");
}
bool built_with_openxr() { return false; }
#endif

// ---------------------------------------------------------------------------
// Stereo layouts

namespace {

// side_by_side: the left eye's pixel x at x, the right eye's at width + x;
// anaglyph: red from the left eye, green and blue from the right.
constexpr const char* kComposeShader = R"(#version 450 core
layout(local_size_x = 8, local_size_y = 8) in;
layout(binding = 0) uniform sampler2D left_eye;
layout(binding = 1) uniform sampler2D right_eye;
layout(binding = 0, rgba32f) uniform writeonly image2D composed;
uniform int anaglyph;
uniform int eye_width;
void main() {
  ivec2 p = ivec2(gl_GlobalInvocationID.xy);
  if (any(greaterThanEqual(p, imageSize(composed)))) return;
  vec4 c;
  if (anaglyph != 0) {
    c = vec4(texelFetch(left_eye, p, 0).r, texelFetch(right_eye, p, 0).gb, 1.0);
  } else {
    c = p.x < eye_width ? texelFetch(left_eye, p, 0) : texelFetch(right_eye, ivec2(p.x - eye_width, p.y), 0);
  }
  imageStore(composed, p, c);
}
)";

}  // namespace

StereoComposer::StereoComposer() {
  const GLuint shader = glCreateShader(GL_COMPUTE_SHADER);
  glShaderSource(shader, 1, &kComposeShader, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[1024] = {};
    glGetShaderInfoLog(shader, sizeof log, nullptr, log);
    glDeleteShader(shader);
    throw atmos::Error(std::string("stereo layout shader: ") + log);
  }
  program_ = glCreateProgram();
  glAttachShader(program_, shader);
  glLinkProgram(program_);
  glDeleteShader(shader);
  glGetProgramiv(program_, GL_LINK_STATUS, &ok);
  if (!ok) {
    glDeleteProgram(program_);
    throw atmos::Error("stereo layout shader: the program does not link");
  }
}

StereoComposer::~StereoComposer() {
  if (output_) glDeleteTextures(1, &output_);
  glDeleteProgram(program_);
}

GLuint StereoComposer::compose(Layout layout, GLuint left, GLuint right, int width, int height) {
  const int out_width = layout == Layout::side_by_side ? 2 * width : width;
  if (out_width != width_ || height != height_) {
    if (output_) glDeleteTextures(1, &output_);
    glCreateTextures(GL_TEXTURE_2D, 1, &output_);
    glTextureStorage2D(output_, 1, GL_RGBA32F, out_width, height);
    width_ = out_width;
    height_ = height;
  }
  glUseProgram(program_);
  glUniform1i(glGetUniformLocation(program_, "anaglyph"), layout == Layout::anaglyph ? 1 : 0);
  glUniform1i(glGetUniformLocation(program_, "eye_width"), width);
  glBindTextureUnit(0, left);
  glBindTextureUnit(1, right);
  glBindImageTexture(0, output_, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  glDispatchCompute(GLuint((out_width + 7) / 8), GLuint((height + 7) / 8), 1);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT |
                  GL_PIXEL_BUFFER_BARRIER_BIT);
  glBindImageTexture(0, 0, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  return output_;
}

}  // namespace atmos_view
