// atmos — the engine plugin: the atmosphere as a post-process over any
// renderer's colour and depth buffers (Collienne 2013, §4.2–4.5).
//
// An engine renders its planet as usual (terrain, objects, its own lighting)
// into an HDR colour texture and a depth texture, then calls
// AtmospherePass::render() once per view. The pass reconstructs every
// pixel's position from the depth buffer and
//  - where nothing was drawn (depth at the far plane): draws the sky, the
//    planet as a Lambertian sphere below the horizon (so a terrain patch sits
//    on a whole planet), and the sun disc;
//  - where a surface was drawn: attenuates it by the transmittance between
//    the camera and the surface and adds the light scattered in between
//    (aerial perspective), optionally lighting it first from a G-buffer;
//  - with a sun shadow map: removes the single scattering of the shadowed
//    parts of each view ray (light shafts; no Mie halo through mountains).
// The camera can be anywhere: on the ground, in the atmosphere, in space
// (the atmosphere's night side stays dark in the planet's shadow), far away.
//
// Units. Positions and matrices are in the engine's units and world frame;
// PlanetFrame says where the planet is and how long a metre is. Radiance is
// linear sRGB on the luminance scale, cd/m², divided by
// FrameInput::nits_per_unit (so that an engine with half-float buffers can
// keep the sun's ~1e9 cd/m² in range). In SurfaceMode::lit_colour the
// engine's colour must be in those same units (use the GLSL library below to
// light it with the atmosphere's sun and sky irradiance).
//
// Threading and GL state: the OpenGL context rule of Renderer (renderer.hpp).
// Construct, use and destroy the pass with the engine's OpenGL 4.5 core
// context current (the pass never creates, owns or switches contexts; the
// constructor throws atmos::Error without one). render() changes the bound program, vertex array,
// framebuffer, viewport, texture units 0–15 and their sampler objects, image
// units 0–3, the stencil state, and disables blending, depth and stencil
// tests, scissor and sRGB conversion; it restores none of them (engines
// typically set their state per pass; docs/plugin.md, OpenGL state).
//
// Precision. The CPU side works in double: the camera position, the view
// and projection matrices are reduced to camera-relative floats before they
// reach the GPU, so that nothing shimmers at 1 m above the ground nor at a
// hundred planet radii.
#pragma once

#include <glm/mat4x4.hpp>
#include <glm/vec3.hpp>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/eclipse.hpp"
#include "atmos/image.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"

namespace atmos {

// The planet in the engine's world.
struct PlanetFrame {
  glm::dvec3 centre{0.0};        // engine units
  double units_per_metre = 1.0;  // engine units in one metre (> 0)
};

// How the engine's depth buffer encodes distance. The pass decides "sky"
// where the depth equals the clear value of the encoding: 1 for standard and
// logarithmic, 0 for reversed_z.
enum class DepthEncoding {
  // OpenGL's default: NDC z in [-1, 1] mapped to depth [0, 1]; any
  // perspective projection, with a finite or an infinite far plane.
  standard,
  // glClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE) with a projection mapping
  // the near plane to 1 and the far plane (or infinity) to 0.
  reversed_z,
  // depth = log2(1 + w) / log2(1 + F), w the distance along the view axis
  // (engine units) and F = FrameInput::log_depth_far — the usual
  // logarithmic depth written in gl_FragDepth. The projection matrix then
  // only gives the pixels' directions.
  logarithmic,
};

// What the engine's colour texture holds for surfaces.
enum class SurfaceMode {
  // Lit colour (Collienne 2013, §4.5): the pass attenuates it and adds in-scatter.
  lit_colour,
  // The pass lights the surfaces itself from a G-buffer (albedo + normal)
  // with the sun and sky irradiance of the tables (and the shadow map's
  // visibility when one is given), then attenuates them and adds in-scatter.
  // The colour texture is not read.
  gbuffer,
};

// One view of one frame.
struct FrameInput {
  // Engine textures (GL texture names, owned by the engine), all
  // width x height, level 0 read.
  std::uint32_t colour = 0;  // RGB(A) float/half-float, linear (lit_colour mode)
  std::uint32_t depth = 0;   // GL_DEPTH_COMPONENT* / GL_DEPTH*_STENCIL8 or GL_R32F holding window depth
  std::uint32_t albedo = 0;  // gbuffer mode: linear reflectance in RGB, in [0, 1]
  std::uint32_t normal = 0;  // gbuffer mode: unit normal in the engine's world frame in RGB (float texture, not packed)
  int width = 0;
  int height = 0;
  SurfaceMode surfaces = SurfaceMode::lit_colour;
  DepthEncoding depth_encoding = DepthEncoding::standard;
  double log_depth_far = 0.0;  // logarithmic only: F, engine units (> 0)

