// The OpenGL renderer and its CPU twin.
//
// Both evaluate radiance_along_view_ray (physics/functions.glsl) for the rays
// of camera_view_ray (gpu/camera.glsl) with the same parameters, the same
// tables and the same float inputs (camera frame, pixel centres, sun
// direction, colour matrix), which this file computes once for both.
#include <epoxy/gl.h>

#include <glm/gtc/packing.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/colour.hpp"
#include "atmos/renderer.hpp"
#include "gpu/camera_cpp.hpp"
#include "gpu/shader_source.hpp"
#include "physics/parameters.hpp"
#include "precompute/samplers.hpp"

namespace atmos {

namespace {

constexpr int kMaxImageSize = 16384;
// The GPU draws the image in tiles of at most this size: the read-back buffer
// stays small (64 MiB) for any image size, and no single draw runs long
// enough to trip a desktop driver's watchdog.
constexpr int kTileSize = 2048;

bool is_finite(const glm::dvec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string to_string(const glm::dvec3& v) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "(%g, %g, %g)", v.x, v.y, v.z);
  return buffer;
}

std::string to_string(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}

// The camera as both renderers see it: float position and orthonormal basis
// (computed in double, then rounded once), pixel grid and projection.
struct CameraFrame {
  glm::vec3 position;
  glm::vec3 right;
  glm::vec3 up;
  glm::vec3 forward;
  glm::vec2 image_size;
  float fov_deg;
  int projection;
};

CameraFrame camera_frame(const Camera& camera) {
  validate_camera(camera);
  const glm::dvec3 forward = glm::normalize(camera.forward);
  const glm::dvec3 right = glm::normalize(glm::cross(forward, camera.up));
  const glm::dvec3 up = glm::cross(right, forward);
  CameraFrame frame;
  frame.position = glm::vec3(camera.position);
  frame.right = glm::vec3(right);
  frame.up = glm::vec3(up);
  frame.forward = glm::vec3(forward);
  frame.image_size = glm::vec2(float(camera.width), float(camera.height));
  frame.fov_deg = float(camera.fov_deg);
  switch (camera.projection) {
    case Projection::perspective: frame.projection = PROJECTION_PERSPECTIVE; break;
    case Projection::fisheye: frame.projection = PROJECTION_FISHEYE; break;
    case Projection::equirect: frame.projection = PROJECTION_EQUIRECT; break;
    default: throw Error("invalid camera: unknown projection");
  }
  return frame;
}

glm::vec3 sun_vector(const glm::dvec3& sun_direction) {
  if (!is_finite(sun_direction) || glm::length(sun_direction) == 0.0)
    throw Error("invalid sun direction " + to_string(sun_direction) + ": need a finite, non-zero vector");
  return glm::vec3(glm::normalize(sun_direction));
}

glm::mat3 srgb_matrix(const Tables& tables) { return physics::channels_to_srgb_matrix(tables.wavelengths_nm); }

// --- OpenGL helpers -------------------------------------------------------

// One line out of a compiler info log: the first error lines, with the line
// numbers of the assembled source mapped back to the files
// ("0:1234(12): error: ..." -> "functions.glsl:57(12): error: ...";
// also NVIDIA's "0(1234) : error" and AMD's "ERROR: 0:1234:").
std::string summarize_log(const std::string& log, const gpu::AssembledSource* source) {
  auto digits_end = [](const std::string& s, size_t i) {
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    return i;
  };
  std::vector<std::string> errors;
  std::vector<std::string> others;
  std::istringstream lines(log);
  std::string line;
  while (std::getline(lines, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty()) continue;
    // "<string>:<line>" or "<string>(<line>" at the start, after an optional "ERROR: ".
    const size_t start = line.rfind("ERROR: ", 0) == 0 ? 7 : 0;
    const size_t separator = digits_end(line, start);
    if (source != nullptr && separator > start && separator < line.size() &&
        (line[separator] == ':' || line[separator] == '(')) {
      const size_t end = digits_end(line, separator + 1);
      if (end > separator + 1 && end - separator <= 9) {
        std::string where = source->locate(std::stoi(line.substr(separator + 1, end - separator - 1)));
        if (line[separator] == '(') where[where.rfind(':')] = '(';  // NVIDIA style: "file(line) : error"
        line = line.substr(0, start) + where + line.substr(end);
      }
    }
    (line.find("error") != std::string::npos || line.find("ERROR") != std::string::npos ? errors : others)
        .push_back(line);
  }
  const std::vector<std::string>& chosen = errors.empty() ? others : errors;
  std::string s;
  for (size_t i = 0; i < chosen.size() && i < 2; ++i) s += (i > 0 ? " | " : "") + chosen[i];
  if (s.empty()) s = "(empty info log)";
  return s;
}

GLuint compile_shader(GLenum type, const gpu::AssembledSource& source, const char* what) {
  GLuint shader = glCreateShader(type);
  const char* text = source.text.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error(std::string(what) + " shader does not compile: " + summarize_log(log.c_str(), &source));
  }
  return shader;
}

