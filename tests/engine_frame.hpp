// A synthetic engine frame for the plugin's tests: an engine camera, the
// ground sphere and one round "mountain" ray-cast in double on the CPU into
// depth (in each of the plugin's depth encodings) and lit colour or a
// G-buffer, in an engine world of kilometres whose planet centre is away
// from the origin.
#pragma once

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "atmos/eclipse.hpp"
#include "atmos/plugin.hpp"
#include "gpu/atmosphere_pass.hpp"

namespace atmos_test {

using atmos::DepthEncoding;
using atmos::FrameInput;
using atmos::PlanetFrame;
using atmos::SurfaceMode;

// The engine's world: kilometres, planet centre away from the origin.
inline PlanetFrame engine_frame() {
  PlanetFrame f;
  f.centre = {1200.0, -6000.0, 300.0};
  f.units_per_metre = 1e-3;
  return f;
}

inline glm::dvec3 to_world(const PlanetFrame& f, const glm::dvec3& planet_metres) {
  return f.centre + planet_metres * f.units_per_metre;
}

// An engine camera and what it drew.
struct Shot {
  glm::dvec3 camera{0.0};        // planet-centred metres
  glm::dvec3 forward{0, 1, 0};   // unit, planet axes
  glm::dvec3 up_hint{0, 0, 1};
  double fov_deg = 60.0;
  int width = 64;
  int height = 48;
  DepthEncoding encoding = DepthEncoding::standard;
  bool infinite_far = false;
  SurfaceMode surfaces = SurfaceMode::lit_colour;
  glm::dvec3 sun{0, 0, 1};
  bool stars = false;
  // Geometry the engine draws: the ground sphere (planet radius + this, or
  // nothing if < -1e6) and one "mountain" sphere.
  double ground_offset_m = 2.0;
  double planet_radius_m = 6371e3;
  double near_km = 1e-4;  // the projection's near plane (engine units)
  glm::dvec3 mountain_centre{0.0};
  double mountain_radius_m = 0.0;
  std::vector<atmos::Moon> moons;  // FrameInput::moons (planet-centred metres)
};

struct EngineFrame {
  FrameInput input;
  atmos::gpu::CpuEngineBuffers buffers;
};

// Ray-sphere intersection in double: nearest positive distance, or -1.
inline double hit_sphere(const glm::dvec3& origin, const glm::dvec3& dir, const glm::dvec3& centre, double radius) {
  const glm::dvec3 oc = origin - centre;
  const double b = glm::dot(oc, dir);
  const double c = glm::dot(oc, oc) - radius * radius;
  const double h = b * b - c;
  if (h < 0.0) return -1.0;
  const double s = std::sqrt(h);
  if (-b - s > 0.0) return -b - s;
  if (-b + s > 0.0) return -b + s;
  return -1.0;
}

inline EngineFrame make_engine_frame(const Shot& shot) {
  const PlanetFrame f = engine_frame();
  EngineFrame e;
  FrameInput& in = e.input;
  in.width = shot.width;
  in.height = shot.height;
  in.surfaces = shot.surfaces;
  in.depth_encoding = shot.encoding;
  in.sun_direction = shot.sun;
  in.stars = shot.stars;
  in.moons = shot.moons;
  const glm::dvec3 eye = to_world(f, shot.camera);
  in.view = glm::lookAt(eye, eye + shot.forward, shot.up_hint);
  const double aspect = double(shot.width) / double(shot.height);
  const double fovy = glm::radians(shot.fov_deg);
  const double near = shot.near_km;
  const double far = 1e5;    // 100 000 km
  if (shot.encoding == DepthEncoding::reversed_z) {
    // Infinite reversed-Z (GL_ZERO_TO_ONE): z_ndc = near / w.
    const double t = 1.0 / std::tan(fovy / 2.0);
    in.projection = glm::dmat4(0.0);
    in.projection[0][0] = t / aspect;
    in.projection[1][1] = t;
    in.projection[2][3] = -1.0;
    in.projection[3][2] = near;
  } else if (shot.infinite_far) {
    in.projection = glm::infinitePerspective(fovy, aspect, near);
  } else {
    in.projection = glm::perspective(fovy, aspect, near, far);
  }
  if (shot.encoding == DepthEncoding::logarithmic) in.log_depth_far = far;

  const size_t n = size_t(shot.width) * size_t(shot.height);
  e.buffers.depth.assign(n, shot.encoding == DepthEncoding::reversed_z ? 0.0f : 1.0f);
  e.buffers.colour.assign(n, glm::vec3(0.0f));
  e.buffers.albedo.assign(n, glm::vec3(0.0f));
  e.buffers.normal.assign(n, glm::vec3(0.0f, 0.0f, 1.0f));
  const glm::dmat4 inverse_view_projection = glm::inverse(in.projection * in.view);
  for (int y = 0; y < shot.height; ++y) {
    for (int x = 0; x < shot.width; ++x) {
      const glm::dvec2 ndc((x + 0.5) / shot.width * 2.0 - 1.0, (y + 0.5) / shot.height * 2.0 - 1.0);
      glm::dvec4 p = inverse_view_projection * glm::dvec4(ndc, shot.encoding == DepthEncoding::reversed_z ? 1.0 : -1.0, 1.0);
      const glm::dvec3 dir = glm::normalize(glm::dvec3(p) / p.w - eye);
      // Cast in planet metres.
      double t = -1.0;
      glm::dvec3 centre(0.0);
      if (shot.ground_offset_m > -1e6) t = hit_sphere(shot.camera, dir, glm::dvec3(0.0), shot.planet_radius_m + shot.ground_offset_m);
      if (shot.mountain_radius_m > 0.0) {
        const double tm = hit_sphere(shot.camera, dir, shot.mountain_centre, shot.mountain_radius_m);
        if (tm > 0.0 && (t < 0.0 || tm < t)) {
          t = tm;
          centre = shot.mountain_centre;
        }
      }
      if (t < 0.0) continue;
      const glm::dvec3 hit = shot.camera + dir * t;
      const glm::dvec3 view_point = glm::dvec3(in.view * glm::dvec4(to_world(f, hit), 1.0));
      const double w = -view_point.z;
      const size_t i = size_t(y) * size_t(shot.width) + size_t(x);
      if (shot.encoding == DepthEncoding::logarithmic) {
        e.buffers.depth[i] = float(std::log2(1.0 + w) / std::log2(1.0 + in.log_depth_far));
      } else {
        const glm::dvec4 clip = in.projection * glm::dvec4(view_point, 1.0);
        const double z = clip.z / clip.w;
        e.buffers.depth[i] = float(shot.encoding == DepthEncoding::reversed_z ? z : 0.5 * z + 0.5);
      }
      const glm::dvec3 normal = glm::normalize(hit - centre);
      e.buffers.normal[i] = glm::vec3(normal);
      e.buffers.albedo[i] = glm::vec3(0.15f, 0.2f, 0.1f);
      // A lit colour of a few hundred cd/m², darker where the sun is low.
      const double lambert = std::max(glm::dot(normal, glm::normalize(shot.sun)), 0.0);
      e.buffers.colour[i] = glm::vec3(float(300.0 * lambert + 20.0), float(350.0 * lambert + 25.0),
                                      float(250.0 * lambert + 30.0));
    }
  }
  return e;
}

}  // namespace atmos_test
