#include "gl.hpp"

#include <algorithm>
#include <sstream>
#include <vector>

namespace engine::gl {

Handle create_texture_2d(GLenum internal_format, int width, int height) {
  GLuint name = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &name);
  glTextureStorage2D(name, 1, internal_format, width, height);
  glTextureParameteri(name, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(name, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTextureParameteri(name, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(name, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return {name, [](GLuint n) { glDeleteTextures(1, &n); }};
}

Handle create_buffer(std::span<const std::byte> bytes) {
  GLuint name = 0;
  glCreateBuffers(1, &name);
  glNamedBufferStorage(name, static_cast<GLsizeiptr>(bytes.size()), bytes.data(), 0);
  return {name, [](GLuint n) { glDeleteBuffers(1, &n); }};
}

Handle create_framebuffer() {
  GLuint name = 0;
  glCreateFramebuffers(1, &name);
  return {name, [](GLuint n) { glDeleteFramebuffers(1, &n); }};
}

Handle create_vertex_array() {
  GLuint name = 0;
  glCreateVertexArrays(1, &name);
  return {name, [](GLuint n) { glDeleteVertexArrays(1, &n); }};
}

Handle create_sampler() {
  GLuint name = 0;
  glCreateSamplers(1, &name);
  return {name, [](GLuint n) { glDeleteSamplers(1, &n); }};
}

void check_framebuffer(GLuint framebuffer, std::string_view label) {
  const GLenum status = glCheckNamedFramebufferStatus(framebuffer, GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    std::ostringstream message;
    message << label << " framebuffer is incomplete (status 0x" << std::hex << status << ")";
    throw Error(message.str());
  }
}

namespace {

// The info log's first lines (a broken shader can produce hundreds), on one
// line: errors are reported as a single line.
std::string first_lines(std::string log, int count) {
  std::string out;
  std::istringstream lines(log);
  std::string line;
  for (int i = 0; i < count && std::getline(lines, line); ++i) out += (i > 0 ? " | " : "") + line;
  return out;
}

const char* stage_name(GLenum type) {
  switch (type) {
    case GL_VERTEX_SHADER: return "vertex";
    case GL_FRAGMENT_SHADER: return "fragment";
    default: return "shader";
  }
}

}  // namespace

Handle create_program(std::string_view label, std::span<const ShaderStage> stages) {
  Handle program(glCreateProgram(), [](GLuint n) { glDeleteProgram(n); });
  std::vector<Handle> shaders;
  for (const ShaderStage& stage : stages) {
    Handle shader(glCreateShader(stage.type), [](GLuint n) { glDeleteShader(n); });
    const char* text = stage.source.c_str();
    glShaderSource(shader.get(), 1, &text, nullptr);
    glCompileShader(shader.get());
    GLint ok = GL_FALSE;
    glGetShaderiv(shader.get(), GL_COMPILE_STATUS, &ok);
    if (ok != GL_TRUE) {
      GLint length = 0;
      glGetShaderiv(shader.get(), GL_INFO_LOG_LENGTH, &length);
      std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
      glGetShaderInfoLog(shader.get(), length, nullptr, log.data());
      throw Error(std::string(label) + ": " + stage_name(stage.type) + " shader: " + first_lines(log, 3));
    }
    glAttachShader(program.get(), shader.get());
    shaders.push_back(std::move(shader));
  }
  glLinkProgram(program.get());
  GLint ok = GL_FALSE;
  glGetProgramiv(program.get(), GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program.get(), GL_INFO_LOG_LENGTH, &length);
    std::string log(static_cast<size_t>(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program.get(), length, nullptr, log.data());
    throw Error(std::string(label) + ": link: " + first_lines(log, 3));
  }
  // The shaders are flagged for deletion when `shaders` goes out of scope;
  // the program keeps what it needs.
  return program;
}

}  // namespace engine::gl