  glm::dmat4 view{1.0};        // world -> view, engine units (rigid: rotation + translation)
  glm::dmat4 projection{1.0};  // view -> clip, OpenGL conventions (camera looks along -z)

  glm::dvec3 sun_direction{0.0, 0.0, 1.0};  // world frame, towards the sun (normalised internally)
  // Illuminance of the sun at the top of the atmosphere, perpendicular to it,
  // in lux; 0 keeps the atmosphere's own (its solar spectrum, e.g. about
  // 128 klx for Earth). Scales all light of the pass.
  double sun_illuminance_lux = 0.0;
  // cd/m² per unit of the engine's colour (and of the output).
  double nits_per_unit = 1.0;
  bool sun_disc = true;  // draw the sun's disc in the sky (limb-darkened, attenuated)
  // Draw the star field behind the atmosphere (src/physics/stars.glsl: a
  // procedural sky with the real sky's counts per magnitude, attenuated by
  // the atmosphere and drowned by its light by day; each star's image about
  // a pixel wide at the image centre). Off by default: turn it on at night,
  // or always (by day it is invisible but costs a little per sky pixel).
  bool stars = false;
  // With a star catalogue (AtmospherePass::set_star_catalogue), the
  // rotation from its frame to the world's axes (e.g. the Earth's rotation
  // by the sidereal time of the frame's instant); a rotation (orthonormal,
  // determinant 1), else render() throws.
  glm::dmat3 world_from_star_catalogue{1.0};
  // Moons that eclipse the sun (include/atmos/eclipse.hpp), at most
  // kMaxMoons: spheres in PLANET-CENTRED METRES in the world's axes — the
  // frame of sun_direction (the world's axes are the planet's: PlanetFrame
  // has no rotation), not engine units. A moon at engine-world position p
  // is at (p - PlanetFrame::centre) / units_per_metre; atmos::moon_in_sky
  // places one in the sky of a planet-centred observer. Every point the
  // pass lights gets the part of the limb-darkened sun they leave visible
  // from there: the sky and the planet's sphere (sky-view table over the
  // full azimuth, or per ray from space; a moon in front hides the sun disc
  // and what else lies behind it — corona, stars — and shows its lit side),
  // the aerial perspective (single scattering node by node; multiple
  // scattering by the documented approximation,
  // diffuse_light_visible_fraction) and, in SurfaceMode::gbuffer, the
  // surfaces' sun and sky irradiance. Lit-colour surfaces are the engine's
  // to dim (docs/plugin.md, Eclipses); light shafts keep their uneclipsed
  // weights along the ray. Empty, or no moon near enough to the sun to hide
  // any of it from the atmosphere (physics::moons_may_eclipse): no eclipse,
  // no moon drawn (the engine draws its moons as objects) and no cost. Invalid moons
  // (validate_moons: too many, non-finite, radius <= 0, reaching into the
  // atmosphere) make render() throw, nothing drawn.
  std::vector<Moon> moons;

  // Terrain shadows and light shafts (optional): a depth texture rendered
  // from the sun with an orthographic projection, and the matrix from the
  // engine's world to its clip space (light projection x light view;
  // standard depth encoding, [-1, 1] clip cube). Points outside the cube are
  // lit. 0: no shadows.
  std::uint32_t shadow_map = 0;
  glm::dmat4 shadow_matrix{1.0};
  int shadow_steps = 24;  // samples of the shadow map along each view ray, 1..256
  // Depth bias of the shadow test, metres along the sun's direction (keeps
  // lit surfaces from shadowing themselves); 0: 1.5 texels of the map's
  // footprint.
  double shadow_bias_m = 0.0;

  // Measure the passes' GPU time (last_timings()). Waits for the GPU at the
  // end of render(): for benchmarks and tools, not for every frame of an
  // engine.
  bool timed = false;

