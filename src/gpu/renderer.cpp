// The OpenGL renderer and its CPU twin.
//
// Both evaluate radiance_along_view_ray (physics/functions.glsl) for the rays
// of camera_view_ray (gpu/camera.glsl) with the same parameters, the same
// tables and the same float inputs (camera frame, pixel centres, sun
// direction, colour matrix), which this file computes once for both.
#include <epoxy/gl.h>

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
#include "gpu/atmosphere_pass.hpp"
#include "gpu/camera_cpp.hpp"
#include "gpu/gl_util.hpp"
#include "gpu/shader_source.hpp"
#include "gpu/star_catalogue_bins.hpp"
#include "physics/checks.hpp"
#include "physics/moons.hpp"
#include "physics/parameters.hpp"
#include "physics/radiance_to_camera_cpp.hpp"
#include "runtime/table_samplers.hpp"

namespace atmos {

namespace {

// The GPU draws the image in tiles of at most this size: the read-back buffer
// stays small (64 MiB) for any image size, and no single draw runs long
// enough to trip a desktop driver's watchdog.
constexpr int kTileSize = 2048;
// render.frag.glsl: `moons_eclipse`, after the moons (gpu::kMoonsLocation, 45..49).
constexpr GLint kMoonsEclipseLocation = 50;

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

std::string to_string(const glm::dvec2& v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "(%g, %g)", v.x, v.y);
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
  glm::vec2 lens_shift;
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
  frame.lens_shift = glm::vec2(camera.lens_shift);
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
  if (camera.width < 1 || camera.width > gpu::kMaxImageSize || camera.height < 1 || camera.height > gpu::kMaxImageSize)
    throw Error("invalid camera: image size " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                " outside 1.." + std::to_string(gpu::kMaxImageSize));
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
  if (!(std::abs(camera.lens_shift.x) <= 100.0 && std::abs(camera.lens_shift.y) <= 100.0))
    throw Error("invalid camera: lens_shift " + to_string(camera.lens_shift) + " is not finite or beyond 100");
  if (camera.projection != Projection::perspective && camera.lens_shift != glm::dvec2(0.0))
    throw Error("invalid camera: lens_shift " + to_string(camera.lens_shift) + " needs the perspective projection");
}

// --- GPU ------------------------------------------------------------------

struct Renderer::Impl {
  std::unique_ptr<gpu::GpuTables> tables;  // the tables and the sky-view table
  std::unique_ptr<gpu::GpuTimer> timer;
  // The render pass's programs: index 1 for a camera in the atmosphere
  // (reads the sky-view table), 0 above it; + 2 with moons (compiled on
  // first use).
  std::uint32_t programs[4] = {0, 0, 0, 0};
  std::uint32_t vertex_array = 0;
  std::uint32_t framebuffer = 0;  // one RGBA32F tile, reused while large enough
  std::uint32_t tile_texture = 0;
  int tile_width = 0;
  int tile_height = 0;
  double last_frame_ms = 0.0;
  double last_sky_view_ms = 0.0;
  bool stars = false;
  std::vector<Moon> moons;
  // The catalogue's stars (none: the procedural field) and its rotation.
  std::vector<double> wavelengths_nm;
  gpu::StarCatalogueBuffers star_catalogue;
  glm::dmat3 world_from_catalogue{1.0};

  std::uint32_t program(bool sky_view_camera, bool eclipse) {
    std::uint32_t& p = programs[(sky_view_camera ? 1 : 0) + (eclipse ? 2 : 0)];
    if (p == 0) {
      gpu::AssembledSource vertex;
      vertex.append("vertex shader", gpu::fullscreen_vertex_shader_source());
      p = gpu::shared_program(vertex, gpu::render_fragment_shader_source(tables->params(), tables->spectral(),
                                                                          sky_view_camera, eclipse));
    }
    return p;
  }

