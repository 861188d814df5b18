// The sweep's loop: tables per planet, the renderer and the plugin built
// once per planet, every run's output read back and checked.
#include "sweep.hpp"

#include <epoxy/gl.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <exception>
#include <memory>
#include <sstream>

#include "atmos/colour.hpp"
#include "atmos/post.hpp"

namespace atmos::sweep {

namespace {

std::atomic<int> g_current_run{-1};

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Largest finite value of a half float (IEEE 754 binary16), and of the
// 11- and 10-bit floats of R11F_G11F_B10F.
constexpr double kHalfMax = 65504.0;
constexpr double kPackedFloatMax = 65024.0;

bool reduced_precision(std::uint32_t format) {
  return format == GL_RGBA16F || format == GL_RGB16F || format == GL_R11F_G11F_B10F;
}

// The rounding of an output format: twice the unit roundoff of its
// mantissa (10 bits for half floats, 5 for the 10-bit blue of
// R11F_G11F_B10F, whose channels are also unsigned: a negative value is
// stored as 0), the spacing of its subnormals, where rounding is absolute
// (2^-24 for half floats; 2^-19 for the 10-bit float, whose exponent bias
// is 15 with 5 mantissa bits), and its largest value, where the driver
// clamps.
CheckPrecision output_precision(std::uint32_t format) {
  CheckPrecision p;
  if (format == GL_RGBA16F || format == GL_RGB16F) {
    p.epsilon = 0x1.0p-10;
    p.subnormal_spacing = 0x1.0p-24;
    p.saturation = kHalfMax;
  } else if (format == GL_R11F_G11F_B10F) {
    p.epsilon = 0x1.0p-5;
    p.subnormal_spacing = 0x1.0p-19;
    p.saturation = kPackedFloatMax;
  }
  return p;
}

// The engine's textures of one frame, deleted with it.
struct EngineTextures {
  std::vector<GLuint> names;
  ~EngineTextures() {
    if (!names.empty()) glDeleteTextures(GLsizei(names.size()), names.data());
  }
  GLuint create(GLenum format, int w, int h) {
    GLuint t = 0;
    glCreateTextures(GL_TEXTURE_2D, 1, &t);
    glTextureStorage2D(t, 1, format, w, h);
    names.push_back(t);
    return t;
  }
};

// A depth texture of `format` holding `depth` (window depth in [0, 1]).
GLuint upload_depth(EngineTextures& textures, GLenum format, int w, int h, const std::vector<float>& depth) {
  const GLuint t = textures.create(format, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  switch (format) {
    case GL_R32F: glTextureSubImage2D(t, 0, 0, 0, w, h, GL_RED, GL_FLOAT, depth.data()); break;
    case GL_DEPTH24_STENCIL8: {
      // GL_UNSIGNED_INT_24_8: depth in the high 24 bits as a normalised integer.
      std::vector<std::uint32_t> packed(depth.size());
      for (size_t i = 0; i < depth.size(); ++i)
        packed[i] = std::uint32_t(std::lround(double(std::clamp(depth[i], 0.0f, 1.0f)) * 16777215.0)) << 8;
      glTextureSubImage2D(t, 0, 0, 0, w, h, GL_DEPTH_STENCIL, GL_UNSIGNED_INT_24_8, packed.data());
      break;
    }
    case GL_DEPTH32F_STENCIL8: {
      // GL_FLOAT_32_UNSIGNED_INT_24_8_REV: a float depth, then 32 bits of which the low 8 are the stencil.
      std::vector<std::uint32_t> packed(2 * depth.size(), 0u);
      for (size_t i = 0; i < depth.size(); ++i) std::memcpy(&packed[2 * i], &depth[i], sizeof(float));
      glTextureSubImage2D(t, 0, 0, 0, w, h, GL_DEPTH_STENCIL, GL_FLOAT_32_UNSIGNED_INT_24_8_REV, packed.data());
      break;
    }
    default: glTextureSubImage2D(t, 0, 0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data()); break;
  }
  return t;
}

GLuint upload_rgb(EngineTextures& textures, GLenum format, int w, int h, const std::vector<glm::vec3>& rgb) {
  const GLuint t = textures.create(format, w, h);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage2D(t, 0, 0, 0, w, h, GL_RGB, GL_FLOAT, rgb.data());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
  return t;
}

std::string gl_error_name(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    default: return "GL error " + std::to_string(e);
  }
}

// The first pending GL error, clearing all of them; "" if none.
std::string take_gl_errors() {
  std::string first;
  for (GLenum e = glGetError(); e != GL_NO_ERROR; e = glGetError())
    if (first.empty()) first = gl_error_name(e);
  return first;
}

struct Outcome {
  std::string kind;  // "" when passed
  std::string message;
  PixelCheck check;
};

std::string pixel_message(const PixelCheck& c, const char* rows) {
  std::ostringstream o;
  o << c.nan << " NaN, " << c.inf << " infinite, " << c.negative << " negative pixels; first at (" << c.x << ", " << c.y
    << ") " << rows << ": (" << number_text(c.value.x, 9) << ", " << number_text(c.value.y, 9) << ", "
    << number_text(c.value.z, 9) << ")";
  return o.str();
}

// The plugin on one engine frame. Returns the output read back (rows bottom-up).
Image render_plugin(AtmospherePass& pass, const PluginCase& c, std::uint32_t output_format, std::string& setup_error) {
  EngineTextures textures;
  FrameInput in = c.input;
  const int w = in.width, h = in.height;
  in.depth = upload_depth(textures, c.depth_format, w, h, c.depth);
  if (in.surfaces == SurfaceMode::lit_colour) {
    in.colour = upload_rgb(textures, c.colour_format, w, h, c.colour);
  } else {
    in.albedo = upload_rgb(textures, c.colour_format, w, h, c.colour);
    in.normal = upload_rgb(textures, GL_RGBA32F, w, h, c.normal);
  }
  if (c.shadow_size > 0)
    in.shadow_map = upload_depth(textures, c.shadow_format, c.shadow_size, c.shadow_size, c.shadow_depth);
  if (output_format != 0) in.output = textures.create(output_format, w, h);
  setup_error = take_gl_errors();
  if (!setup_error.empty()) return {};
  const std::uint32_t out = pass.render(in);
  return read_linear_image(out, w, h);
}

Outcome run_plugin(AtmospherePass& pass, const PluginCase& c, const glm::dmat3& to_radiance, SweepResult& result) {
  Outcome o;
  std::string setup_error;
  const Image image = render_plugin(pass, c, c.output_format, setup_error);
  if (!setup_error.empty()) {
    o.kind = "harness gl error";
    o.message = "uploading the engine's textures: " + setup_error;
    return o;
  }
  std::vector<bool> sky(c.depth.size());
  const float clear = c.input.depth_encoding == DepthEncoding::reversed_z ? 0.0f : 1.0f;
  for (size_t i = 0; i < sky.size(); ++i) sky[i] = c.depth[i] == clear;
  CheckPrecision precision = output_precision(c.output_format);
  precision.clamped_at_zero = true;
  o.check = check_image(image, to_radiance, precision, sky);
  if (!o.check.passed() && reduced_precision(c.output_format) && o.check.nan == 0 && o.check.negative == 0) {
    // Infinite values in a half-float (or 11/10-bit float) output: light
    // beyond the format's range, the engine's to scale with nits_per_unit,
    // if the same frame rendered to RGBA32F is finite and that large there.
    std::string again_error;
    const Image full = render_plugin(pass, c, GL_RGBA32F, again_error);
    CheckPrecision full_precision;
    full_precision.clamped_at_zero = true;
    const PixelCheck full_check = check_image(full, to_radiance, full_precision, sky);
    if (again_error.empty() && full_check.passed()) {
      bool overflow = true;
      int count = 0;
      const double limit = c.output_format == GL_R11F_G11F_B10F ? kPackedFloatMax : kHalfMax;
      for (size_t i = 0; i < image.rgb.size(); ++i) {
        if (std::isfinite(image.rgb[i])) continue;
        ++count;
        if (!(double(full.rgb[i]) > 0.5 * limit)) overflow = false;
      }
      if (overflow) {
        result.half_overflow_pixels += count;
        o.check = full_check;
      }
    }
  }
  result.pixels += (long long)(image.width) * image.height;
  result.out_of_gamut_pixels += o.check.out_of_gamut;
  if (!o.check.passed()) {
    o.kind = o.check.kind;
    o.message = pixel_message(o.check, "(x, y from the bottom-left, GL window coordinates)");
  }
  return o;
}

Outcome run_renderer(Renderer& renderer, const RendererCase& c, const glm::dmat3& to_radiance, SweepResult& result) {
  Outcome o;
  renderer.set_stars(c.stars);
  renderer.set_moons(c.moons);
  const Image image = renderer.render(c.camera, c.sun);
  o.check = check_image(image, to_radiance);
  result.pixels += (long long)(image.width) * image.height;
  result.out_of_gamut_pixels += o.check.out_of_gamut;
  if (!o.check.passed()) {
    o.kind = o.check.kind;
    o.message = pixel_message(o.check, "(x, y from the top-left)");
  }
  return o;
}

// What one planet needs for its runs: its tables and the GL objects built
// from them (only those its runs use).
struct PlanetState {
  PlanetCase planet;
  Tables tables;
  std::unique_ptr<Renderer> renderer;
  std::unique_ptr<AtmospherePass> pass;
  glm::dmat3 to_radiance{0.0};
  std::string error_kind;  // the planet could not be prepared: every run of it fails with this
  bool refused = false;    // the precomputation refused the planet with an atmos::Error
  std::string error;
};

template <typename F>
void catching(F&& f, std::string& kind, std::string& message) {
  try {
    f();
  } catch (const Error& e) {
    kind = "error";
    message = e.what();
  } catch (const std::exception& e) {
    kind = "exception";
    message = e.what();
  }
}

}  // namespace

std::string number_text(double x, int digits) {
  std::ostringstream o;
  o.precision(digits);
  o << x;
  return o.str();
}

int current_run_index() { return g_current_run.load(); }

glm::dmat3 radiance_from_srgb(const Atmosphere& atmosphere) {
  const std::vector<double>& w = atmosphere.wavelengths_nm;
  if (w.size() != 3) return glm::dmat3(0.0);
  const glm::dmat3 m(radiance_to_srgb_matrix({w[0], w[1], w[2]}));
  if (glm::determinant(m) == 0.0) return glm::dmat3(0.0);
  return glm::inverse(m);
}

namespace {

// Whether q = T c has a coordinate below -Σ_j |T_ij| (ε |c_j| + δ): each
// channel is off by at most ε relative or δ absolute (subnormals, or the
// underflow of the values it was computed from).
bool negative_coordinate(const glm::dmat3& t, const glm::dvec3& c, const CheckPrecision& precision) {
  const glm::dvec3 q = t * c;
  const double delta = std::max(precision.subnormal_spacing, precision.underflow_floor);
  const glm::dvec3 channel_error = precision.epsilon * glm::abs(c) + glm::dvec3(delta);
  const glm::dvec3 bound = glm::dmat3(glm::abs(t[0]), glm::abs(t[1]), glm::abs(t[2])) * channel_error;
  return q.x < -bound.x || q.y < -bound.y || q.z < -bound.z;
}

// XYZ from linear sRGB (srgb_to_xyz), as a matrix.
glm::dmat3 xyz_from_srgb() {
  return glm::dmat3(srgb_to_xyz({1.0, 0.0, 0.0}), srgb_to_xyz({0.0, 1.0, 0.0}), srgb_to_xyz({0.0, 0.0, 1.0}));
}

}  // namespace

PixelCheck check_image(const Image& image, const glm::dmat3& to_radiance, const CheckPrecision& precision,
                       const std::vector<bool>& atmosphere_only) {
  PixelCheck c;
  const bool three_wavelengths = to_radiance != glm::dmat3(0.0);
  const glm::dmat3 to_xyz = xyz_from_srgb();
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < image.width; ++x) {
      const size_t pixel = size_t(y) * size_t(image.width) + size_t(x);
      const glm::vec3 v(image.rgb[3 * pixel], image.rgb[3 * pixel + 1], image.rgb[3 * pixel + 2]);
      std::string kind;
      if (std::isnan(v.x) || std::isnan(v.y) || std::isnan(v.z)) {
        ++c.nan;
        kind = "nan";
      } else if (std::isinf(v.x) || std::isinf(v.y) || std::isinf(v.z)) {
        ++c.inf;
        kind = "inf";
      } else if (std::max({v.x, v.y, v.z}) < precision.saturation) {
        const glm::dvec3 rgb(v);
        const bool clamped = precision.clamped_at_zero && (v.x == 0.0f || v.y == 0.0f || v.z == 0.0f);
        const bool radiance_check =
            three_wavelengths && !clamped && (atmosphere_only.empty() || atmosphere_only[pixel]);
        if (negative_coordinate(to_xyz, rgb, precision) ||
            (radiance_check && negative_coordinate(to_radiance, rgb, precision))) {
          ++c.negative;
          kind = "negative";
        } else if (std::min({v.x, v.y, v.z}) < 0.0f) {
          ++c.out_of_gamut;
        }
      }
      if (!kind.empty() && c.kind.empty()) {
        c.kind = kind;
        c.x = x;
        c.y = y;
        c.value = v;
      }
    }
  }
  return c;
}

