// Small OpenGL 4.5 helpers of the example engine: owning handles for GL
// objects, shader compilation with readable errors, and pass timing.
//
// Direct state access (glCreate*, glNamed*, glTexture*) throughout: objects
// are created and configured without binding them, so no helper depends on
// or disturbs the current bindings.
#pragma once

#include <epoxy/gl.h>

#include <chrono>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace engine::gl {

// A failure of the engine's OpenGL code (shader compilation, incomplete
// framebuffer): reported on one line, exit code 1.
struct Error : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Owns one OpenGL object name; deletes it with the function it was given.
// Move-only, like std::unique_ptr.
class Handle {
 public:
  using Deleter = void (*)(GLuint);

  Handle() = default;
  Handle(GLuint name, Deleter deleter) noexcept : name_(name), deleter_(deleter) {}
  Handle(Handle&& other) noexcept : name_(std::exchange(other.name_, 0)), deleter_(other.deleter_) {}
  Handle& operator=(Handle&& other) noexcept {
    if (this != &other) {
      reset();
      name_ = std::exchange(other.name_, 0);
      deleter_ = other.deleter_;
    }
    return *this;
  }
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() { reset(); }

  GLuint get() const { return name_; }

 private:
  void reset() noexcept {
    if (name_ != 0 && deleter_ != nullptr) deleter_(name_);
    name_ = 0;
  }

  GLuint name_ = 0;
  Deleter deleter_ = nullptr;
};

// A 2D texture with immutable storage (one level), nearest filtering and
// clamping: render targets read texel by texel.
Handle create_texture_2d(GLenum internal_format, int width, int height);
// An immutable buffer holding `bytes`.
Handle create_buffer(std::span<const std::byte> bytes);
Handle create_framebuffer();
Handle create_vertex_array();
Handle create_sampler();

// Throws gl::Error naming `label` unless the framebuffer is complete.
void check_framebuffer(GLuint framebuffer, std::string_view label);

// One stage of a program: its type and its complete source text.
struct ShaderStage {
  GLenum type;
  std::string source;
};

// Compiles and links a program; throws gl::Error with `label`, the stage and
// the first lines of the info log on failure.
Handle create_program(std::string_view label, std::span<const ShaderStage> stages);

// Location of a uniform; -1 (ignored by glProgramUniform*) when the
// compiler removed an unused uniform.
inline GLint uniform(GLuint program, const char* name) { return glGetUniformLocation(program, name); }

// Milliseconds that `work` takes on the GPU, measured as the wall-clock time
// from an idle GPU to glFinish. Engines normally use GL_TIME_ELAPSED queries,
// but on Mesa's llvmpipe (the GPU of this example's CI) those only time the
// submission of the deferred rasterisation; glFinish is exact there and
// costs nothing that matters in a one-frame program.
template <typename Work>
double timed_ms(Work&& work) {
  glFinish();
  const auto start = std::chrono::steady_clock::now();
  std::forward<Work>(work)();
  glFinish();
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace engine::gl