GLuint link_program(const gpu::AssembledSource& vertex_source, const gpu::AssembledSource& fragment_source) {
  GLuint vertex = compile_shader(GL_VERTEX_SHADER, vertex_source, "vertex");
  GLuint fragment = 0;
  try {
    fragment = compile_shader(GL_FRAGMENT_SHADER, fragment_source, "fragment");
  } catch (...) {
    glDeleteShader(vertex);
    throw;
  }
  GLuint program = glCreateProgram();
  glAttachShader(program, vertex);
  glAttachShader(program, fragment);
  glLinkProgram(program);
  // The program keeps the compiled code; the shader objects can go.
  glDeleteShader(vertex);
  glDeleteShader(fragment);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error("shader program does not link: " + summarize_log(log.c_str(), nullptr));
  }
  return program;
}

void set_table_sampling(GLuint texture) {
  // GL_LINEAR + CLAMP_TO_EDGE is the arithmetic that physics/shader_cpp.hpp
  // reproduces on the CPU; no mipmaps (the lookups are not minified images).
  glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

// Texel data for an upload: floats as they are, or rounded to half floats on
// the CPU (glm::packHalf1x16, round to nearest). Rounding here rather than in
// the driver makes the GPU's texels the same on every driver, and lets the
// tests give the CPU twin exactly the same half-rounded tables.
struct TexelData {
  GLenum type = GL_FLOAT;
  const void* pixels = nullptr;
  std::vector<std::uint16_t> halves;
};

TexelData texel_data(const std::vector<glm::vec3>& texels, GLenum internal_format) {
  TexelData data;
  if (internal_format != GL_RGB16F) {
    data.pixels = texels.data();
    return data;
  }
  data.type = GL_HALF_FLOAT;
  data.halves.resize(texels.size() * 3);
  for (size_t i = 0; i < texels.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      const float value = texels[i][c];
      if (!(std::abs(value) <= 65504.0f))
        throw Error("table value " + to_string(double(value)) +
                    " is outside the half-float range; render with full texture precision");
      data.halves[3 * i + size_t(c)] = glm::packHalf1x16(value);
    }
  }
  data.pixels = data.halves.data();
  return data;
}

GLuint make_texture_2d(int width, int height, const std::vector<glm::vec3>& texels, GLenum internal_format) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (width > max_size || height > max_size)
    throw Error("table of " + std::to_string(width) + "x" + std::to_string(height) +
                " texels exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(max_size));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  // Rows of RGB half floats are 6 bytes per texel: not always 4-byte aligned.
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureStorage2D(texture, 1, internal_format, width, height);
  const TexelData data = texel_data(texels, internal_format);
  glTextureSubImage2D(texture, 0, 0, 0, width, height, GL_RGB, data.type, data.pixels);
  set_table_sampling(texture);
  return texture;
}

GLuint make_texture_3d(int width, int height, int depth, const std::vector<glm::vec3>& texels,
                       GLenum internal_format) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_size);
  if (width > max_size || height > max_size || depth > max_size)
    throw Error("table of " + std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(depth) +
                " texels exceeds GL_MAX_3D_TEXTURE_SIZE " + std::to_string(max_size));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_3D, 1, &texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureStorage3D(texture, 1, internal_format, width, height, depth);
  const TexelData data = texel_data(texels, internal_format);
  glTextureSubImage3D(texture, 0, 0, 0, 0, width, height, depth, GL_RGB, data.type, data.pixels);
  set_table_sampling(texture);
  return texture;
}