  void release() {
    for (std::uint32_t& p : programs) gpu::release_program(p);
    if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
    if (framebuffer != 0) glDeleteFramebuffers(1, &framebuffer);
    if (tile_texture != 0) glDeleteTextures(1, &tile_texture);
    vertex_array = framebuffer = tile_texture = 0;
    star_catalogue.release();
    timer.reset();
    tables.reset();
  }

  // The tile render target, grown to at least w x h pixels.
  void reserve_tile(int width, int height) {
    if (width <= tile_width && height <= tile_height) return;
    const int w = std::max(width, tile_width);
    const int h = std::max(height, tile_height);
    if (framebuffer != 0) glDeleteFramebuffers(1, &framebuffer);
    if (tile_texture != 0) glDeleteTextures(1, &tile_texture);
    framebuffer = tile_texture = 0;
    tile_width = tile_height = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &tile_texture);
    glTextureStorage2D(tile_texture, 1, GL_RGBA32F, w, h);
    glCreateFramebuffers(1, &framebuffer);
    glNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, tile_texture, 0);
    glNamedFramebufferDrawBuffer(framebuffer, GL_COLOR_ATTACHMENT0);
    glNamedFramebufferReadBuffer(framebuffer, GL_COLOR_ATTACHMENT0);
    gpu::check_gl("while creating the render target");
    if (glCheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw Error("the RGBA32F render target of " + std::to_string(w) + "x" + std::to_string(h) +
                  " pixels is not supported by this OpenGL driver");
    tile_width = w;
    tile_height = h;
  }
};

Renderer::Renderer(const Atmosphere& atmosphere, const Tables& tables, TexturePrecision precision)
    : impl_(std::make_unique<Impl>()) {
  gpu::require_gl_context("atmos::Renderer");
  check_tables_match(atmosphere, tables);
  gpu::clear_gl_errors();
  Impl& p = *impl_;
  try {
    p.wavelengths_nm = tables.wavelengths_nm;
    p.tables = std::make_unique<gpu::GpuTables>(atmosphere, tables, precision);
    p.timer = std::make_unique<gpu::GpuTimer>();
    p.program(true, false);
    p.program(false, false);
    // Core profile draws need a vertex array object, even an empty one.
    glCreateVertexArrays(1, &p.vertex_array);
    gpu::check_gl("while creating the renderer");
    // Drivers (llvmpipe's JIT in particular) compile the shader at its first
    // draw; do it now, so that render() and last_frame_ms() time frames, not
    // compilation.
    Camera warm_up;
    warm_up.position = {0.0, 0.0, atmosphere.bottom_radius_m + 1.0};
    warm_up.width = 1;
    warm_up.height = 1;
    render(warm_up, {0.0, 0.0, 1.0});
    p.last_frame_ms = p.last_sky_view_ms = 0.0;
  } catch (...) {
    p.release();
    throw;
  }
}

Renderer::~Renderer() {
  // Without a current context the objects die with their context.
  if (impl_ && gpu::gl_context_is_current()) impl_->release();
}

void Renderer::set_stars(bool enabled) { impl_->stars = enabled; }
bool Renderer::stars() const { return impl_->stars; }
void Renderer::set_star_catalogue(const std::vector<Star>& stars) {
  impl_->star_catalogue.set(stars, impl_->wavelengths_nm);
}
const std::vector<Star>& Renderer::star_catalogue() const { return impl_->star_catalogue.stars(); }
void Renderer::set_star_orientation(const glm::dmat3& world_from_catalogue) {
  gpu::validate_star_orientation(world_from_catalogue, "Renderer::set_star_orientation");
  impl_->world_from_catalogue = world_from_catalogue;
}
const std::vector<Moon>& Renderer::moons() const { return impl_->moons; }
double Renderer::last_frame_ms() const { return impl_->last_frame_ms; }
double Renderer::last_sky_view_ms() const { return impl_->last_sky_view_ms; }

