// atmos — real-time rendering of an atmosphere with OpenGL 4.5, headless,
// and the same image computed on the CPU.
//
// Both paths evaluate the one definition of the physics
// (src/physics/radiance_to_camera.glsl: radiance_along_view_ray) and of the camera
// model (src/gpu/camera.glsl), the GPU as GLSL, the CPU as C++, with the same
// lookup tables. They differ only by floating-point rounding (the GPU's own
// sin/cos/sqrt, evaluation order): ~1e-5 relative in the sky, up to ~1e-2
// for ground seen from a few metres, where float32 planet-centred
// coordinates amplify one-ulp differences of the view ray (see
// tests/gpu_test.cpp for the measurements).
//
// Units: positions in metres relative to the planet centre, angles in degrees,
// output in linear sRGB on the cd/m² luminance scale (atmos/image.hpp).
#pragma once

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/image.hpp"
#include "atmos/tables.hpp"

namespace atmos {

enum class Projection {
  perspective,  // pinhole; fov_deg is the vertical field of view
  fisheye,      // equidistant all-sky: the angle from `forward` grows linearly with the distance from the
                // image centre, reaching fov_deg / 2 on the largest centred circle; pixels outside it are black
  equirect,     // whole sphere: x -> azimuth -180..180° (forward at the centre, right at +90°),
                // y -> elevation +90° (top row, towards `up`) .. -90°; fov_deg is ignored
};

// Internal format of the scattering and irradiance textures: RGB16F (half
// the memory and bandwidth, 11 significant bits, rounded on the CPU) or
// RGB32F. The optical-depth texture (the transmittance of every wavelength
// triple) is RGB32F in both cases: it is small (a few hundred KB, no
// bandwidth worth saving), and the lookups subtract two of its values for
// every transmittance along a ray: the depth of a short segment is the
// difference of two long paths' depths (tens at the horizon), which half
// floats' 11 bits would lose.
enum class TexturePrecision { half, full };

struct Camera {
  glm::dvec3 position{0.0};      // metres, planet-centred
  glm::dvec3 forward{0, 1, 0};   // view direction (normalised internally)
  glm::dvec3 up{0, 0, 1};        // up hint: need not be orthogonal to forward, only not parallel
  double fov_deg = 60.0;         // perspective: vertical fov, in (0, 180); fisheye: full field, in (0, 360]
                                 // (180 for an all-sky image looking at the zenith); equirect: ignored
  Projection projection = Projection::perspective;
  int width = 640;               // pixels, 1..16384
  int height = 360;
  // Perspective only: an off-axis frustum, as a stereo eye's
  // (atmos/stereo.hpp). The image plane at distance 1 moves by lens_shift
  // (right, up), dimensionless (tangents): the image centre looks along
  // forward + right lens_shift.x + up lens_shift.y. Finite, |each| <= 100.
  glm::dvec2 lens_shift{0.0};
};

// A star of a catalogue, as the renderers draw it instead of the procedural
// star field (atmos/star_catalogue.hpp places the Yale Bright Star
// Catalogue's for a date and place: renderer_stars). Its image is a
// Gaussian of width star_image_sigma that integrates to its irradiance,
// attenuated by the atmosphere along the view ray like the sun's disc.
struct Star {
  glm::dvec3 direction{0.0, 0.0, 1.0};  // towards the star, the catalogue's frame (normalised internally)
  // Spectral irradiance above the atmosphere at 545 nm, the V band's
  // effective wavelength, W m⁻² nm⁻¹ (v_band_spectral_irradiance of its V).
  double v_band_irradiance = 0.0;
  // Its spectrum: a blackbody of this temperature, kelvin, in [1000, 100000],
  // scaled to v_band_irradiance at 545 nm.
  double temperature_k = 5772.0;
};

// Throws atmos::Error with one line naming the first bad star: a direction
// that is zero or not finite, an irradiance that is negative or not finite,
// a temperature outside [1000, 100000] K.
void validate_stars(const std::vector<Star>& stars);

// A star's irradiance above the atmosphere in the channels of tables
// computed at `wavelengths_nm` (three: at them; more: linear sRGB over
// 683 lm/W, weighted as the sun's is), as the renderers draw the
// catalogue's stars: its blackbody spectrum scaled to v_band_irradiance at
// 545 nm.
glm::vec3 star_channel_irradiance(const Star& star, const std::vector<double>& wavelengths_nm);

// Throws atmos::Error, naming `who`, unless `m` is a rotation (orthonormal
// with determinant 1, to 1e-6), as the star orientations the renderers
// take (FrameInput::world_from_star_catalogue) must be.
void validate_star_orientation(const glm::dmat3& m, const char* who);

// Throws atmos::Error with one line naming the first problem: non-finite
// position, zero or non-finite forward/up, up parallel to forward, size
// outside 1..16384, field of view outside its range.
void validate_camera(const Camera& camera);

// A desktop OpenGL 4.5 core context without any window or surface (EGL,
// EGL_KHR_surfaceless_context): Mesa's surfaceless platform first (llvmpipe
// or a render node), then the EGL devices (EGL_EXT_platform_device, e.g. the
// NVIDIA driver), then EGL_DEFAULT_DISPLAY. GL functions are resolved by
// libepoxy. The context is made current on the creating thread.
class GlContext {
 public:
  // Throws atmos::Error with one line such as
  // "no OpenGL 4.5 context: eglInitialize failed (EGL_NOT_INITIALIZED)".
  static std::unique_ptr<GlContext> create_headless();
  ~GlContext();
  GlContext(const GlContext&) = delete;
  GlContext& operator=(const GlContext&) = delete;

