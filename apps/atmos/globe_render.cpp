#include "globe_render.hpp"

#include <epoxy/gl.h>
#include <glm/geometric.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "atmos/globe.hpp"
#include "atmos/plugin.hpp"
#include "atmos/stereo.hpp"

namespace atmos_cli {

namespace {

// The engine's world is planet-centred metres (PlanetFrame's defaults), and
// its colour is radiance in cd/m² divided by this.
constexpr double kNitsPerUnit = 1000.0;
// Near plane of the reversed-Z projection, m: the camera may stand at 0 m
// above the terrain; reversed-Z float depth keeps the far field exact.
constexpr double kNearM = 0.01;

// A pinhole view: the camera basis (right, up, forward: orthonormal, the
// frame of atmos::Camera after Renderer's orthonormalisation) and the
// vertical field of view.
struct PinholeView {
  glm::dvec3 position{0.0};
  glm::dvec3 right{1, 0, 0}, up{0, 0, 1}, forward{0, 1, 0};
  double fov_y_rad = 1.0;
  glm::dvec2 lens_shift{0.0};  // atmos::Camera::lens_shift: an off-axis frustum
  int width = 1, height = 1;
};

// atmos::Camera's basis: right = forward x up, up re-orthogonalised
// (glm::lookAt's convention, as the renderer's camera model).
void camera_basis(const atmos::Camera& camera, glm::dvec3& right, glm::dvec3& up, glm::dvec3& forward) {
  forward = glm::normalize(camera.forward);
  right = glm::normalize(glm::cross(forward, camera.up));
  up = glm::cross(right, forward);
}

// The unit view ray through the pixel centre (px, py) (x to the right, y
// down from the top-left corner) of a fisheye or equirect camera, in its
// basis; false for fisheye pixels outside the image circle. The mappings
// are those atmos::Projection documents:
//  - fisheye: the equidistant projection r = f θ (Kannala & Brandt 2006,
//    eq. 3): the angle θ from the axis grows linearly with the distance r
//    from the image centre and reaches fov/2 on the largest centred circle;
//  - equirect: the plate carrée, azimuth -180..180° across (0 = forward,
//    +90° = right), elevation +90° (top edge) .. -90° (bottom edge).
bool pixel_ray(const atmos::Camera& camera, double px, double py, const glm::dvec3& right, const glm::dvec3& up,
               const glm::dvec3& forward, glm::dvec3& ray) {
  const double w = camera.width, h = camera.height;
  if (camera.projection == atmos::Projection::equirect) {
    const double azimuth = (px / w - 0.5) * 2.0 * M_PI;
    const double elevation = (0.5 - py / h) * M_PI;
    ray = forward * (std::cos(elevation) * std::cos(azimuth)) + right * (std::cos(elevation) * std::sin(azimuth)) +
          up * std::sin(elevation);
    return true;
  }
  const double x = px - 0.5 * w, y = 0.5 * h - py;
  const double radius = 0.5 * std::min(w, h), rho = std::hypot(x, y);
  if (rho > radius) return false;
  const double theta = rho / radius * 0.5 * camera.fov_deg * M_PI / 180.0;
  const double s = rho > 0.0 ? std::sin(theta) / rho : 0.0;
  ray = glm::normalize(forward * std::cos(theta) + right * (x * s) + up * (y * s));
  return true;
}

// The angle of one pixel of a fisheye (at its centre) or equirect camera.
double pixel_angle_rad(const atmos::Camera& camera) {
  if (camera.projection == atmos::Projection::equirect)
    return std::min(2.0 * M_PI / camera.width, M_PI / camera.height);
  return camera.fov_deg * M_PI / 180.0 / std::min(camera.width, camera.height);
}

// The engine's render targets of one size: the globe's colour and depth,
// and the pass's output.
struct Targets {
  GLuint colour = 0, depth = 0, output = 0;
  GLuint framebuffer = 0;

  Targets(int width, int height) {
    glCreateTextures(GL_TEXTURE_2D, 1, &colour);
    glTextureStorage2D(colour, 1, GL_RGBA32F, width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &depth);
    glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT32F, width, height);
    glCreateTextures(GL_TEXTURE_2D, 1, &output);
    glTextureStorage2D(output, 1, GL_RGBA32F, width, height);
    glCreateFramebuffers(1, &framebuffer);
    glNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, colour, 0);
    glNamedFramebufferTexture(framebuffer, GL_DEPTH_ATTACHMENT, depth, 0);
  }
  ~Targets() {
    glDeleteFramebuffers(1, &framebuffer);
    const GLuint textures[] = {colour, depth, output};
    glDeleteTextures(3, textures);
  }
  Targets(const Targets&) = delete;
  Targets& operator=(const Targets&) = delete;
};

}  // namespace