void Renderer::set_moons(const std::vector<Moon>& moons) {
  validate_moons(moons, double(impl_->tables->params().top_radius));
  impl_->moons = moons;
}

Image Renderer::render(const Camera& camera, const glm::dvec3& sun_direction) {
  const CameraFrame frame = camera_frame(camera);
  const glm::vec3 sun = sun_vector(sun_direction);
  Impl& p = *impl_;
  gpu::require_gl_context("atmos::Renderer::render");
  gpu::clear_gl_errors();

  const int width = camera.width;
  const int height = camera.height;
  const int tile_width = std::min(width, kTileSize);
  const int tile_height = std::min(height, kTileSize);
  p.reserve_tile(tile_width, tile_height);

  gpu::set_full_screen_state();
  glDisable(GL_DITHER);

  // Pass 1: this frame's sky-view table, for cameras in the atmosphere (see
  // sky_radiance); the test is the shared function's, on the same floats.
  double gpu_ms = 0.0;
  const gpu::GpuTables& tables = *p.tables;
  const bool sky_view_camera = physics::camera_uses_sky_view(tables.params(), frame.position);
  // The moons, all drawn; those that may hide the sun also eclipse.
  const physics::Moons moons = physics::make_moons(tables.params(), p.moons);
  const physics::Moons eclipsing =
      physics::moons_may_eclipse(tables.params(), moons, sun) ? moons : physics::no_moons();
  physics::SkyViewFrame sky_view = tables.sky_view_frame(frame.position, sun);
  sky_view.full_azimuth = eclipsing.count > 0;
  if (sky_view_camera) gpu_ms += p.tables->update_sky_view(frame.position, sun, sky_view, p.timer.get(), eclipsing);
  p.last_sky_view_ms = gpu_ms;

  // Pass 2: the image, in tiles.
  const GLuint program = p.program(sky_view_camera, moons.count > 0);
  const glm::mat3& matrix = tables.radiance_to_srgb();
  glUseProgram(program);
  glBindVertexArray(p.vertex_array);
  glProgramUniform3f(program, 0, frame.position.x, frame.position.y, frame.position.z);
  glProgramUniform3f(program, 1, frame.right.x, frame.right.y, frame.right.z);
  glProgramUniform3f(program, 2, frame.up.x, frame.up.y, frame.up.z);
  glProgramUniform3f(program, 3, frame.forward.x, frame.forward.y, frame.forward.z);
  glProgramUniform1f(program, 4, frame.fov_deg);
  glProgramUniform2f(program, 14, frame.lens_shift.x, frame.lens_shift.y);
  glProgramUniform1i(program, 5, frame.projection);
  glProgramUniform2f(program, 6, frame.image_size.x, frame.image_size.y);
  glProgramUniform3f(program, 7, sun.x, sun.y, sun.z);
  glProgramUniformMatrix3fv(program, 9, 1, GL_FALSE, &matrix[0][0]);
  gpu::set_sky_view_frame_uniforms(program, sky_view);
  glProgramUniform1i(program, 12, p.stars ? 1 : 0);
  glProgramUniform1f(program, 13, float(star_image_sigma(camera)));
  const bool catalogue = p.stars && !p.star_catalogue.empty();
  gpu::set_star_catalogue_uniforms(program, catalogue, p.world_from_catalogue);
  if (catalogue) p.star_catalogue.bind(double(float(star_image_sigma(camera))));
  gpu::set_moons_uniforms(program, moons);
  glProgramUniform1i(program, kMoonsEclipseLocation, eclipsing.count > 0 ? 1 : 0);
  tables.bind();
  glBindFramebuffer(GL_FRAMEBUFFER, p.framebuffer);
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
      p.timer->begin();
      glDrawArrays(GL_TRIANGLES, 0, 3);
      gpu_ms += p.timer->end_ms();
      glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, tile.data());
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
  if (catalogue) gpu::StarCatalogueBuffers::unbind();
  gpu::check_gl("while rendering");
  p.last_frame_ms = gpu_ms;
  return image;
}

