// The planet layer's OpenGL programs (the globe's terrain and the sea): its
// embedded GLSL sources and their compilation, with errors as atmos::Error,
// and the checks of the views they draw.
// The planet layer draws through the public API and OpenGL only, so it keeps
// this small helper of its own rather than the GPU layer's private one.
#pragma once

#include <epoxy/gl.h>
#include <glm/mat4x4.hpp>

#include <string>

#include "atmos/globe.hpp"

namespace atmos::planet {

// The text of an embedded GLSL file (src/data); `who` names the caller in the
// error ("globe", "ocean") when the file is not embedded.
const char* shader_text(const char* who, const char* path);

// A program of a vertex and a fragment shader; throws atmos::Error with the
// driver's log ("<who>: the fragment shader does not compile: ...").
GLuint link_program(const char* who, const std::string& vertex, const std::string& fragment);

// Whether every element of `m` is finite.
bool finite(const glm::dmat4& m);

// Throws atmos::Error ("<who> view: ...") unless `view` has a non-empty
// viewport, finite view and projection matrices, an invertible view matrix
// and a projection that does not collapse the image's vertical axis: the
// checks every draw of the planet layer makes before it changes any state.
void check_view_matrices(const char* who, const GlobeView& view);

}  // namespace atmos::planet