struct GlobeRenderer::Impl {
  atmos::Atmosphere air;  // the pass's: the planet's continued below the datum
  atmos::AtmospherePass pass;
  atmos::Globe globe;
  bool regional_albedo = false;  // tables with a ground response: the air over the globe's regional albedo
  std::map<std::pair<int, int>, std::unique_ptr<Targets>> targets;

  static atmos::GlobeSettings settings() {
    atmos::GlobeSettings s;
    s.complete_every_frame = true;
    return s;
  }

  Impl(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables, const atmos::PlanetSurface& surface)
      : air(atmos::extend_below_datum(atmosphere, surface)),
        // Each of `atmos render`'s images compiles the programs it draws
        // with at its first use: no warm-up of others.
        pass(air, tables, atmos::PlanetFrame{}, atmos::PassPrograms::none),
        globe(atmosphere, surface, pass, settings()),
        regional_albedo(!tables.ground_response.empty()) {}

  ~Impl() { targets.clear(); }

  Targets& targets_of(int width, int height) {
    auto& t = targets[{width, height}];
    if (!t) t = std::make_unique<Targets>(width, height);
    return *t;
  }

  // One pinhole view: the globe (its ground eclipsed by the moons) and the
  // pass; the composited image read back in cd/m², rows top-down.
  atmos::Image draw(const PinholeView& v, const glm::dvec3& sun, bool stars, const std::vector<atmos::Moon>& moons) {
    Targets& t = targets_of(v.width, v.height);
    atmos::GlobeView view;
    view.view = glm::lookAt(v.position, v.position + v.forward, v.up);
    // The frustum's four sides (atmos/stereo.hpp), off-axis by the lens shift.
    const double half = std::tan(0.5 * v.fov_y_rad), aspect = double(v.width) / double(v.height);
    const atmos::FieldOfView fov{std::atan(-aspect * half + v.lens_shift.x),
                                 std::atan(aspect * half + v.lens_shift.x), std::atan(half + v.lens_shift.y),
                                 std::atan(-half + v.lens_shift.y)};
    view.projection = atmos::reversed_z_projection(fov, kNearM);
    view.width = v.width;
    view.height = v.height;
    view.sun_direction = sun;
    view.nits_per_unit = kNitsPerUnit;
    view.moons = moons;

    const float clear_colour[4] = {0, 0, 0, 0};
    const float clear_depth = 0.0f;
    glClearNamedFramebufferfv(t.framebuffer, GL_COLOR, 0, clear_colour);
    glClearNamedFramebufferfv(t.framebuffer, GL_DEPTH, 0, &clear_depth);
    glBindFramebuffer(GL_FRAMEBUFFER, t.framebuffer);
    // The air lit by the ground around the camera (before the globe's draw,
    // which lights its ground with the pass's sky light).
    if (regional_albedo) pass.set_ground_albedo(globe.regional_albedo(v.position));
    globe.draw(view);

    atmos::FrameInput input;
    input.colour = t.colour;
    input.depth = t.depth;
    input.width = v.width;
    input.height = v.height;
    input.depth_encoding = atmos::DepthEncoding::reversed_z;
    input.view = view.view;
    input.projection = view.projection;
    input.sun_direction = sun;
    input.nits_per_unit = kNitsPerUnit;
    input.stars = stars;
    input.moons = moons;
    input.output = t.output;
    pass.render(input);

    std::vector<float> rgba(size_t(v.width) * size_t(v.height) * 4);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    glGetTextureImage(t.output, 0, GL_RGBA, GL_FLOAT, GLsizei(rgba.size() * sizeof(float)), rgba.data());
    atmos::Image image;
    image.width = v.width;
    image.height = v.height;
    image.rgb.resize(size_t(v.width) * size_t(v.height) * 3);
    for (size_t y = 0; y < size_t(v.height); ++y)
      for (size_t x = 0; x < size_t(v.width); ++x)
        for (size_t c = 0; c < 3; ++c)
          image.rgb[(y * size_t(v.width) + x) * 3 + c] =
              float(double(rgba[((size_t(v.height) - 1 - y) * size_t(v.width) + x) * 4 + c]) * kNitsPerUnit);
    return image;
  }

