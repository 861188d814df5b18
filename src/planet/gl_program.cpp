#include "planet/gl_program.hpp"

#include <glm/matrix.hpp>

#include <algorithm>
#include <cmath>
#include <string>

#include "atmos/atmosphere.hpp"
#include "data/embedded_files.hpp"
#include "data/glsl_prune.hpp"

namespace atmos::planet {

namespace {

GLuint compile(const char* who, GLenum stage, const std::string& source, const char* name) {
  const GLuint shader = glCreateShader(stage);
  // Only the functions the shader uses (of the pass's whole library).
  const std::string pruned = data::prune_unreferenced_functions(source);
  const char* text = pruned.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error(std::string(who) + ": the " + name + " shader does not compile: " + log.c_str());
  }
  return shader;
}

}  // namespace

const char* shader_text(const char* who, const char* path) {
  const char* text = data::embedded_file(path);
  if (text == nullptr) throw Error(std::string(who) + ": shader source " + path + " is not embedded");
  return text;
}

GLuint link_program(const char* who, const std::string& vertex, const std::string& fragment) {
  const GLuint vs = compile(who, GL_VERTEX_SHADER, vertex, "vertex");
  GLuint fs = 0;
  try {
    fs = compile(who, GL_FRAGMENT_SHADER, fragment, "fragment");
  } catch (...) {
    glDeleteShader(vs);
    throw;
  }
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error(std::string(who) + ": the shaders do not link: " + log.c_str());
  }
  return program;
}

bool finite(const glm::dmat4& m) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (!std::isfinite(m[c][r])) return false;
  return true;
}

void check_view_matrices(const char* who, const GlobeView& view) {
  const std::string prefix = std::string(who) + " view: ";
  if (view.width < 1 || view.height < 1) throw Error(prefix + "empty viewport");
  if (!finite(view.view) || !finite(view.projection)) throw Error(prefix + "non-finite view or projection matrix");
  const double determinant = glm::determinant(view.view);
  if (!std::isfinite(determinant) || std::abs(determinant) < 1e-12) throw Error(prefix + "singular view matrix");
  if (!(std::abs(view.projection[1][1]) > 0.0)) throw Error(prefix + "degenerate projection");
}

}  // namespace atmos::planet
