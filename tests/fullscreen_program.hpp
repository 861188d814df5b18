// A test program: a full-screen triangle (three vertices from gl_VertexID,
// no vertex array data) and the given fragment shader, compiled and linked
// in the current context. Compile or link errors are test failures (with
// the driver's log); the program is returned all the same (0 only if GL
// gives none).
#pragma once

#include <epoxy/gl.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

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

// Draws `program` (fullscreen_program's) over a new width x height RGBA32F
// target, depth test and blending off, and returns its texels (RGBA, rows
// bottom-up). The caller sets the program's uniforms and binds its textures.
inline std::vector<float> draw_fullscreen(GLuint program, int width, int height) {
  GLuint target = 0, framebuffer = 0, vao = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &target);
  glTextureStorage2D(target, 1, GL_RGBA32F, width, height);
  glCreateFramebuffers(1, &framebuffer);
  glNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, target, 0);
  glCreateVertexArrays(1, &vao);
  glUseProgram(program);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glViewport(0, 0, width, height);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  std::vector<float> texels(size_t(width) * size_t(height) * 4);
  glGetTextureImage(target, 0, GL_RGBA, GL_FLOAT, GLsizei(texels.size() * sizeof(float)), texels.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glBindVertexArray(0);
  glDeleteVertexArrays(1, &vao);
  glDeleteFramebuffers(1, &framebuffer);
  glDeleteTextures(1, &target);
  return texels;
}

}  // namespace atmos_test
