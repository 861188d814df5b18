// A test program: a full-screen triangle (three vertices from gl_VertexID,
// no vertex array data) and the given fragment shader, compiled and linked
// in the current context. Compile or link errors are test failures (with
// the driver's log); the program is returned all the same (0 only if GL
// gives none).
#pragma once

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <string>

namespace atmos_test {

inline GLuint fullscreen_program(const std::string& fragment) {
  const auto compile = [](GLenum type, const std::string& source) {
    const GLuint shader = glCreateShader(type);
    const char* text = source.c_str();
    glShaderSource(shader, 1, &text, nullptr);
    glCompileShader(shader);
    GLint ok = 0;
    glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
    if (!ok) {
      char log[2048];
      glGetShaderInfoLog(shader, sizeof log, nullptr, log);
      ADD_FAILURE() << log;
    }
    return shader;
  };
  const GLuint vs = compile(GL_VERTEX_SHADER,
                            "#version 450 core\nvoid main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), "
                            "float(gl_VertexID & 2)); gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }\n");
  const GLuint fs = compile(GL_FRAGMENT_SHADER, fragment);
  const GLuint program = glCreateProgram();
  glAttachShader(program, vs);
  glAttachShader(program, fs);
  glLinkProgram(program);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) ADD_FAILURE() << "the test program does not link";
  return program;
}

}  // namespace atmos_test