SweepResult run_sweep(const SweepOptions& options) {
  const auto start = Clock::now();
  SweepResult result;
  const int per_planet = std::max(options.runs_per_planet, 1);
  const int first = options.replay >= 0 ? options.replay : std::clamp(options.first_run, 0, options.runs);
  const int end = options.replay >= 0 ? options.replay + 1 : options.runs;
  std::unique_ptr<PlanetState> state;
  for (int index = first; index < end; ++index) {
    const int planet = index / per_planet;
    if (!state || state->planet.index != planet) {
      state.reset();
      state = std::make_unique<PlanetState>();
      ++result.planets;
      const auto planet_start = Clock::now();
      // Which targets this planet's runs use (the GL objects are built only for those).
      bool needs_renderer = false, needs_plugin = false;
      std::string kind, message;
      catching(
          [&] {
            state->planet = make_planet(options.seed, planet);
            const int last = std::min(end, (planet + 1) * per_planet);
            for (int i = index; i < last; ++i) {
              const Target t = make_run(options.seed, i, state->planet, options.targets).target;
              (t == Target::renderer ? needs_renderer : needs_plugin) = true;
            }
          },
          kind, message);
      if (!kind.empty()) {
        state->planet.index = planet;
        state->error_kind = "generator " + kind;
        state->error = message;
      } else {
        auto t0 = Clock::now();
        catching([&] { state->tables = precompute_tables(state->planet.atmosphere, state->planet.options); }, kind,
                 message);
        result.precompute_seconds += seconds_since(t0);
        if (kind == "error") {
          state->refused = true;
          state->error_kind = "refused";
          state->error = message;
          result.refusals.push_back("planet " + std::to_string(planet) + " (" + state->planet.recipe + "): " + message);
        } else if (!kind.empty()) {
          state->error_kind = "precompute " + kind;
          state->error = message;
        } else {
          t0 = Clock::now();
          catching(
              [&] {
                if (needs_renderer)
                  state->renderer = std::make_unique<Renderer>(state->planet.atmosphere, state->tables,
                                                               state->planet.precision);
                if (needs_plugin)
                  state->pass =
                      std::make_unique<AtmospherePass>(state->planet.atmosphere, state->tables, state->planet.frame,
                                                       PassPrograms::none);
              },
              kind, message);
          result.setup_seconds += seconds_since(t0);
          if (!kind.empty()) {
            state->error_kind = "setup " + kind;
            state->error = message;
          }
        }
        state->to_radiance = radiance_from_srgb(state->planet.atmosphere);
      }
      if (options.log)
        options.log("planet " + std::to_string(planet) + ": " + state->planet.recipe + "; prepared in " +
                    number_text(seconds_since(planet_start), 9) + " s" +
                    (state->error_kind.empty() ? "" : " (" + state->error_kind + ": " + state->error + ")"));
    }

    g_current_run.store(index);
    Failure failure;
    failure.index = index;
    failure.planet = planet;
    RunCase run;
    if (state->error_kind.empty()) {
      std::string kind, message;
      catching([&] { run = make_run(options.seed, index, state->planet, options.targets); }, kind, message);
      if (!kind.empty()) {
        failure.kind = "generator " + kind;
        failure.message = message;
      } else {
        const auto t0 = Clock::now();
        Outcome outcome;
        catching(
            [&] {
              take_gl_errors();
              outcome = run.target == Target::renderer
                            ? run_renderer(*state->renderer, run.renderer, state->to_radiance, result)
                            : run_plugin(*state->pass, run.plugin, state->to_radiance, result);
              if (run.target == Target::plugin && options.log && run.plugin.input.timed) {
                const PassTimings& t = state->pass->last_timings();
                options.log("  timings: sky view " + number_text(t.sky_view_ms, 9) + " ms, volume " +
                            number_text(t.volume_ms, 9) + " ms, composite " + number_text(t.composite_ms, 9) +
                            " ms, |r| " + number_text(glm::length(run.plugin.camera_planet), 9) +
                            (run.plugin.shadow_size ? " shadows" : "") +
                            (run.plugin.input.moons.empty() ? "" : " moons") + " " +
                            std::to_string(run.plugin.input.width) + "x" + std::to_string(run.plugin.input.height));
              }
              if (outcome.kind.empty()) {
                const std::string gl = take_gl_errors();
                if (!gl.empty()) {
                  outcome.kind = "gl error";
                  outcome.message = gl + " after the run";
                }
              }
            },
            outcome.kind, outcome.message);
        const double run_seconds = seconds_since(t0);
        result.render_seconds += run_seconds;
        if (options.log)
          options.log("run " + std::to_string(index) + " " + (run.target == Target::renderer ? "renderer" : "plugin") +
                      " " + number_text(run_seconds, 9) + " s " + (outcome.kind.empty() ? "passed" : outcome.kind));
        failure.kind = outcome.kind;
        failure.message = outcome.message;
      }
    } else if (!state->refused) {
      failure.kind = state->error_kind;
      failure.message = state->error;
    }
    failure.target = run.target;
    if (state->refused) ++result.refused_runs;
    ++result.runs;
    (run.target == Target::renderer ? result.renderer_runs : result.plugin_runs) += 1;
    if (!failure.kind.empty()) {
      failure.configuration = describe(state->planet) + "\n" + (state->error_kind.empty() ? describe(run) : "");
      ++result.failures_by_kind[failure.kind];
      result.failures.push_back(std::move(failure));
    }
    g_current_run.store(-1);
    if (options.progress) {
      const std::string status = result.failures.empty() ? "" : std::to_string(result.failures.size()) + " failed";
      options.progress(result.runs, end - first, status);
    }
  }
  result.seconds = seconds_since(start);
  return result;
}