  // Where to write the composited image: an RGBA16F or RGBA32F texture of
  // width x height owned by the engine (not `colour`); 0: a texture of the
  // pass (RGBA32F, valid until the next render() or the pass's destruction).
  std::uint32_t output = 0;
};

// GPU time of the last render() with FrameInput::timed, in milliseconds
// (timer queries; wall-clock up to glFinish on software rasterisers, see
// Renderer::last_frame_ms); zero for untimed frames.
struct PassTimings {
  double sky_view_ms = 0.0;   // the per-frame sky-view table (cameras in the atmosphere)
  double volume_ms = 0.0;     // the per-frame aerial-perspective volume (cameras low in the atmosphere or above it)
  double composite_ms = 0.0;  // the full-screen pass: sky, surfaces, aerial perspective, shafts
  double total_ms() const { return sky_view_ms + volume_ms + composite_ms; }
};

// Which programs an AtmospherePass compiles before its constructor returns.
// Drivers compile much of a program's code at its first draw (llvmpipe's
// JIT in particular, for each draw state), so that the default draws a 3x3
// frame with each, with the engine textures' formats of docs/plugin.md:
// the engine's first frames then measure frames, not compilation.
enum class PassPrograms {
  // Those of a camera in the atmosphere and of one above it, by day, the
  // engine's colour lit (SurfaceMode::lit_colour), without shadows or stars.
  common,
  // None: each is compiled at its first use in render(), or beforehand by
  // link_programs() (on other threads too).
  none,
};

// The views whose programs AtmospherePass::link_programs() prepares.
enum class ProgramScope {
  view,    // the input's view alone
  flight,  // the input's view and the same view from the ground to beyond the atmosphere over its point
};

class AtmospherePass {
 public:
  // Uploads the tables and compiles the shaders (`programs`) in the CURRENT
  // OpenGL context (4.5 core). Throws atmos::Error on mismatched tables, a
  // missing or too old context, compile errors, or an invalid frame.
  AtmospherePass(const Atmosphere& atmosphere, const Tables& tables, const PlanetFrame& frame,
                 PassPrograms programs = PassPrograms::common);
  // The instant approximate mode (Hillaire 2020; docs/instant.md): the same
  // pass from InstantTables (compute_instant_tables: 0.2 s for three
  // wavelengths on 2 cores),
  // without any 4D table. Each frame integrates its sky-view table and
  // aerial-perspective volume along the view rays through the
  // multiple-scattering table (for cameras in the atmosphere; from above it
  // every pixel's ray is integrated), then composites as the exact mode
  // does. A few per cent off the exact mode by day (docs/instant.md gives
  // the measured error). glsl_library() integrates along each call's ray
  // in this mode (see there). Not in this mode: eclipses (render() throws
  // with moons that hide part of the sun) and set_ground_albedo() (no
  // ground response: compute the instant tables of an atmosphere with the
  // new albedo).
  AtmospherePass(const Atmosphere& atmosphere, const InstantTables& tables, const PlanetFrame& frame,
                 PassPrograms programs = PassPrograms::common);
  ~AtmospherePass();
  AtmospherePass(const AtmospherePass&) = delete;
  AtmospherePass& operator=(const AtmospherePass&) = delete;

  // Composites one view. Returns the texture written (input.output, or the
  // pass's own). Throws atmos::Error, with nothing drawn, on invalid input:
  // missing or mismatched textures, non-finite or singular matrices, a
  // degenerate projection, a zero sun direction, a non-affine shadow
  // matrix, invalid moons. A camera inside the planet is moved up to its
  // surface (documented clamping, as everywhere in atmos).
  std::uint32_t render(const FrameInput& input);

  // Links the programs that render(input) would draw with and that are not
  // linked yet: the sky-view table's, the volume's and the composite's
  // variants of that camera, sun, moons, shadows, stars and surface mode.
  // Each new program is drawn once in the CURRENT context over 3x3 pixels of
  // scratch textures like the input's (where its textures are 0: those of
  // docs/plugin.md at the input's size): drivers that compile machine code
  // at a program's first draw (Mesa's llvmpipe) compile it here, for the
  // formats and sizes it samples, and with a shader cache (Mesa's, on by
  // default) reuse it in the engine's context. So pass the engine's
  // textures, or textures of their formats and size.
  // The input's textures are not read; its matrices, size and sun are
  // checked as render() checks them. With ProgramScope::flight, also the
  // programs of the same view from the other altitudes of a flight over the
  // camera's point, from the ground to beyond the atmosphere, nearest
  // first. It may run on several threads at once, each with its own current
  // context that shares objects with the pass's (a GL share group: a shared
  // context of the engine's window), and while the engine's thread calls
  // render(): each program is linked by one of them, render() waits for one
  // being linked elsewhere instead of linking it twice. With `stop`, it
  // returns before the next program once *stop is true (those linked are
  // kept). Throws atmos::Error as render() does.
  void link_programs(const FrameInput& input, ProgramScope scope = ProgramScope::view,
                     const std::atomic<bool>* stop = nullptr);
  // Whether every program render(input) would draw with is linked (then
  // render() links none; the driver may still compile machine code at the
  // first draw). The input's textures are not read. Throws atmos::Error as
  // link_programs() does.
  bool programs_linked(const FrameInput& input) const;

