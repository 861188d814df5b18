// A colour (RGBA32F) and reversed-Z depth (DEPTH_COMPONENT32F) target for
// the globe's GPU tests, with its framebuffer; the context must be current.
#pragma once

#include <epoxy/gl.h>

#include <vector>

namespace atmos_test {

struct GlobeTarget {
  GlobeTarget(const GlobeTarget&) = delete;
  GlobeTarget& operator=(const GlobeTarget&) = delete;
  GLuint colour = 0, depth = 0, framebuffer = 0;
  int width = 0, height = 0;
  GlobeTarget(int w, int h) : width(w), height(h) {
    glCreateTextures(GL_TEXTURE_2D, 1, &colour);
    glTextureStorage2D(colour, 1, GL_RGBA32F, w, h);
    glCreateTextures(GL_TEXTURE_2D, 1, &depth);
    glTextureStorage2D(depth, 1, GL_DEPTH_COMPONENT32F, w, h);
    glCreateFramebuffers(1, &framebuffer);
    glNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, colour, 0);
    glNamedFramebufferTexture(framebuffer, GL_DEPTH_ATTACHMENT, depth, 0);
  }
  ~GlobeTarget() {
    glDeleteFramebuffers(1, &framebuffer);
    glDeleteTextures(1, &colour);
    glDeleteTextures(1, &depth);
  }
  // Clears colour to a sentinel and depth to 0 (reversed-Z: infinitely far).
  void clear() const {
    const float sentinel[4] = {-1.0f, -1.0f, -1.0f, -1.0f};
    const float far_depth = 0.0f;
    glClearNamedFramebufferfv(framebuffer, GL_COLOR, 0, sentinel);
    glClearNamedFramebufferfv(framebuffer, GL_DEPTH, 0, &far_depth);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  }
  std::vector<float> read_depth() const {
    std::vector<float> d(size_t(width * height));
    glGetTextureImage(depth, 0, GL_DEPTH_COMPONENT, GL_FLOAT, GLsizei(d.size() * sizeof(float)), d.data());
    return d;
  }
  std::vector<float> read_colour() const {
    std::vector<float> c(size_t(width * height * 4));
    glGetTextureImage(colour, 0, GL_RGBA, GL_FLOAT, GLsizei(c.size() * sizeof(float)), c.data());
    return c;
  }
};

}  // namespace atmos_test
