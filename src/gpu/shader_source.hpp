// Assembles the renderer's GLSL from the embedded shared sources
// (src/physics/*.glsl, src/gpu/*.glsl; see io/embedded_files.hpp).
#pragma once

#include <string>
#include <vector>

#include "physics/shader_cpp.hpp"

namespace atmos::gpu {

// A GLSL float literal that reads back as exactly `value` ("%.9g", with
// ".0" added where the digits alone would be an integer literal).
// Throws atmos::Error for NaN or infinity, which GLSL cannot spell.
std::string glsl_float(float value);

// "const AtmosphereParams ATMOSPHERE = AtmosphereParams(...);": the C++
// parameters as a GLSL constant, so that the shader compiler folds them.
std::string atmosphere_params_glsl(const physics::AtmosphereParams& params);

// "const SpectralSets SPECTRAL = ...;" for the wavelength triples.
std::string spectral_sets_glsl(const physics::SpectralSets& sets);

// The vertex shader: one triangle covering the viewport, from gl_VertexID.
std::string fullscreen_vertex_shader_source();

// A shader assembled from several files, and where each one starts, so that
// compiler messages can name the file and line of the error.
struct AssembledSource {
  struct Part {
    int first_line;    // 1-based line of `text` where the part starts
    std::string name;  // e.g. "functions.glsl"
  };
  std::string text;
  std::vector<Part> parts;

  void append(const std::string& name, const std::string& part_text);
  // "functions.glsl:57" for the line of `text` that is line 57 of functions.glsl.
  std::string locate(int line) const;
};

// The fragment shader: "#version 450 core", the GLSL meaning of the subset
// macros, definitions.glsl, ATMOSPHERE, functions.glsl, camera.glsl and
// render.frag.glsl; `sky_view_camera`: the variant for cameras in the
// atmosphere, which reads the sky-view table (see sky_radiance).
AssembledSource render_fragment_shader_source(const physics::AtmosphereParams& params,
                                              const physics::SpectralSets& spectral, bool sky_view_camera);

// The fragment shader of the sky-view pass: the same shared part, then
// sky_view.frag.glsl.
AssembledSource sky_view_fragment_shader_source(const physics::AtmosphereParams& params,
                                                const physics::SpectralSets& spectral);

}  // namespace atmos::gpu