  // A fisheye or equirect camera through a cube map around it: six (or as
  // many as its pixels look into) 90° pinhole views along ± the camera's
  // axes, each drawn and composited as a perspective camera is, then
  // resampled bilinearly at the camera's own rays. Each face has N x N
  // pixels over its 90° plus one guard pixel on every side, so that the
  // bilinear footprint of every ray stays inside the face its direction
  // falls on; N makes a face pixel (2/N rad at the face's centre, less
  // towards its edges) no wider than the camera's pixel.
  atmos::Image cube(const atmos::Camera& camera, const glm::dvec3& sun, bool stars,
                    const std::vector<atmos::Moon>& moons) {
    glm::dvec3 right, up, forward;
    camera_basis(camera, right, up, forward);
    // Face f looks along axis[f] with up[f]; its right is axis x up.
    const std::array<glm::dvec3, 6> axis = {forward, -forward, right, -right, up, -up};
    const std::array<glm::dvec3, 6> face_up = {up, up, up, up, -forward, forward};
    const int n = std::clamp(int(std::ceil(2.0 / pixel_angle_rad(camera))), 16, 4096);
    const int m = n + 2;
    const double half_extent = double(m) / double(n);  // tan of the half field, guard pixels included

    struct Sample {
      int face = -1;  // -1: outside the fisheye circle (black)
      double x = 0.0, y = 0.0;  // face pixel coordinates, x right, y down from the top-left corner
    };
    std::vector<Sample> samples(size_t(camera.width) * size_t(camera.height));
    std::array<bool, 6> used{};
    for (int py = 0; py < camera.height; ++py)
      for (int px = 0; px < camera.width; ++px) {
        glm::dvec3 ray;
        if (!pixel_ray(camera, px + 0.5, py + 0.5, right, up, forward, ray)) continue;
        int face = 0;
        double largest = -1.0;
        for (int f = 0; f < 6; ++f) {
          const double d = glm::dot(ray, axis[size_t(f)]);
          if (d > largest) {
            largest = d;
            face = f;
          }
        }
        const glm::dvec3 face_right = glm::cross(axis[size_t(face)], face_up[size_t(face)]);
        const double u = glm::dot(ray, face_right) / largest, v = glm::dot(ray, face_up[size_t(face)]) / largest;
        Sample& s = samples[size_t(py) * size_t(camera.width) + size_t(px)];
        s.face = face;
        s.x = 0.5 * m + 0.5 * n * u;
        s.y = 0.5 * m - 0.5 * n * v;
        used[size_t(face)] = true;
      }

    std::array<atmos::Image, 6> faces;
    for (int f = 0; f < 6; ++f) {
      if (!used[size_t(f)]) continue;
      PinholeView v;
      v.position = camera.position;
      v.forward = axis[size_t(f)];
      v.up = face_up[size_t(f)];
      v.right = glm::cross(v.forward, v.up);
      v.fov_y_rad = 2.0 * std::atan(half_extent);
      v.width = v.height = m;
      faces[size_t(f)] = draw(v, sun, stars, moons);
    }

    atmos::Image image;
    image.width = camera.width;
    image.height = camera.height;
    image.rgb.assign(size_t(camera.width) * size_t(camera.height) * 3, 0.0f);
    for (size_t i = 0; i < samples.size(); ++i) {
      const Sample& s = samples[i];
      if (s.face < 0) continue;
      const atmos::Image& face = faces[size_t(s.face)];
      // Bilinear between the four pixel centres around (x, y); the guard
      // band keeps them inside the face.
      const double fx = s.x - 0.5, fy = s.y - 0.5;
      const int x0 = std::clamp(int(std::floor(fx)), 0, m - 2), y0 = std::clamp(int(std::floor(fy)), 0, m - 2);
      const double wx = std::clamp(fx - x0, 0.0, 1.0), wy = std::clamp(fy - y0, 0.0, 1.0);
      for (size_t c = 0; c < 3; ++c) {
        auto at = [&](int x, int y) { return double(face.rgb[(size_t(y) * size_t(m) + size_t(x)) * 3 + c]); };
        const double top = at(x0, y0) * (1.0 - wx) + at(x0 + 1, y0) * wx;
        const double bottom = at(x0, y0 + 1) * (1.0 - wx) + at(x0 + 1, y0 + 1) * wx;
        image.rgb[i * 3 + c] = float(top * (1.0 - wy) + bottom * wy);
      }
    }
    return image;
  }
};

GlobeRenderer::GlobeRenderer(const atmos::Atmosphere& atmosphere, const atmos::Tables& tables,
                             const atmos::PlanetSurface& surface)
    : impl_(std::make_unique<Impl>(atmosphere, tables, surface)) {}

GlobeRenderer::~GlobeRenderer() = default;

glm::dvec3 GlobeRenderer::above_terrain(const glm::dvec3& position) const {
  return position + glm::normalize(position) * impl_->globe.height_m(position);
}

atmos::Image GlobeRenderer::render(const atmos::Camera& camera, const glm::dvec3& sun_direction, bool stars,
                                   const std::vector<atmos::Moon>& moons) {
  atmos::validate_camera(camera);
  if (camera.projection != atmos::Projection::perspective) return impl_->cube(camera, sun_direction, stars, moons);
  PinholeView v;
  v.position = camera.position;
  camera_basis(camera, v.right, v.up, v.forward);
  v.fov_y_rad = camera.fov_deg * M_PI / 180.0;
  v.lens_shift = camera.lens_shift;
  v.width = camera.width;
  v.height = camera.height;
  return impl_->draw(v, sun_direction, stars, moons);
}

void GlobeRenderer::set_star_catalogue(const std::vector<atmos::Star>& stars) { impl_->pass.set_star_catalogue(stars); }

}  // namespace atmos_cli