// --- CPU ------------------------------------------------------------------

double star_image_sigma(const Camera& camera) {
  validate_camera(camera);
  const double pixels = double(std::min(camera.width, camera.height));
  double pixel_angle;
  switch (camera.projection) {
    case Projection::perspective:
      pixel_angle = 2.0 * std::tan(0.5 * camera.fov_deg * M_PI / 180.0) / double(camera.height);
      break;
    case Projection::fisheye:
      pixel_angle = camera.fov_deg * M_PI / 180.0 / pixels;
      break;
    default:  // equirect: 2 pi over the width
      pixel_angle = 2.0 * M_PI / double(camera.width);
  }
  return 0.6 * pixel_angle;
}

Image render_cpu(const Atmosphere& atmosphere, const Tables& tables, const Camera& camera,
                 const glm::dvec3& sun_direction, bool stars, const std::vector<Moon>& moon_list,
                 const std::vector<Star>& star_catalogue, const glm::dmat3& world_from_catalogue) {
  check_tables_match(atmosphere, tables);
  validate_stars(star_catalogue);
  gpu::validate_star_orientation(world_from_catalogue, "render_cpu");
  const CameraFrame frame = camera_frame(camera);
  const glm::vec3 sun = sun_vector(sun_direction);
  const physics::AtmosphereParams params = physics::make_render_params(atmosphere, tables.sizes);
  const std::unique_ptr<physics::SpectralSets> spectral = physics::make_spectral_sets(atmosphere, tables.sizes);
  const runtime::TableSamplers samplers = runtime::make_samplers(tables);
  const glm::mat3 matrix = srgb_matrix(tables);

  // The sky-view table, texel by texel as the sky-view pass computes it.
  const physics::Moons moons = physics::make_moons(params, moon_list);
  const physics::Moons eclipsing = physics::moons_may_eclipse(params, moons, sun) ? moons : physics::no_moons();
  const bool sky_view_camera = physics::camera_uses_sky_view(params, frame.position);
  physics::SkyViewFrame sky_view_frame =
      physics::sky_view_frame(params, physics::camera_above_ground(params, frame.position), sun);
  sky_view_frame.full_azimuth = eclipsing.count > 0;
  gpu::CpuSkyView sky_view;
  if (sky_view_camera)
    sky_view = gpu::compute_sky_view_cpu(params, *spectral, samplers, frame.position, sun, eclipsing);
  physics::StarField star_field{stars, float(star_image_sigma(camera))};
  // The catalogue's stars, binned as Renderer::render bins them.
  gpu::StarBins star_bins;
  if (stars && !star_catalogue.empty()) {
    std::vector<glm::vec3> directions, irradiances;
    for (const Star& star : star_catalogue) {
      directions.push_back(glm::vec3(glm::normalize(star.direction)));
      irradiances.push_back(gpu::star_channel_irradiance(star, tables.wavelengths_nm));
    }
    star_bins = gpu::bin_stars(directions, irradiances, gpu::star_bin_radius(double(star_field.sigma)));
    star_field.catalogue = star_bins.view(world_from_catalogue);
  }

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
                                                            frame.forward, frame.fov_deg, frame.lens_shift,
                                                            frame.projection, valid);
        glm::vec3 rgb(0.0f);
        if (valid) {
          const glm::vec3 radiance = physics::radiance_along_view_ray(
              params, *spectral, samplers.spectral_optical_depth, samplers.scattering, samplers.single_aerosol,
              samplers.multiple_scattering, samplers.indirect_irradiance, sky_view.sampler(0),
              sky_view.sampler(1), sky_view.sampler(2), sky_view_camera, sky_view_frame, frame.position, view_ray,
              sun, true, star_field, moons, eclipsing.count > 0);
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
