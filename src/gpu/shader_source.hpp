// Assembles the renderer's GLSL from the embedded shared sources
// (src/physics/*.glsl, src/gpu/*.glsl; see data/embedded_files.hpp).
#pragma once

#include <string>
#include <vector>

#include "physics/shader_cpp.hpp"

namespace atmos::gpu {

// A GLSL float literal that reads back as exactly `value` ("%.9g", with
// ".0" added where the digits alone would be an integer literal).
// Throws atmos::Error for NaN or infinity, which GLSL cannot spell.
std::string glsl_float(float value);

// The uniform binding of the parameter block in atmos's own programs.
constexpr int kParametersBinding = 0;
// The block's GLSL names: "uniform AtmosParameters { vec4 atmos_parameter_values[N]; }".
inline constexpr const char* kParameterBlock = "AtmosParameters";
inline constexpr const char* kParameterArray = "atmos_parameter_values";

// The atmosphere as the shaders see it, split into its structure and its
// values: `glsl` declares the std140 uniform block at `binding` and defines
// ATMOSPHERE and SPECTRAL (and atmos_radiance_to_srgb()) as the
// AtmosphereParams and SpectralSets whose integer fields (counts, kinds,
// knot counts, table sizes, tiles) are literals, as are the floats whose
// zero the shaders test for, coefficients that are zero at all three
// wavelengths, the three-wavelength mode's identity conversion to the
// channels and the fields never read, while every other float reads the
// block; `values` is the block's content (the driver's
// std140 layout of a vec4 array: 16 bytes per element, value i at byte 4 i).
// The text therefore depends on the structure alone: atmospheres that
// differ only in values share programs. Throws atmos::Error for a value
// that is NaN or infinite.
struct ParameterBlock {
  std::string glsl;
  std::vector<float> values;
};
ParameterBlock parameter_block(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                               const physics::mat3& radiance_to_srgb, int binding = kParametersBinding);

// The vertex shader: one triangle covering the viewport, from gl_VertexID.
std::string fullscreen_vertex_shader_source();

// A shader assembled from several files, and where each one starts, so that
// compiler messages can name the file and line of the error.
struct AssembledSource {
  struct Part {
    int first_line;    // 1-based line of `text` where the part starts
    std::string name;  // e.g. "table_lookups.glsl"
  };
  std::string text;
  std::vector<Part> parts;