std::string summary(const SweepResult& r, const SweepOptions& options) {
  std::ostringstream o;
  o << "sweep: seed " << options.seed << ", " << r.runs << " runs (" << r.renderer_runs << " renderer, "
    << r.plugin_runs << " plugin) on " << r.planets << " planets, " << r.pixels << " pixels\n";
  o << "  failures: " << r.failures.size();
  for (const auto& [kind, count] : r.failures_by_kind) o << "; " << kind << " " << count;
  if (r.refused_runs > 0) {
    o << "\n  refused by the library with a clear error (not failures): " << r.refused_runs << " runs on "
      << r.refusals.size() << " planets";
    for (const std::string& line : r.refusals) o << "\n    " << line;
  }
  o << "\n  out-of-gamut pixels (negative linear sRGB of non-negative light, not failures): "
    << r.out_of_gamut_pixels << "\n";
  o << "  half-float overflow pixels (infinite in a 16-bit output, finite above its range in RGBA32F): "
    << r.half_overflow_pixels << "\n";
  o.precision(3);
  o << std::fixed << "  time: " << r.seconds << " s (tables " << r.precompute_seconds << " s, renderer and pass "
    << r.setup_seconds << " s, runs " << r.render_seconds << " s)\n";
  return o.str();
}

std::string describe(const Failure& f) {
  std::ostringstream o;
  o << "run " << f.index << " (planet " << f.planet << ", " << (f.target == Target::renderer ? "renderer" : "plugin")
    << "): " << f.kind << ": " << f.message << "\n" << f.configuration;
  return o.str();
}

}  // namespace atmos::sweep