void check_gl(const char* when) {
  GLenum error = glGetError();
  if (error == GL_NO_ERROR) return;
  while (glGetError() != GL_NO_ERROR) {
  }
  char code[16];
  std::snprintf(code, sizeof code, "0x%04X", error);
  const char* name = error == GL_OUT_OF_MEMORY       ? " (GL_OUT_OF_MEMORY)"
                     : error == GL_INVALID_OPERATION ? " (GL_INVALID_OPERATION)"
                     : error == GL_INVALID_VALUE     ? " (GL_INVALID_VALUE)"
                     : error == GL_INVALID_ENUM      ? " (GL_INVALID_ENUM)"
                                                     : "";
  throw Error(std::string("OpenGL error ") + code + name + " " + when);
}

}  // namespace

void validate_camera(const Camera& camera) {
  if (!is_finite(camera.position))
    throw Error("invalid camera: position " + to_string(camera.position) + " is not finite");
  if (!is_finite(camera.forward) || glm::length(camera.forward) == 0.0)
    throw Error("invalid camera: forward " + to_string(camera.forward) + " is zero or not finite");
  if (!is_finite(camera.up) || glm::length(camera.up) == 0.0)
    throw Error("invalid camera: up " + to_string(camera.up) + " is zero or not finite");
  // The basis is built from cross(forward, up): it needs an angle between them.
  if (glm::length(glm::cross(glm::normalize(camera.forward), glm::normalize(camera.up))) < 1e-6)
    throw Error("invalid camera: up " + to_string(camera.up) + " is parallel to forward " +
                to_string(camera.forward));
  if (camera.width < 1 || camera.width > kMaxImageSize || camera.height < 1 || camera.height > kMaxImageSize)
    throw Error("invalid camera: image size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                " outside 1.." + std::to_string(kMaxImageSize));
  switch (camera.projection) {
    case Projection::perspective:
      if (!(camera.fov_deg > 0.0 && camera.fov_deg < 180.0))
        throw Error("invalid camera: perspective fov_deg " + to_string(camera.fov_deg) + " outside (0, 180)");
      break;
    case Projection::fisheye:
      if (!(camera.fov_deg > 0.0 && camera.fov_deg <= 360.0))
        throw Error("invalid camera: fisheye fov_deg " + to_string(camera.fov_deg) + " outside (0, 360]");
      break;
    case Projection::equirect: break;  // always the whole sphere
    default: throw Error("invalid camera: unknown projection");
  }
}

// --- GPU ------------------------------------------------------------------

namespace {

void delete_gl_objects(GLuint& program, GLuint& vertex_array, GLuint (&textures)[5], GLuint& query,
                       GLuint& framebuffer, GLuint& tile_texture, GLuint& sky_view_program,
                       GLuint& sky_view_framebuffer, GLuint (&sky_view_textures)[2], GLuint& space_program) {
  if (sky_view_program != 0) glDeleteProgram(sky_view_program);
  if (space_program != 0) glDeleteProgram(space_program);
  space_program = 0;
  if (sky_view_framebuffer != 0) glDeleteFramebuffers(1, &sky_view_framebuffer);
  glDeleteTextures(2, sky_view_textures);
  sky_view_program = sky_view_framebuffer = 0;
  for (GLuint& t : sky_view_textures) t = 0;
  if (program != 0) glDeleteProgram(program);
  if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
  glDeleteTextures(5, textures);
  if (query != 0) glDeleteQueries(1, &query);
  if (framebuffer != 0) glDeleteFramebuffers(1, &framebuffer);
  if (tile_texture != 0) glDeleteTextures(1, &tile_texture);
  program = vertex_array = query = framebuffer = tile_texture = 0;
  for (GLuint& t : textures) t = 0;
}

}  // namespace

Renderer::Renderer(GlContext& context, const Atmosphere& atmosphere, const Tables& tables,
                   TexturePrecision precision)
    : context_(context) {
  check_tables_match(atmosphere, tables);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const glm::mat3 matrix = srgb_matrix(tables);
  params_ = std::make_unique<physics::AtmosphereParams>(params);
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) radiance_to_srgb_[3 * c + r] = matrix[c][r];

  context_.make_current();
  while (glGetError() != GL_NO_ERROR) {
  }
  try {
    gpu::AssembledSource vertex;
    vertex.append("vertex shader", gpu::fullscreen_vertex_shader_source());
    program_ = link_program(vertex, gpu::render_fragment_shader_source(params, *spectral, true));
    space_program_ = link_program(vertex, gpu::render_fragment_shader_source(params, *spectral, false));
    sky_view_program_ = link_program(vertex, gpu::sky_view_fragment_shader_source(params, *spectral));
    // The sky-view table: recomputed by every render(), read with GL_LINEAR
    // + CLAMP_TO_EDGE like the precomputed tables.
    glCreateTextures(GL_TEXTURE_2D, 2, sky_view_textures_);
    glCreateFramebuffers(1, &sky_view_framebuffer_);
    for (int i = 0; i < 2; ++i) {
      glTextureStorage2D(sky_view_textures_[i], 1, GL_RGBA32F, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT);
      set_table_sampling(sky_view_textures_[i]);
      glNamedFramebufferTexture(sky_view_framebuffer_, GLenum(GL_COLOR_ATTACHMENT0 + i), sky_view_textures_[i], 0);
    }
    const GLenum attachments[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    glNamedFramebufferDrawBuffers(sky_view_framebuffer_, 2, attachments);
    check_gl("while creating the sky-view table");
    if (glCheckNamedFramebufferStatus(sky_view_framebuffer_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("the RGBA32F sky-view target is not supported by this OpenGL driver");
    // Core profile draws need a vertex array object, even an empty one.
    glCreateVertexArrays(1, &vertex_array_);
    glCreateQueries(GL_TIME_ELAPSED, 1, &timer_query_);
    const GLubyte* name = glGetString(GL_RENDERER);
    const std::string renderer_name = name != nullptr ? reinterpret_cast<const char*>(name) : "";
    for (const char* software : {"llvmpipe", "softpipe", "SwiftShader", "swrast"})
      if (renderer_name.find(software) != std::string::npos) software_rasterizer_ = true;

    const TableSizes& s = tables.sizes;
    const TableSet& t = tables.set;
    const GLenum format = precision == TexturePrecision::half ? GL_RGB16F : GL_RGB32F;
    // The optical depth of every wavelength triple, side by side (32-bit
    // whatever the precision, see TexturePrecision).
    textures_[0] = make_texture_2d(s.transmittance_mu * tables.spectral_sets(), s.transmittance_r,
                                   tables.spectral_optical_depth, GL_RGB32F);
    textures_[1] = make_texture_3d(tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                                   t.scattering, format);
    textures_[2] = make_texture_3d(tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                                   t.single_aerosol, format);
    textures_[3] = make_texture_2d(s.irradiance_mu_s, s.irradiance_r, t.indirect_irradiance, format);
    textures_[4] = make_texture_3d(tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                                   t.multiple_scattering, format);
    
    check_gl("while uploading the tables");
    // Drivers (llvmpipe's JIT in particular) compile the shader at its first
    // draw; do it now, so that render() and last_frame_ms() time frames, not
    // compilation.
    Camera warm_up;
    warm_up.position = {0.0, 0.0, atmosphere.bottom_radius_m + 1.0};
    warm_up.width = 1;
    warm_up.height = 1;
    render(warm_up, {0.0, 0.0, 1.0});
    last_frame_ms_ = last_sky_view_ms_ = 0.0;
  } catch (...) {
    delete_gl_objects(program_, vertex_array_, textures_, timer_query_, framebuffer_, tile_texture_,
                      sky_view_program_, sky_view_framebuffer_, sky_view_textures_, space_program_);
    throw;
  }
}

Renderer::~Renderer() {
  try {
    context_.make_current();
  } catch (const Error&) {
    return;  // the context is current elsewhere: its objects die with it
  }
  delete_gl_objects(program_, vertex_array_, textures_, timer_query_, framebuffer_, tile_texture_,
                      sky_view_program_, sky_view_framebuffer_, sky_view_textures_, space_program_);
}

Image Renderer::render(const Camera& camera, const glm::dvec3& sun_direction) {
  const CameraFrame frame = camera_frame(camera);
  const glm::vec3 sun = sun_vector(sun_direction);
  context_.make_current();
  while (glGetError() != GL_NO_ERROR) {
  }

  const int width = camera.width;
  const int height = camera.height;
  const int tile_width = std::min(width, kTileSize);
  const int tile_height = std::min(height, kTileSize);
  if (tile_width > tile_width_ || tile_height > tile_height_) {
    const int w = std::max(tile_width, tile_width_);
    const int h = std::max(tile_height, tile_height_);
    if (framebuffer_ != 0) glDeleteFramebuffers(1, &framebuffer_);
    if (tile_texture_ != 0) glDeleteTextures(1, &tile_texture_);
    framebuffer_ = tile_texture_ = 0;
    tile_width_ = tile_height_ = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &tile_texture_);
    glTextureStorage2D(tile_texture_, 1, GL_RGBA32F, w, h);
    glCreateFramebuffers(1, &framebuffer_);
    glNamedFramebufferTexture(framebuffer_, GL_COLOR_ATTACHMENT0, tile_texture_, 0);
    glNamedFramebufferDrawBuffer(framebuffer_, GL_COLOR_ATTACHMENT0);
    glNamedFramebufferReadBuffer(framebuffer_, GL_COLOR_ATTACHMENT0);
    check_gl("while creating the render target");
    if (glCheckNamedFramebufferStatus(framebuffer_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("the RGBA32F render target of " + std::to_string(w) + "x" + std::to_string(h) +
                  " pixels is not supported by this OpenGL driver");
    tile_width_ = w;
    tile_height_ = h;
  }

  glBindVertexArray(vertex_array_);
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_DITHER);
  glDisable(GL_FRAMEBUFFER_SRGB);

  // Pass 1: this frame's sky-view table, for cameras in the atmosphere (see
  // sky_radiance); the test is the shared function's, on the same floats.
  double gpu_ms = 0.0;
  const bool sky_view_camera = physics::camera_uses_sky_view(*params_, frame.position);
  if (sky_view_camera) {
    glUseProgram(sky_view_program_);
    glProgramUniform3f(sky_view_program_, 0, frame.position.x, frame.position.y, frame.position.z);
    glProgramUniform3f(sky_view_program_, 7, sun.x, sun.y, sun.z);
    for (GLuint unit = 0; unit < 5; ++unit) glBindTextureUnit(unit, textures_[unit]);
    glBindFramebuffer(GL_FRAMEBUFFER, sky_view_framebuffer_);
    glViewport(0, 0, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT);
    const auto start = std::chrono::steady_clock::now();
    if (!software_rasterizer_) glBeginQuery(GL_TIME_ELAPSED, timer_query_);
    glDrawArrays(GL_TRIANGLES, 0, 3);
    if (!software_rasterizer_) {
      glEndQuery(GL_TIME_ELAPSED);
      GLuint64 nanoseconds = 0;
      glGetQueryObjectui64v(timer_query_, GL_QUERY_RESULT, &nanoseconds);
      gpu_ms += double(nanoseconds) * 1e-6;
    } else {
      glFinish();
      gpu_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    }
  }
  last_sky_view_ms_ = gpu_ms;

  // Pass 2: the image, in tiles.
  const GLuint program = sky_view_camera ? program_ : space_program_;
  glUseProgram(program);
  glProgramUniform3f(program, 0, frame.position.x, frame.position.y, frame.position.z);
  glProgramUniform3f(program, 1, frame.right.x, frame.right.y, frame.right.z);
  glProgramUniform3f(program, 2, frame.up.x, frame.up.y, frame.up.z);
  glProgramUniform3f(program, 3, frame.forward.x, frame.forward.y, frame.forward.z);
  glProgramUniform1f(program, 4, frame.fov_deg);
  glProgramUniform1i(program, 5, frame.projection);
  glProgramUniform2f(program, 6, frame.image_size.x, frame.image_size.y);
  glProgramUniform3f(program, 7, sun.x, sun.y, sun.z);
  glProgramUniformMatrix3fv(program, 9, 1, GL_FALSE, radiance_to_srgb_);
  for (GLuint unit = 0; unit < 5; ++unit) glBindTextureUnit(unit, textures_[unit]);
  glBindTextureUnit(5, sky_view_textures_[0]);
  glBindTextureUnit(6, sky_view_textures_[1]);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer_);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glPixelStorei(GL_PACK_ROW_LENGTH, 0);
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);

  Image image;
  image.width = width;
  image.height = height;
  image.rgb.resize(size_t(width) * size_t(height) * 3);
  std::vector<float> tile(size_t(tile_width) * size_t(tile_height) * 4);
  for (int y0 = 0; y0 < height; y0 += kTileSize) {
    for (int x0 = 0; x0 < width; x0 += kTileSize) {
      const int w = std::min(kTileSize, width - x0);
      const int h = std::min(kTileSize, height - y0);
      glViewport(0, 0, w, h);
      glProgramUniform2f(program, 8, float(x0), float(y0 + h));
      if (software_rasterizer_) {
        const auto start = std::chrono::steady_clock::now();
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glFinish();
        gpu_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      } else {
        glBeginQuery(GL_TIME_ELAPSED, timer_query_);
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glEndQuery(GL_TIME_ELAPSED);
      }
      glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, tile.data());
      if (!software_rasterizer_) {
        // Available: glReadPixels waited for the draw.
        GLuint64 nanoseconds = 0;
        glGetQueryObjectui64v(timer_query_, GL_QUERY_RESULT, &nanoseconds);
        gpu_ms += double(nanoseconds) * 1e-6;
      }
      // GL rows go up from the bottom of the tile, image rows down from the top.
      for (int row = 0; row < h; ++row) {
        const float* src = &tile[size_t(row) * size_t(w) * 4];
        float* dst = &image.rgb[(size_t(y0 + h - 1 - row) * size_t(width) + size_t(x0)) * 3];
        for (int x = 0; x < w; ++x) {
          dst[3 * x + 0] = src[4 * x + 0];
          dst[3 * x + 1] = src[4 * x + 1];
          dst[3 * x + 2] = src[4 * x + 2];
        }
      }
    }
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  check_gl("while rendering");
  last_frame_ms_ = gpu_ms;
  return image;
}

// --- CPU ------------------------------------------------------------------

Image render_cpu(const Atmosphere& atmosphere, const Tables& tables, const Camera& camera,
                 const glm::dvec3& sun_direction) {
  check_tables_match(atmosphere, tables);
  const CameraFrame frame = camera_frame(camera);
  const glm::vec3 sun = sun_vector(sun_direction);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const precompute::TableSamplers samplers = precompute::make_samplers(tables);
  const glm::mat3 matrix = srgb_matrix(tables);

  // The sky-view table, texel by texel as the sky-view pass computes it.
  std::vector<glm::vec3> sky_view_rayleigh(size_t(SKY_VIEW_WIDTH) * SKY_VIEW_HEIGHT);
  std::vector<glm::vec3> sky_view_aerosol(sky_view_rayleigh.size());
  const bool sky_view_camera = physics::camera_uses_sky_view(params, frame.position);
  if (sky_view_camera) {
    tbb::parallel_for(0, SKY_VIEW_HEIGHT, [&](int y) {
      for (int x = 0; x < SKY_VIEW_WIDTH; ++x) {
        const glm::vec2 uv((float(x) + 0.5f) / float(SKY_VIEW_WIDTH), (float(y) + 0.5f) / float(SKY_VIEW_HEIGHT));
        const size_t i = size_t(y) * SKY_VIEW_WIDTH + size_t(x);
        physics::compute_sky_view_texel(params, *spectral, samplers.spectral_optical_depth, samplers.scattering,
                                        samplers.single_aerosol,
                                        samplers.multiple_scattering, frame.position, sun, uv, sky_view_rayleigh[i],
                                        sky_view_aerosol[i]);
      }
    });
  }
  const physics::sampler2D sky_view_rayleigh_sampler{SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT, sky_view_rayleigh.data()};
  const physics::sampler2D sky_view_aerosol_sampler{SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT, sky_view_aerosol.data()};

  Image image;
  image.width = camera.width;
  image.height = camera.height;
  image.rgb.resize(size_t(camera.width) * size_t(camera.height) * 3);
  tbb::parallel_for(tbb::blocked_range<int>(0, camera.height), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      float* dst = &image.rgb[size_t(y) * size_t(camera.width) * 3];
      for (int x = 0; x < camera.width; ++x) {
        // The pixel centre, as gl_FragCoord gives it to the shader.
        const glm::vec2 pixel(float(x) + 0.5f, float(y) + 0.5f);
        bool valid = true;
        const glm::vec3 view_ray = physics::camera_view_ray(pixel, frame.image_size, frame.right, frame.up,
                                                            frame.forward, frame.fov_deg, frame.projection, valid);
        glm::vec3 rgb(0.0f);
        if (valid) {
          const glm::vec3 radiance = physics::radiance_along_view_ray(
              params, *spectral, samplers.spectral_optical_depth, samplers.scattering, samplers.single_aerosol,
              samplers.multiple_scattering, samplers.indirect_irradiance, sky_view_rayleigh_sampler,
              sky_view_aerosol_sampler, sky_view_camera, frame.position, view_ray, sun, true);
          rgb = matrix * radiance;
        }
        dst[3 * x + 0] = rgb.x;
        dst[3 * x + 1] = rgb.y;
        dst[3 * x + 2] = rgb.z;
      }
    }
  });
  return image;
}

}  // namespace atmos