  void append(const std::string& name, const std::string& part_text);
  // "table_lookups.glsl:57" for the line of `text` that is line 57 of table_lookups.glsl.
  std::string locate(int line) const;
};

// The fragment shader: "#version 450 core", the GLSL meaning of the subset
// macros, definitions.glsl, ATMOSPHERE, the physics up to
// radiance_to_camera.glsl, camera.glsl and render.frag.glsl; `sky_view_camera`: the variant for cameras in the
// atmosphere, which reads the sky-view table (see sky_radiance); `eclipse`:
// with the moons' uniforms (table_bindings.glsl).
AssembledSource render_fragment_shader_source(const physics::AtmosphereParams& params,
                                              const physics::SpectralSets& spectral, bool sky_view_camera,
                                              bool eclipse);

// The fragment shader of the sky-view pass: the definitions and the physics
// up to sky_view_table.glsl, then sky_view.frag.glsl; `low_sun`: with the
// twilight integration (sky_view_table.glsl: sun_may_be_low_on_view_rays); `eclipse`: with the moons'
// uniforms (table_bindings.glsl), which needs `low_sun`.
AssembledSource sky_view_fragment_shader_source(const physics::AtmosphereParams& params,
                                                const physics::SpectralSets& spectral, bool low_sun, bool eclipse);

// The program variants of the engine plugin's pass: what composite.glsl
// treats as constants (see PassFrame).
struct PassVariant {
  // Which pixels the program draws (atmosphere_pass.frag.glsl: PIXELS_*):
  // it marks a class of pixels in the stencil buffer (the sky, those that
  // need the low-sun integration, the sky beside the atmosphere, the
  // surfaces the space volume covers), or shades
  // the sky's, the surfaces' or those of the space beside the atmosphere.
  // classify_all sorts every pixel into all the frame's classes at once,
  // writing their bits as its stencil value (GL_ARB_shader_stencil_export):
  // the low-sun class with low_sun, the space beside the atmosphere without
  // sky_view_camera, the space volume's surfaces with space_volume.
  enum class Pixels {
    classify = 0,
    sky = 1,
    surface = 2,
    space = 3,
    classify_low_sun = 4,
    classify_space = 5,
    classify_space_volume = 6,
    classify_all = 7,
    // The instant mode's pixels of a camera above the atmosphere, every one
    // (instant_composite.glsl: instant_space_pixel).
    instant_space = 8
  };
  Pixels pixels = Pixels::sky;
  bool sky_view_camera = true;  // camera in the atmosphere: reads the sky-view table
  bool low_sun = false;         // integrates single scattering where the sun is low
  bool shadows = false;         // a shadow map: light shafts
  bool gbuffer = false;         // lights surfaces from albedo + normal
  bool volume = false;          // surfaces read the aerial-perspective volume
  bool blend = false;           // ... mixed with the exact evaluation (cameras in the blend band)
  bool stars = false;           // the star field behind the sky
  bool eclipse = false;         // the frame has moons (needs low_sun): the uniforms of uniform_moons()
  bool space_volume = false;    // surfaces read the volume of cameras above the atmosphere
  bool night = false;           // surfaces in the planet's shadow: no single scattering (PassFrame::night)
  static constexpr int kCount = 9 * 1024;
  int index() const {
    return int(pixels) * 1024 + ((sky_view_camera ? 1 : 0) | (low_sun ? 2 : 0) | (shadows ? 4 : 0) |
                                 (gbuffer ? 8 : 0) | (volume ? 16 : 0) | (blend ? 32 : 0) | (stars ? 64 : 0) |
                                 (eclipse ? 128 : 0) | (space_volume ? 256 : 0) | (night ? 512 : 0));
  }
};

// The fragment shader of the engine plugin's pass (AtmospherePass): the
// definitions, the physics up to radiance_to_camera.glsl and
// aerial_perspective.glsl, composite.glsl and atmosphere_pass.frag.glsl.
AssembledSource atmosphere_pass_fragment_shader_source(const physics::AtmosphereParams& params,
                                                      const physics::SpectralSets& spectral,
                                                      const PassVariant& variant);

// The vertex shader of the engine plugin's pass: pixel_ray.glsl and
// atmosphere_pass.vert.glsl (each pixel's PixelRay, interpolated).
AssembledSource atmosphere_pass_vertex_shader_source();

// The compute shader of the plugin's aerial-perspective volume: the same
// physics, composite.glsl and aerial_perspective.comp.glsl; `low_sun`: the
// transmittance to the sun over the disc with the planet's shadow;
// `eclipse`: with the moons' uniforms (table_bindings.glsl), which needs
// `low_sun`; `space`: composite.glsl's space volume over a list of columns
// instead (`split`: single Rayleigh apart from the multiple scattering).
AssembledSource aerial_perspective_compute_shader_source(const physics::AtmosphereParams& params,
                                                        const physics::SpectralSets& spectral, bool low_sun,
                                                        bool eclipse, bool space, bool split);

// The instant mode's sky-view pass (instant_sky_view.frag.glsl: the view
// rays marched through the multiple-scattering table; `low_sun` as
// sky_view_fragment_shader_source's) and aerial-perspective volume
// (instant_aerial_perspective.comp.glsl; `low_sun`: the transmittance to the
// sun over the disc with the planet's shadow).
AssembledSource instant_sky_view_fragment_shader_source(const physics::AtmosphereParams& params,
                                                        const physics::SpectralSets& spectral, bool low_sun);
AssembledSource instant_aerial_perspective_compute_shader_source(const physics::AtmosphereParams& params,
                                                                const physics::SpectralSets& spectral,
                                                                bool low_sun);

// The GLSL library for engines' own shaders (AtmospherePass::glsl_library):
// the definitions, the parameter block at `parameters_binding` and the
// physics up to view_ray_scattering.glsl and aerial_perspective.glsl (and
// the instant mode's march for a pass of that mode, `instant`) without
// "#version", then engine_library.glsl with its textures on units
// first_unit .. first_unit + 4.
std::string engine_library_source(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                  int first_unit, int parameters_binding, bool instant);

}  // namespace atmos::gpu
