// Random valid runs: cameras, suns and moons for the renderer; engine frames
// (matrices, depth encodings, depth buffers, G-buffers, shadow maps) for the
// plugin.
#include <epoxy/gl.h>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "random.hpp"
#include "sweep.hpp"

namespace atmos::sweep {

namespace {

constexpr std::uint64_t kRunStream = 2;

std::string vec(const glm::dvec3& v) {
  return "(" + number_text(v.x, 9) + ", " + number_text(v.y, 9) + ", " + number_text(v.z, 9) + ")";
}

// The unit vector of v, or `fallback` when v is zero.
glm::dvec3 direction_or(const glm::dvec3& v, const glm::dvec3& fallback) {
  const double l = glm::length(v);
  return l > 0.0 ? v / l : fallback;
}

// A unit vector orthogonal to the unit vector n.
glm::dvec3 any_perpendicular(const glm::dvec3& n) {
  const glm::dvec3 a = std::abs(n.x) < 0.9 ? glm::dvec3(1, 0, 0) : glm::dvec3(0, 1, 0);
  return glm::normalize(glm::cross(n, a));
}

// The unit vector at angle `angle` (radians) from the unit vector n, in a
// random direction around it.
glm::dvec3 tilted(Random& r, const glm::dvec3& n, double angle) {
  const glm::dvec3 u = any_perpendicular(n);
  const glm::dvec3 v = glm::cross(n, u);
  const double phi = r.uniform(0.0, 2.0 * M_PI);
  return glm::normalize(n * std::cos(angle) + (u * std::cos(phi) + v * std::sin(phi)) * std::sin(angle));
}

// A view direction: anywhere, at the horizon, towards the planet, near the sun.
glm::dvec3 random_forward(Random& r, const glm::dvec3& zenith, const glm::dvec3& sun) {
  const double kind = r.uniform();
  if (kind < 0.4) return r.unit_vector();
  if (kind < 0.6) return tilted(r, zenith, glm::radians(90.0 + r.uniform(-5.0, 5.0)));
  if (kind < 0.8) return tilted(r, -zenith, glm::radians(r.uniform(0.0, 60.0)));
  return tilted(r, sun, glm::radians(r.log_uniform(1e-3, 30.0)));
}

// An up hint not parallel to `forward` (the zenith when it is not).
glm::dvec3 random_up(Random& r, const glm::dvec3& forward, const glm::dvec3& zenith) {
  if (r.chance(0.5) && std::abs(glm::dot(forward, zenith)) < 0.999) return zenith;
  for (;;) {
    const glm::dvec3 up = r.unit_vector();
    if (std::abs(glm::dot(forward, up)) < 0.999) return up;
  }
}

// The sun: anywhere, or within 20° of the horizon of the point below the
// camera (sunset, twilight, the terminator).
glm::dvec3 random_sun(Random& r, const glm::dvec3& zenith) {
  if (r.chance(0.5)) return r.unit_vector();
  return tilted(r, zenith, glm::radians(90.0 + r.uniform(-20.0, 20.0)));
}

Camera random_renderer_camera(Random& r, const glm::dvec3& position, const glm::dvec3& zenith,
                              const glm::dvec3& sun) {
  Camera c;
  c.position = position;
  c.forward = random_forward(r, zenith, sun);
  c.up = random_up(r, c.forward, zenith);
  const double kind = r.uniform();
  if (kind < 0.5) {
    c.projection = Projection::perspective;
    c.fov_deg = r.chance(0.9) ? r.uniform(1.0, 170.0) : (r.chance(0.5) ? r.log_uniform(1e-3, 1.0) : 179.9);
  } else if (kind < 0.8) {
    c.projection = Projection::fisheye;
    c.fov_deg = r.chance(0.9) ? r.uniform(1.0, 360.0) : 360.0;
  } else {
    c.projection = Projection::equirect;
  }
  if (r.chance(0.05)) {
    c.width = r.integer(1, 4);
    c.height = r.integer(1, 4);
  } else {
    c.width = r.integer(16, 48);
    c.height = r.integer(16, 32);
  }
  return c;
}

// --- The plugin's engine frame ----------------------------------------------

struct Frustum {
  glm::dmat4 projection{1.0};
  double near = 0.0;
  double far = 0.0;  // infinity for infinite projections
};

// A perspective projection with an off-centre window: the near plane's
// window spans [left, right] x [bottom, top] (OpenGL's glFrustum), and the
// depth row maps view depth w = -z to
//   standard finite:   z_ndc = ((f + n) w - 2 f n) / ((f - n) w), -1 at n, 1 at f;
//   standard infinite: z_ndc = (w - 2 n) / w, the limit f -> infinity;
//   reversed-Z finite: z_ndc = n (f - w) / ((f - n) w), 1 at n, 0 at f (GL_ZERO_TO_ONE);
//   reversed-Z infinite: z_ndc = n / w.
Frustum random_frustum(Random& r, double aspect, DepthEncoding encoding, double units_per_metre, std::string& kind) {
  Frustum f;
  f.near = r.log_uniform(1e-3, 10.0) * units_per_metre;
  const bool infinite = encoding != DepthEncoding::logarithmic && r.chance(0.4);
  f.far = infinite ? INFINITY : f.near * r.log_uniform(10.0, 1e9);
  const double fov = glm::radians(r.chance(0.9) ? r.uniform(5.0, 150.0) : r.uniform(150.0, 175.0));
  const double half_height = f.near * std::tan(fov / 2.0);
  const double half_width = half_height * aspect;
  const double shift_x = r.chance(0.7) ? 0.0 : r.uniform(-0.8, 0.8) * half_width;
  const double shift_y = r.chance(0.7) ? 0.0 : r.uniform(-0.8, 0.8) * half_height;
  const double left = -half_width + shift_x, right = half_width + shift_x;
  const double bottom = -half_height + shift_y, top = half_height + shift_y;
  glm::dmat4 p(0.0);
  p[0][0] = 2.0 * f.near / (right - left);
  p[1][1] = 2.0 * f.near / (top - bottom);
  p[2][0] = (right + left) / (right - left);
  p[2][1] = (top + bottom) / (top - bottom);
  p[2][3] = -1.0;
  const double n = f.near, fa = f.far;
  if (encoding == DepthEncoding::reversed_z) {
    p[2][2] = infinite ? 0.0 : n / (fa - n);
    p[3][2] = infinite ? n : fa * n / (fa - n);
    kind = infinite ? "reversed-Z infinite" : "reversed-Z finite";
  } else {
    p[2][2] = infinite ? -1.0 : -(fa + n) / (fa - n);
    p[3][2] = infinite ? -2.0 * n : -2.0 * fa * n / (fa - n);
    kind = encoding == DepthEncoding::logarithmic ? "logarithmic" : (infinite ? "standard infinite" : "standard finite");
  }
  if (shift_x != 0.0 || shift_y != 0.0) kind += ", off-centre";
  kind += ", near " + number_text(f.near, 9) + ", far " + number_text(f.far, 9) + ", fov " +
          number_text(glm::degrees(fov), 9) + " deg";
  f.projection = p;
  return f;
}

// Window depth of a surface at view depth w (engine units) under each encoding.
float encode_depth(const FrameInput& in, double w) {
  if (in.depth_encoding == DepthEncoding::logarithmic)
    return float(std::log2(1.0 + w) / std::log2(1.0 + in.log_depth_far));
  const double z_ndc = (in.projection[2][2] * -w + in.projection[3][2]) / w;
  return float(in.depth_encoding == DepthEncoding::reversed_z ? z_ndc : 0.5 * z_ndc + 0.5);
}

// Nearest positive distance along `dir` (unit) from `origin` to a sphere, or -1.
double hit_sphere(const glm::dvec3& origin, const glm::dvec3& dir, double radius) {
  const double b = glm::dot(origin, dir);
  const double c = glm::dot(origin, origin) - radius * radius;
  const double h = b * b - c;
  if (h < 0.0) return -1.0;
  const double s = std::sqrt(h);
  if (-b - s > 0.0) return -b - s;
  if (-b + s > 0.0) return -b + s;
  return -1.0;
}

const GLenum kDepthFormats[] = {GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT24, GL_DEPTH_COMPONENT16,
                                GL_DEPTH24_STENCIL8,   GL_DEPTH32F_STENCIL8,  GL_R32F};
const GLenum kColourFormats[] = {GL_RGBA32F, GL_RGBA16F, GL_R11F_G11F_B10F};
const GLenum kOutputFormats[] = {GL_RGBA32F, GL_RGB32F, GL_RGBA16F, GL_RGB16F, GL_R11F_G11F_B10F};

template <size_t N>
GLenum pick(Random& r, const GLenum (&formats)[N]) {
  return formats[size_t(r.integer(0, int(N) - 1))];
}

PluginCase random_plugin_case(Random& r, const PlanetCase& planet, const glm::dvec3& position,
                              const glm::dvec3& zenith) {
  const Atmosphere& a = planet.atmosphere;
  const PlanetFrame& frame = planet.frame;
  PluginCase c;
  FrameInput& in = c.input;
  c.camera_planet = position;
  in.sun_direction = random_sun(r, zenith) * r.log_uniform(1e-3, 1e3);  // any length: normalised by the pass
  const glm::dvec3 sun = glm::normalize(in.sun_direction);
  if (r.chance(0.05)) {
    in.width = r.integer(1, 4);
    in.height = r.integer(1, 4);
  } else {
    in.width = r.integer(16, 48);
    in.height = r.integer(16, 32);
  }
  const double encoding = r.uniform();
  in.depth_encoding = encoding < 0.4 ? DepthEncoding::standard
                      : encoding < 0.75 ? DepthEncoding::reversed_z
                                        : DepthEncoding::logarithmic;
  in.surfaces = planet.surfaces;
  const glm::dvec3 forward = random_forward(r, zenith, sun);
  const glm::dvec3 up = random_up(r, forward, zenith);
  const glm::dvec3 eye = frame.centre + position * frame.units_per_metre;
  in.view = glm::lookAt(eye, eye + forward, up);
  const Frustum f = random_frustum(r, double(in.width) / double(in.height), in.depth_encoding,
                                   frame.units_per_metre, c.projection_kind);
  in.projection = f.projection;
  if (in.depth_encoding == DepthEncoding::logarithmic) in.log_depth_far = f.far;
  in.sun_illuminance_lux = r.chance(0.5) ? 0.0 : r.log_uniform(1e-3, 1e6);
  in.nits_per_unit = r.log_uniform(1e-3, 1e6);
  in.sun_disc = r.chance(0.8);
  in.stars = planet.plugin_stars;
  in.timed = r.chance(0.1);
  if (planet.moons) in.moons = random_moons(r, a, position, sun);

  c.depth_format = planet.formats.depth;
  c.colour_format = planet.formats.colour;
  c.output_format = planet.formats.output;

  // The depth buffer: sky, the ground sphere (raised or lowered by up to a
  // tenth of the atmosphere's thickness), surfaces at random depths, or the
  // ground with random surfaces in front of or behind it.
  const double content = r.uniform();
  c.depth_content = content < 0.1 ? "sky" : content < 0.45 ? "planet" : content < 0.7 ? "noise" : "planet + noise";
  const bool planet_surface = c.depth_content == "planet" || c.depth_content == "planet + noise";
  const bool noise = c.depth_content == "noise" || c.depth_content == "planet + noise";
  const double thickness = a.top_radius_m - a.bottom_radius_m;
  const double ground_radius = a.bottom_radius_m + thickness * r.uniform(-0.1, 0.1);
  const double sky_fraction = r.uniform();
  const double far_surface = std::isinf(f.far) ? f.near * 1e9 : f.far;
  const glm::vec3 base_albedo(float(r.uniform()), float(r.uniform()), float(r.uniform()));
  const glm::dmat4 inverse_projection = glm::inverse(in.projection);
  const glm::dmat3 view_to_world = glm::transpose(glm::dmat3(in.view));
  const float clear = in.depth_encoding == DepthEncoding::reversed_z ? 0.0f : 1.0f;
  const size_t n = size_t(in.width) * size_t(in.height);
  c.depth.assign(n, clear);
  c.colour.assign(n, glm::vec3(0.0f));
  c.normal.assign(n, glm::vec3(0.0f, 0.0f, 1.0f));
  for (int y = 0; y < in.height; ++y) {
    for (int x = 0; x < in.width; ++x) {
      const size_t i = size_t(y) * size_t(in.width) + size_t(x);
      const glm::dvec4 ndc((x + 0.5) / in.width * 2.0 - 1.0, (y + 0.5) / in.height * 2.0 - 1.0, 0.0, 1.0);
      const glm::dvec4 q = inverse_projection * ndc;
      const glm::dvec3 view_dir = glm::normalize(glm::dvec3(q) / q.w);
      const glm::dvec3 world_dir = glm::normalize(view_to_world * view_dir);
      double w = -1.0;  // view depth of the surface, engine units
      glm::dvec3 normal = r.unit_vector();
      if (planet_surface) {
        const double t = hit_sphere(position, world_dir, ground_radius);
        if (t > 0.0) {
          w = t * frame.units_per_metre * -view_dir.z;
          normal = glm::normalize(position + world_dir * t);
        }
      }
      if (noise && !r.chance(sky_fraction)) {
        const double wn = r.log_uniform(f.near, far_surface);
        if (w < 0.0 || r.chance(0.5)) w = wn;
      }
      if (w >= f.near && w <= f.far) {
        c.depth[i] = encode_depth(in, w);
        c.normal[i] = glm::vec3(normal);
        if (in.surfaces == SurfaceMode::lit_colour) {
          c.colour[i] = glm::vec3(float(r.log_uniform(1e-4, 1e3)), float(r.log_uniform(1e-4, 1e3)),
                                  float(r.log_uniform(1e-4, 1e3)));
          if (r.chance(0.05)) c.colour[i] = glm::vec3(0.0f);
        } else {
          c.colour[i] = r.chance(0.7) ? base_albedo : glm::vec3(float(r.uniform()), float(r.uniform()), float(r.uniform()));
        }
      }
    }
  }

  // A sun shadow map: an orthographic view along the sun around a point
  // near the camera, with random depths.
  if (planet.shadow_map) {
    c.shadow_size = r.integer(4, 64);
    c.shadow_format = planet.formats.shadow;
    const double extent = r.log_uniform(10.0, 1e5) * frame.units_per_metre;
    const glm::dvec3 target = eye + r.unit_vector() * extent * r.uniform(0.0, 1.0);
    const glm::dvec3 light_eye = target + sun * extent * 2.0;
    const glm::dmat4 light_view = glm::lookAt(light_eye, target, any_perpendicular(sun));
    in.shadow_matrix = glm::ortho(-extent, extent, -extent, extent, 0.0, 4.0 * extent) * light_view;
    in.shadow_steps = r.integer(1, 256);
    in.shadow_bias_m = r.chance(0.5) ? 0.0 : r.log_uniform(1e-3, 1e3);
    c.shadow_depth.resize(size_t(c.shadow_size) * size_t(c.shadow_size));
    const bool flat = r.chance(0.3);
    const float flat_depth = float(r.uniform());
    for (float& d : c.shadow_depth) d = flat ? flat_depth : float(r.uniform());
  }
  return c;
}

}  // namespace

TextureFormats random_texture_formats(Random& r) {
  TextureFormats f;
  f.depth = pick(r, kDepthFormats);
  f.colour = pick(r, kColourFormats);
  f.output = r.chance(0.5) ? 0 : pick(r, kOutputFormats);
  f.shadow = pick(r, kDepthFormats);
  if (f.shadow == GL_R32F) f.shadow = GL_DEPTH_COMPONENT32F;
  return f;
}

glm::dvec3 random_camera_position(Random& r, const Atmosphere& a) {
  const double R = a.bottom_radius_m, T = a.top_radius_m;
  const double kind = r.uniform();
  double radius;
  if (kind < 0.01) {
    radius = 0.0;  // the planet's centre
  } else if (kind < 0.08) {
    radius = R * r.uniform(0.0, 1.0);
  } else if (kind < 0.12) {
    radius = R - std::min(r.log_uniform(1e-3, 1e4), 0.5 * R);  // just below the ground
  } else if (kind < 0.3) {
    radius = R + std::min(r.log_uniform(1e-2, 1e3), T - R);  // the first kilometre
  } else if (kind < 0.55) {
    radius = r.uniform(R, T);
  } else if (kind < 0.65) {
    const double d = std::min(r.log_uniform(1e-1, 1e4), 0.5 * (T - R));
    radius = r.chance(0.5) ? T - d : T + d;  // around the top of the atmosphere
  } else {
    radius = r.log_uniform(T, 100.0 * R);
  }
  return r.unit_vector() * radius;
}

std::vector<Moon> random_moons(Random& r, const Atmosphere& a, const glm::dvec3& camera, const glm::dvec3& sun) {
  std::vector<Moon> moons;
  const int count = r.integer(1, kMaxMoons);
  const double T = a.top_radius_m;
  const glm::dvec3 up = direction_or(camera, sun);
  for (int i = 0; i < count; ++i) {
    for (int attempt = 0; attempt < 20; ++attempt) {
      Moon m;
      if (r.chance(0.6)) {
        // On the sun or near it, seen from a point of the atmosphere above
        // or near the camera's nadir. From an observer o (|o| <= T), a
        // moon of angular radius α at distance d along u has its centre at
        // |o + d u| >= d - T and radius d sin α, so it clears the
        // atmosphere (|centre| - radius > T) when d (1 - sin α) > 2 T.
        const glm::dvec3 observer =
            tilted(r, up, glm::radians(r.uniform(0.0, 5.0))) * (a.bottom_radius_m + r.uniform(0.0, 1.0) * (T - a.bottom_radius_m));
        const double alpha = std::min(a.sun_angular_radius_rad * r.log_uniform(0.5, 2.0), glm::radians(10.0));
        const double offset = (a.sun_angular_radius_rad + alpha) * r.uniform(0.0, 1.5);
        const glm::dvec3 direction = offset > 0.0 ? tilted(r, sun, offset) : sun;
        const double d_min = 2.01 * T / (1.0 - std::sin(alpha));
        const double d = r.log_uniform(d_min, std::max(2.0 * d_min, std::min(1e3 * T, 1e11)));
        m = moon_in_sky(observer, direction, alpha, d);
      } else {
        const double distance = r.log_uniform(1.1 * T, 1e11);
        m.centre_m = r.unit_vector() * distance;
        m.radius_m = r.log_uniform(1e-3 * (distance - T), 0.9 * (distance - T));
      }
      try {
        std::vector<Moon> with = moons;
        with.push_back(m);
        validate_moons(with, T);
        moons = with;
        break;
      } catch (const Error&) {
        // Rounding at the bounds: draw again.
      }
    }
  }
  return moons;
}

RunCase make_run(std::uint64_t seed, int index, const PlanetCase& planet, Targets targets) {
  Random r(derive_seed(seed, kRunStream, std::uint64_t(index)));
  RunCase run;
  run.index = index;
  const bool renderer = targets == Targets::renderer_only || (targets == Targets::both && r.chance(0.5));
  run.target = renderer ? Target::renderer : Target::plugin;
  const glm::dvec3 position = random_camera_position(r, planet.atmosphere);
  const glm::dvec3 zenith = direction_or(position, r.unit_vector());
  if (renderer) {
    RendererCase& c = run.renderer;
    c.sun = random_sun(r, zenith) * r.log_uniform(1e-3, 1e3);
    c.camera = random_renderer_camera(r, position, zenith, glm::normalize(c.sun));
    if (planet.moons) c.moons = random_moons(r, planet.atmosphere, position, glm::normalize(c.sun));
    c.stars = r.chance(0.3);
  } else {
    run.plugin = random_plugin_case(r, planet, position, zenith);
  }
  return run;
}

namespace {

const char* format_name(std::uint32_t f) {
  switch (f) {
    case 0: return "the pass's own";
    case GL_DEPTH_COMPONENT32F: return "DEPTH_COMPONENT32F";
    case GL_DEPTH_COMPONENT24: return "DEPTH_COMPONENT24";
    case GL_DEPTH_COMPONENT16: return "DEPTH_COMPONENT16";
    case GL_DEPTH24_STENCIL8: return "DEPTH24_STENCIL8";
    case GL_DEPTH32F_STENCIL8: return "DEPTH32F_STENCIL8";
    case GL_R32F: return "R32F";
    case GL_RGBA32F: return "RGBA32F";
    case GL_RGB32F: return "RGB32F";
    case GL_RGBA16F: return "RGBA16F";
    case GL_RGB16F: return "RGB16F";
    case GL_R11F_G11F_B10F: return "R11F_G11F_B10F";
    default: return "?";
  }
}

std::string moons_text(const std::vector<Moon>& moons) {
  std::string s = std::to_string(moons.size()) + " moons";
  for (const Moon& m : moons) s += "; centre " + vec(m.centre_m) + " m radius " + number_text(m.radius_m, 9) + " m";
  return s;
}

}  // namespace

std::string describe(const RunCase& run) {
  std::ostringstream o;
  if (run.target == Target::renderer) {
    const RendererCase& c = run.renderer;
    const char* projection = c.camera.projection == Projection::perspective ? "perspective"
                             : c.camera.projection == Projection::fisheye   ? "fisheye"
                                                                            : "equirect";
    o << "renderer: camera " << vec(c.camera.position) << " m (|r| " << number_text(glm::length(c.camera.position), 9)
      << "), forward " << vec(c.camera.forward) << ", up " << vec(c.camera.up) << ", " << projection << " fov "
      << number_text(c.camera.fov_deg, 9) << ", " << c.camera.width << "x" << c.camera.height << "\n  sun "
      << vec(c.sun) << ", stars " << (c.stars ? "on" : "off") << ", " << moons_text(c.moons);
    return o.str();
  }
  const PluginCase& c = run.plugin;
  const FrameInput& in = c.input;
  o << "plugin: camera " << vec(c.camera_planet) << " m planet-centred (|r| "
    << number_text(glm::length(c.camera_planet), 9) << "), " << in.width << "x" << in.height << ", "
    << (in.surfaces == SurfaceMode::lit_colour ? "lit colour" : "G-buffer") << ", depth "
    << (in.depth_encoding == DepthEncoding::standard     ? "standard"
        : in.depth_encoding == DepthEncoding::reversed_z ? "reversed-Z"
                                                         : "logarithmic (F " + number_text(in.log_depth_far, 9) + ")")
    << " in " << format_name(c.depth_format) << " (" << c.depth_content << ")\n  projection " << c.projection_kind
    << "\n  view row-major:";
  for (int row = 0; row < 4; ++row) {
    o << " [";
    for (int col = 0; col < 4; ++col) o << (col ? " " : "") << number_text(in.view[col][row], 9);
    o << "]";
  }
  o << "\n  sun " << vec(in.sun_direction) << ", sun lux " << number_text(in.sun_illuminance_lux, 9)
    << ", nits per unit " << number_text(in.nits_per_unit, 9) << ", sun disc " << (in.sun_disc ? "on" : "off")
    << ", stars " << (in.stars ? "on" : "off") << ", timed " << (in.timed ? "yes" : "no") << "\n  colour "
    << format_name(c.colour_format) << ", output " << format_name(c.output_format) << ", " << moons_text(in.moons);
  if (c.shadow_size > 0)
    o << "\n  shadow map " << c.shadow_size << "^2 " << format_name(c.shadow_format) << ", steps "
      << in.shadow_steps << ", bias " << number_text(in.shadow_bias_m, 9) << " m";
  return o.str();
}

}  // namespace atmos::sweep
