// atmos view: stereo and head-mounted displays. A view provider says, each
// frame, where each eye is and what it sees (its pose and four field-of-view
// angles, as OpenXR's XrView gives them); the viewer draws each eye through
// exactly those (Scene::render_eyes: one tile selection for both eyes, the
// sky, the sun and the aerial perspective along each eye's own inverse
// projection) and hands the images back. Two providers: OpenXR's
// (openxr/openxr_provider.cpp, built with ATMOS_OPENXR), and a mock with
// fixed eyes that tests and `atmos view --xr-mock` use.
//
// The tracking space is OpenXR's: metres, x right, y up, z backwards (the
// head looks along -z at rest). It is anchored at the flight's camera:
// the tracking origin at the camera's position, its -z along the camera's
// forward, its y along the camera's up.
#pragma once

#include <epoxy/gl.h>

#include <glm/gtc/quaternion.hpp>
#include <glm/vec3.hpp>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "atmos/image.hpp"
#include "atmos/post.hpp"
#include "atmos/stereo.hpp"
#include "flight.hpp"
#include "scene.hpp"

namespace atmos_view {

// One eye of a frame, in the tracking space (XrView: XrPosef and XrFovf).
struct EyeView {
  glm::dvec3 position_m{0.0};
  glm::dquat orientation{1.0, 0.0, 0.0, 0.0};  // tracking axes from the eye's (w, x, y, z), unit
  atmos::FieldOfView fov;
};

struct HeadsetFrame {
  bool render = true;  // false: the runtime asks for no images this frame
  std::array<EyeView, 2> eyes;
};

class ViewProvider {
 public:
  virtual ~ViewProvider() = default;
  // Each eye's image size, pixels.
  virtual int eye_width() const = 0;
  virtual int eye_height() const = 0;
  // Waits for the next frame and returns its eyes; none when the session
  // has ended (the headset's user quit, the mock's frames are done).
  virtual std::optional<HeadsetFrame> begin_frame() = 0;
  // An eye's images of the frame begun, eye 0 (left) then 1: the linear
  // HDR image (RGBA32F, cd/m² divided by Scene::kNitsPerUnit) and the
  // display image (sRGB-encoded RGBA8), eye_width x eye_height, valid
  // during the call. Not called when the frame's `render` is false.
  virtual void submit_eye(int eye, GLuint hdr, GLuint display) = 0;
  // Ends the frame begun (presents it).
  virtual void end_frame() = 0;
};

// The planet-frame eye of a tracking-space eye, with the tracking space
// anchored at `head` (above).
atmos::Eye eye_in_planet(const CameraPose& head, const EyeView& eye);

// Draws a provider's frames from a scene: each eye through Scene::render_eyes,
// then the post-processing into that eye's display image, both handed to
// the provider. The frame's sun, moons and stars are `frame`'s; its pose
// anchors the tracking space.
class HeadsetRenderer {
 public:
  HeadsetRenderer() = default;
  ~HeadsetRenderer();
  HeadsetRenderer(const HeadsetRenderer&) = delete;
  HeadsetRenderer& operator=(const HeadsetRenderer&) = delete;

  // One frame: false when the provider's session has ended.
  bool frame(ViewProvider& provider, Scene& scene, atmos::PostProcess& post, const SceneFrame& frame,
             const atmos::PostSettings& settings, double dt_s);
  // The eyes of the last frame drawn, planet frame.
  const std::array<atmos::Eye, 2>& last_eyes() const { return eyes_; }

 private:
  std::array<GLuint, 2> display_{};
  int width_ = 0, height_ = 0;
  std::array<atmos::Eye, 2> eyes_;
};

// Fixed eyes, the same every frame, for a number of frames; keeps each
// eye's images of the last frame. The JSON form (docs/viewer.md):
//   {"width": 96, "height": 64, "frames": 2,
//    "eyes": [{"position_m": [-0.032, 0, 0], "orientation_wxyz": [1, 0, 0, 0],
//              "fov_deg": {"left": -45, "right": 40, "up": 35, "down": -40}}, {...}]}
class MockViewProvider : public ViewProvider {
 public:
  MockViewProvider(const std::array<EyeView, 2>& eyes, int width, int height, int frames);
  // Throws atmos::Error naming the file and the first bad field.
  static MockViewProvider read(const std::string& path);

  int eye_width() const override { return width_; }
  int eye_height() const override { return height_; }
  std::optional<HeadsetFrame> begin_frame() override;
  void submit_eye(int eye, GLuint hdr, GLuint display) override;
  void end_frame() override;

  int frames_ended() const { return ended_; }
  // The last frame's images: HDR in cd/m², rows top-down; display sRGB.
  const atmos::Image& hdr(int eye) const { return hdr_[size_t(eye)]; }
  const atmos::DisplayImage& display(int eye) const { return display_[size_t(eye)]; }

 private:
  std::array<EyeView, 2> eyes_;
  int width_, height_, frames_;
  int begun_ = 0, ended_ = 0;
  std::array<atmos::Image, 2> hdr_;
  std::array<atmos::DisplayImage, 2> display_;
};

// The OpenXR provider (openxr/openxr_provider.cpp): an instance with
// XR_KHR_opengl_enable and the headset's system, created now, so that no
// runtime, no headset or no OpenGL support fails before any window opens
// (atmos::Error naming OpenXR's result); start() then creates the session
// with the current GLX context. Throws atmos::Error when atmos was built
// without OpenXR.
class OpenXrProvider : public ViewProvider {
 public:
  virtual void start() = 0;  // with the viewer's OpenGL context current
};
std::unique_ptr<OpenXrProvider> make_openxr_provider();
bool built_with_openxr();

// Two eyes' HDR images into one for a stereo display: side by side (left
// eye on the left, twice the width) or a red-cyan anaglyph (red from the
// left eye, green and blue from the right), on the GPU (a small compute
// program), as atmos::side_by_side and atmos::anaglyph do on the CPU.
class StereoComposer {
 public:
  enum class Layout { side_by_side, anaglyph };
  StereoComposer();
  ~StereoComposer();
  StereoComposer(const StereoComposer&) = delete;
  StereoComposer& operator=(const StereoComposer&) = delete;
  // Each eye width x height; returns an RGBA32F texture of the layout's
  // size, valid until the next call.
  GLuint compose(Layout layout, GLuint left, GLuint right, int width, int height);

 private:
  GLuint program_ = 0, output_ = 0;
  int width_ = 0, height_ = 0;
};

}  // namespace atmos_view