  const PassTimings& last_timings() const;

  // GLSL for engines that shade in their own shaders (see docs/plugin.md):
  // declarations of the atmosphere's textures on units
  // first_unit..first_unit+4 and the functions
  //   vec3 atmos_sky_radiance(vec3 camera, vec3 view_ray, vec3 sun, out vec3 transmittance);
  //   vec3 atmos_radiance_to_point(vec3 camera, vec3 offset, vec3 sun, out vec3 transmittance);
  //   vec3 atmos_sun_and_sky_irradiance(vec3 point, vec3 normal, vec3 sun, out vec3 sky_irradiance);
  //   vec3 atmos_transmittance_to_sun(vec3 point, vec3 sun);
  // with positions in metres relative to the planet centre (`offset`: from
  // the camera to the point, which keeps float precision near the camera),
  // directions as unit vectors in the planet's axes, radiance in cd/m²
  // linear sRGB, irradiance in lux-scaled linear sRGB (cd/m² x sr); the sun
  // at the atmosphere's own illuminance. Paste it after "#version 450 core".
  // A pass of the instant mode gives the same functions: the irradiance and
  // the transmittance from its tables as in the exact mode, the sky and the
  // aerial perspective integrated along the ray at each call (24 steps
  // through its multiple-scattering table: far costlier per call than the
  // exact mode's lookups), its textures on the same units.
  // The atmosphere's values (radii, coefficients, solar irradiance, ...)
  // are read from a std140 uniform block that the library declares at
  // uniform-buffer binding `parameters_binding` (block AtmosParameters), so
  // that the text depends only on the atmosphere's structure (its
  // constituents, profile kinds, table sizes and wavelength count): a pass
  // of another atmosphere with the same structure returns the same text,
  // and programs linked with it serve that pass too. Throws atmos::Error
  // for units or a binding outside the context's.
  std::string glsl_library(int first_unit, int parameters_binding = 0) const;
  // Binds the textures and the parameter block glsl_library() declares
  // (the same first_unit and parameters_binding).
  void bind_textures(int first_unit, int parameters_binding = 0) const;

  // The albedo of the ground below the air, per channel of the tables
  // (linear sRGB in spectral mode, the three working wavelengths' in
  // three-wavelength mode), dimensionless, in [0, 1]. The light the air
  // scatters and the sky light on the ground then follow it
  // (tables_for_ground_albedo): give the regional mean albedo of the ground
  // around the camera (Globe::regional_albedo) instead of the atmosphere's
  // constant. The tables must hold a ground response
  // (PrecomputeOptions::ground_albedo_response). A change of more than
  // 0.001 in a channel re-blends the three ground-dependent tables on the
  // CPU and uploads them (atmos bench: plugin.ground_albedo); a smaller one
  // keeps them. The Lambertian sphere the pass draws where nothing was drawn
  // keeps the atmosphere's albedo. Throws atmos::Error, changing nothing, on
  // tables without a ground response or an albedo outside [0, 1].
  void set_ground_albedo(const glm::dvec3& albedo);
  // The ground albedo of the current tables (the atmosphere's until set).
  glm::dvec3 ground_albedo() const;

  // The stars of a catalogue instead of the procedural field, drawn when
  // FrameInput::stars is on, turned into the world's axes by
  // FrameInput::world_from_star_catalogue; empty (the default): the
  // procedural field. Throws atmos::Error as validate_stars does (the
  // previous catalogue is kept).
  void set_star_catalogue(const std::vector<Star>& stars);
  const std::vector<Star>& star_catalogue() const;

  // Whether the pass was made from InstantTables (the instant approximate mode).
  bool instant() const;

  const PlanetFrame& frame() const;
  // The radius of the atmosphere's ground (its bottom_radius), m: the
  // lowest point its tables reach.
  double bottom_radius_m() const;
  // The illuminance of the atmosphere's own sun at the top of the
  // atmosphere (lux): what FrameInput::sun_illuminance_lux = 0 means, and
  // the sun of glsl_library()'s functions (scale their light by
  // your_lux / sun_illuminance_lux() to match a frame's).
  double sun_illuminance_lux() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace atmos