  // A new context in this one's share group (textures, buffers, programs),
  // for another thread: make it current there, and destroy it there (its
  // destructor releases it from the calling thread). The calling thread's
  // current context stays current. Throws atmos::Error as create_headless().
  std::unique_ptr<GlContext> create_shared();
  // Makes the context current on the calling thread (no-op when it already is).
  void make_current();
  // GL_RENDERER and GL_VERSION, e.g. "llvmpipe (LLVM 15.0.6, 256 bits), OpenGL 4.5 (Core Profile) Mesa 22.3.6".
  std::string renderer_string();

 private:
  GlContext(void* display, void* context) : display_(display), context_(context) {}
  void* display_;  // EGLDisplay
  void* context_;  // EGLContext
};

// Renders images of one atmosphere from its tables on the GPU.
//
// OpenGL contexts (the rule of every GL class of atmos: Renderer,
// AtmospherePass, PostProcess): the class neither creates, owns nor switches
// a context. Construct it, call it and destroy it with an OpenGL 4.5 core
// context current on the calling thread: the engine's, or one from
// GlContext::create_headless(). The constructor throws atmos::Error when no
// such context is current; destroyed without one, its GL objects are left to
// die with their context.
class Renderer {
 public:
  // Uploads the tables (computed for the atmosphere's wavelengths, three or
  // spectral) and the atmosphere's parameters; its shaders depend on the
  // atmosphere's structure alone and are shared with any Renderer or
  // AtmospherePass of the same structure in the context's share group (see
  // AtmospherePass::glsl_library), else linked at their first use. Throws
  // atmos::Error without a current OpenGL 4.5 context, on mismatched tables
  // or on shader compile/link errors (with the first lines of the info log).
  Renderer(const Atmosphere& atmosphere, const Tables& tables, TexturePrecision precision = TexturePrecision::full);
  ~Renderer();
  Renderer(const Renderer&) = delete;
  Renderer& operator=(const Renderer&) = delete;

  // `sun_direction`: unit vector from the planet towards the sun (normalised
  // internally). The camera position is passed to the GPU as float (about
  // 0.5 m resolution at the Earth's surface, enough for the atmosphere).
  Image render(const Camera& camera, const glm::dvec3& sun_direction);

  // The star field behind the atmosphere (src/physics/stars.glsl: a
  // procedural sky with the real sky's counts per magnitude, attenuated by
  // the atmosphere and drowned by its light by day). Off by default; the CLI
  // turns it on when the sun is below the horizon (or with --stars).
  void set_stars(bool enabled);
  bool stars() const;

  // The stars of a catalogue instead of the procedural field, drawn when
  // the stars are on; empty (the default): the procedural field. Throws
  // atmos::Error as validate_stars does (the previous catalogue is kept).
  // The catalogue's frame is turned into the camera's by
  // set_star_orientation (the identity by default), so that a sky of
  // another time needs only a new rotation.
  void set_star_catalogue(const std::vector<Star>& stars);
  const std::vector<Star>& star_catalogue() const;
  // The rotation from the catalogue's frame to the camera's (world) frame;
  // throws atmos::Error unless it is a rotation (orthonormal, determinant 1,
  // to 1e-6).
  void set_star_orientation(const glm::dmat3& world_from_catalogue);

  // The moons that may eclipse the sun (include/atmos/eclipse.hpp), in the
  // planet-centred frame of the camera; none by default. Throws
  // atmos::Error as validate_moons does (the previous moons are kept).
  // With moons, the sky-view table is the eclipsed one: single scattering
  // integrated along every view ray (as at twilight) over the full azimuth.
  void set_moons(const std::vector<Moon>& moons);
  const std::vector<Moon>& moons() const;

  // GPU time of the draw of the last render() in milliseconds (all tiles,
  // excluding the read-back); 0 before the first render. From GL_TIME_ELAPSED
  // queries, except on software rasterisers (llvmpipe, softpipe, SwiftShader):
  // their queries time only the submission of the deferred rasterisation, so
  // there it is the wall-clock time of the draw up to glFinish — the time
  // the "GPU", i.e. the CPU, spent rendering.
  double last_frame_ms() const;
  // The part of last_frame_ms() spent on the sky-view table (the per-frame
  // low-sun single scattering).
  double last_sky_view_ms() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The same image computed on the CPU (all cores, TBB) with the same shared
// functions and camera model; for tests and as a fallback without OpenGL.
// `stars`: as Renderer::set_stars; `moons`: as Renderer::set_moons.
// `star_catalogue` and `world_from_catalogue`: as Renderer::set_star_catalogue
// and set_star_orientation.
Image render_cpu(const Atmosphere& atmosphere, const Tables& tables, const Camera& camera,
                 const glm::dvec3& sun_direction, bool stars = false, const std::vector<Moon>& moons = {},
                 const std::vector<Star>& star_catalogue = {},
                 const glm::dmat3& world_from_catalogue = glm::dmat3(1.0));

// Width (Gaussian sigma, radians) of a star's image in this camera's pixels:
// 0.6 of a pixel's angular size at the image centre, so that a star lights a
// pixel or two wherever it falls.
double star_image_sigma(const Camera& camera);

}  // namespace atmos
