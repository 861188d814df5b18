// The planet layer's OpenGL programs (the globe's terrain and the sea): its
// embedded GLSL sources and their compilation, with errors as atmos::Error.
// The planet layer draws through the public API and OpenGL only, so it keeps
// this small helper of its own rather than the GPU layer's private one.
#pragma once

#include <epoxy/gl.h>
#include <glm/mat4x4.hpp>

#include <string>

namespace atmos::planet {

// The text of an embedded GLSL file (src/data); `who` names the caller in the
// error ("globe", "ocean") when the file is not embedded.
const char* shader_text(const char* who, const char* path);

// A program of a vertex and a fragment shader; throws atmos::Error with the
// driver's log ("<who>: the fragment shader does not compile: ...").
GLuint link_program(const char* who, const std::string& vertex, const std::string& fragment);

// Whether every element of `m` is finite.
bool finite(const glm::dmat4& m);

}  // namespace atmos::planet
