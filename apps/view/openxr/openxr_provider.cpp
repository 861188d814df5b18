// atmos view --xr: the OpenXR view provider (xr.hpp), built with
// ATMOS_OPENXR (Debian's libopenxr-dev). One instance with
// XR_KHR_opengl_enable, the head-mounted display's system, a session bound
// to the viewer's GLX context, a LOCAL reference space, the primary stereo
// view configuration and one swapchain per eye. Each frame: xrWaitFrame,
// xrBeginFrame, xrLocateViews (each eye's pose and four angles at the
// predicted display time), the eyes' display images copied into the
// swapchains' images, and xrEndFrame with one projection layer whose views
// are the located ones, so that the runtime reprojects from the poses the
// images were drawn for.
#define XR_USE_PLATFORM_XLIB
#define XR_USE_GRAPHICS_API_OPENGL
#include <epoxy/gl.h>
#include <epoxy/glx.h>

#include <X11/Xlib.h>
#include <openxr/openxr.h>
#include <openxr/openxr_platform.h>
#include <openxr/openxr_reflection.h>

#include <array>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "xr.hpp"

namespace atmos_view {

namespace {

std::string result_name(XrResult r) {
  switch (r) {
#define ATMOS_XR_RESULT_NAME(name, value) \
  case name:                              \
    return #name;
    XR_LIST_ENUM_XrResult(ATMOS_XR_RESULT_NAME)
#undef ATMOS_XR_RESULT_NAME
    default:
      return "XrResult " + std::to_string(int(r));
  }
}

// An OpenXR structure of type `type`, its other members zero.
template <typename T>
T xr_struct(XrStructureType type) {
  T value{};
  value.type = type;
  return value;
}

void check(XrResult r, const char* call) {
  if (XR_FAILED(r)) throw atmos::Error(std::string("OpenXR: ") + call + " failed (" + result_name(r) + ")");
}

class Provider : public OpenXrProvider {
 public:
  Provider() {
    auto info = xr_struct<XrInstanceCreateInfo>(XR_TYPE_INSTANCE_CREATE_INFO);
    std::strncpy(info.applicationInfo.applicationName, "atmos view", XR_MAX_APPLICATION_NAME_SIZE - 1);
    info.applicationInfo.applicationVersion = 1;
    std::strncpy(info.applicationInfo.engineName, "atmos", XR_MAX_ENGINE_NAME_SIZE - 1);
    info.applicationInfo.apiVersion = XR_CURRENT_API_VERSION;
    const char* extensions[] = {XR_KHR_OPENGL_ENABLE_EXTENSION_NAME};
    info.enabledExtensionCount = 1;
    info.enabledExtensionNames = extensions;
    // The loader prints its own lines for every failure (five without a
    // runtime) unless told otherwise; atmos says it in one. A user's
    // XR_LOADER_DEBUG is kept.
    setenv("XR_LOADER_DEBUG", "none", 0);
    const XrResult r = xrCreateInstance(&info, &instance_);
    if (r == XR_ERROR_RUNTIME_UNAVAILABLE || r == XR_ERROR_RUNTIME_FAILURE || r == XR_ERROR_INSTANCE_LOST)
      throw atmos::Error("atmos view --xr: no OpenXR runtime is installed/active (" + result_name(r) +
                         " from xrCreateInstance): install one (e.g. Monado) and make it active "
                         "(XR_RUNTIME_JSON, or the active_runtime.json of the XDG config directories)");
    if (r == XR_ERROR_EXTENSION_NOT_PRESENT)
      throw atmos::Error("atmos view --xr: the active OpenXR runtime has no OpenGL support (" +
                         std::string(XR_KHR_OPENGL_ENABLE_EXTENSION_NAME) + " is not present)");
    check(r, "xrCreateInstance");
    try {
      find_system();
    } catch (...) {
      xrDestroyInstance(instance_);
      instance_ = XR_NULL_HANDLE;
      throw;
    }
  }

  // The head-mounted display's system and its eyes' recommended size.
  void find_system() {
    auto system = xr_struct<XrSystemGetInfo>(XR_TYPE_SYSTEM_GET_INFO);
    system.formFactor = XR_FORM_FACTOR_HEAD_MOUNTED_DISPLAY;
    const XrResult s = xrGetSystem(instance_, &system, &system_);
    if (s == XR_ERROR_FORM_FACTOR_UNAVAILABLE || s == XR_ERROR_FORM_FACTOR_UNSUPPORTED)
      throw atmos::Error("atmos view --xr: no head-mounted display is connected (" + result_name(s) +
                         " from xrGetSystem)");
    check(s, "xrGetSystem");
    uint32_t count = 0;
    check(xrEnumerateViewConfigurationViews(instance_, system_, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, 0, &count,
                                            nullptr),
          "xrEnumerateViewConfigurationViews");
    std::vector<XrViewConfigurationView> views(count,
                                               xr_struct<XrViewConfigurationView>(XR_TYPE_VIEW_CONFIGURATION_VIEW));
    check(xrEnumerateViewConfigurationViews(instance_, system_, XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO, count,
                                            &count, views.data()),
          "xrEnumerateViewConfigurationViews");
    if (count != 2) throw atmos::Error("atmos view --xr: the headset's stereo configuration has " +
                                       std::to_string(count) + " views, not 2");
    width_ = int(views[0].recommendedImageRectWidth);
    height_ = int(views[0].recommendedImageRectHeight);
  }

  ~Provider() override {
    for (XrSwapchain s : swapchains_)
      if (s != XR_NULL_HANDLE) xrDestroySwapchain(s);
    if (space_ != XR_NULL_HANDLE) xrDestroySpace(space_);
    if (session_ != XR_NULL_HANDLE) xrDestroySession(session_);
    if (instance_ != XR_NULL_HANDLE) xrDestroyInstance(instance_);
  }

  void start() override {
    // The runtime's OpenGL requirements must be asked before the session.
    PFN_xrGetOpenGLGraphicsRequirementsKHR requirements = nullptr;
    check(xrGetInstanceProcAddr(instance_, "xrGetOpenGLGraphicsRequirementsKHR",
                                reinterpret_cast<PFN_xrVoidFunction*>(&requirements)),
          "xrGetInstanceProcAddr(xrGetOpenGLGraphicsRequirementsKHR)");
    auto needs = xr_struct<XrGraphicsRequirementsOpenGLKHR>(XR_TYPE_GRAPHICS_REQUIREMENTS_OPENGL_KHR);
    check(requirements(instance_, system_, &needs), "xrGetOpenGLGraphicsRequirementsKHR");
    if (XR_MAKE_VERSION(4, 5, 0) < needs.minApiVersionSupported)
      throw atmos::Error("atmos view --xr: the OpenXR runtime needs an OpenGL newer than 4.5");

    auto binding = xr_struct<XrGraphicsBindingOpenGLXlibKHR>(XR_TYPE_GRAPHICS_BINDING_OPENGL_XLIB_KHR);
    binding.xDisplay = glXGetCurrentDisplay();
    binding.glxContext = glXGetCurrentContext();
    binding.glxDrawable = glXGetCurrentDrawable();
    if (!binding.xDisplay || !binding.glxContext)
      throw atmos::Error("atmos view --xr: OpenXR's OpenGL binding needs a current GLX context (an X11 window)");
    int config_id = 0;
    glXQueryContext(binding.xDisplay, binding.glxContext, GLX_FBCONFIG_ID, &config_id);
    const int attributes[] = {GLX_FBCONFIG_ID, config_id, None};
    int configs = 0;
    GLXFBConfig* config = glXChooseFBConfig(binding.xDisplay, DefaultScreen(binding.xDisplay), attributes, &configs);
    if (config && configs > 0) {
      binding.glxFBConfig = config[0];
      if (XVisualInfo* visual = glXGetVisualFromFBConfig(binding.xDisplay, config[0])) {
        binding.visualid = uint32_t(visual->visualid);
        XFree(visual);
      }
    }
    if (config) XFree(config);

    auto info = xr_struct<XrSessionCreateInfo>(XR_TYPE_SESSION_CREATE_INFO);
    info.next = &binding;
    info.systemId = system_;
    check(xrCreateSession(instance_, &info, &session_), "xrCreateSession");
    auto space = xr_struct<XrReferenceSpaceCreateInfo>(XR_TYPE_REFERENCE_SPACE_CREATE_INFO);
    space.referenceSpaceType = XR_REFERENCE_SPACE_TYPE_LOCAL;
    space.poseInReferenceSpace.orientation.w = 1.0f;
    check(xrCreateReferenceSpace(session_, &space, &space_), "xrCreateReferenceSpace");

    // sRGB images: the display images hold sRGB-encoded values, copied bit
    // for bit.
    uint32_t count = 0;
    check(xrEnumerateSwapchainFormats(session_, 0, &count, nullptr), "xrEnumerateSwapchainFormats");
    std::vector<int64_t> formats(count);
    check(xrEnumerateSwapchainFormats(session_, count, &count, formats.data()), "xrEnumerateSwapchainFormats");
    int64_t format = 0;
    for (int64_t f : formats)
      if (f == GL_SRGB8_ALPHA8) format = f;
    if (format == 0)
      throw atmos::Error("atmos view --xr: the OpenXR runtime offers no GL_SRGB8_ALPHA8 swapchain");
    for (size_t i = 0; i < 2; ++i) {
      auto sc = xr_struct<XrSwapchainCreateInfo>(XR_TYPE_SWAPCHAIN_CREATE_INFO);
      sc.usageFlags = XR_SWAPCHAIN_USAGE_COLOR_ATTACHMENT_BIT | XR_SWAPCHAIN_USAGE_TRANSFER_DST_BIT;
      sc.format = format;
      sc.sampleCount = 1;
      sc.width = uint32_t(width_);
      sc.height = uint32_t(height_);
      sc.faceCount = 1;
      sc.arraySize = 1;
      sc.mipCount = 1;
      check(xrCreateSwapchain(session_, &sc, &swapchains_[i]), "xrCreateSwapchain");
      uint32_t images = 0;
      check(xrEnumerateSwapchainImages(swapchains_[i], 0, &images, nullptr), "xrEnumerateSwapchainImages");
      images_[i].assign(images, xr_struct<XrSwapchainImageOpenGLKHR>(XR_TYPE_SWAPCHAIN_IMAGE_OPENGL_KHR));
      check(xrEnumerateSwapchainImages(swapchains_[i], images,  &images,
                                       reinterpret_cast<XrSwapchainImageBaseHeader*>(images_[i].data())),
            "xrEnumerateSwapchainImages");
    }
  }

  int eye_width() const override { return width_; }
  int eye_height() const override { return height_; }

  std::optional<HeadsetFrame> begin_frame() override {
    if (session_ == XR_NULL_HANDLE) throw atmos::Error("OpenXR: begin_frame before start()");
    // The session's state: it runs from READY until STOPPING.
    while (true) {
      auto event = xr_struct<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
      while (xrPollEvent(instance_, &event) == XR_SUCCESS) {
        if (event.type == XR_TYPE_EVENT_DATA_INSTANCE_LOSS_PENDING) ended_ = true;
        if (event.type == XR_TYPE_EVENT_DATA_SESSION_STATE_CHANGED) {
          const auto& change = reinterpret_cast<const XrEventDataSessionStateChanged&>(event);
          if (change.state == XR_SESSION_STATE_READY) {
            auto begin = xr_struct<XrSessionBeginInfo>(XR_TYPE_SESSION_BEGIN_INFO);
            begin.primaryViewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
            check(xrBeginSession(session_, &begin), "xrBeginSession");
            running_ = true;
          } else if (change.state == XR_SESSION_STATE_STOPPING) {
            check(xrEndSession(session_), "xrEndSession");
            running_ = false;
          } else if (change.state == XR_SESSION_STATE_EXITING || change.state == XR_SESSION_STATE_LOSS_PENDING) {
            ended_ = true;
          }
        }
        event = xr_struct<XrEventDataBuffer>(XR_TYPE_EVENT_DATA_BUFFER);
      }
      if (ended_) return std::nullopt;
      if (running_) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    auto wait = xr_struct<XrFrameWaitInfo>(XR_TYPE_FRAME_WAIT_INFO);
    state_ = xr_struct<XrFrameState>(XR_TYPE_FRAME_STATE);
    check(xrWaitFrame(session_, &wait, &state_), "xrWaitFrame");
    auto begin = xr_struct<XrFrameBeginInfo>(XR_TYPE_FRAME_BEGIN_INFO);
    check(xrBeginFrame(session_, &begin), "xrBeginFrame");

    auto locate = xr_struct<XrViewLocateInfo>(XR_TYPE_VIEW_LOCATE_INFO);
    locate.viewConfigurationType = XR_VIEW_CONFIGURATION_TYPE_PRIMARY_STEREO;
    locate.displayTime = state_.predictedDisplayTime;
    locate.space = space_;
    auto view_state = xr_struct<XrViewState>(XR_TYPE_VIEW_STATE);
    uint32_t count = 2;
    views_[0] = views_[1] = xr_struct<XrView>(XR_TYPE_VIEW);
    check(xrLocateViews(session_, &locate, &view_state, 2, &count, views_.data()), "xrLocateViews");
    const XrViewStateFlags valid = XR_VIEW_STATE_POSITION_VALID_BIT | XR_VIEW_STATE_ORIENTATION_VALID_BIT;
    HeadsetFrame frame;
    frame.render = state_.shouldRender && (view_state.viewStateFlags & valid) == valid && count == 2;
    for (size_t i = 0; i < 2; ++i) {
      const XrPosef& pose = views_[i].pose;
      frame.eyes[i].position_m = {pose.position.x, pose.position.y, pose.position.z};
      frame.eyes[i].orientation = glm::dquat(pose.orientation.w, pose.orientation.x, pose.orientation.y,
                                             pose.orientation.z);
      const XrFovf& f = views_[i].fov;
      frame.eyes[i].fov = {f.angleLeft, f.angleRight, f.angleUp, f.angleDown};
    }
    rendered_ = frame.render;
    return frame;
  }

  void submit_eye(int eye, GLuint, GLuint display) override {
    const size_t i = size_t(eye);
    uint32_t index = 0;
    auto acquire = xr_struct<XrSwapchainImageAcquireInfo>(XR_TYPE_SWAPCHAIN_IMAGE_ACQUIRE_INFO);
    check(xrAcquireSwapchainImage(swapchains_[i], &acquire, &index), "xrAcquireSwapchainImage");
    auto wait = xr_struct<XrSwapchainImageWaitInfo>(XR_TYPE_SWAPCHAIN_IMAGE_WAIT_INFO);
    wait.timeout = XR_INFINITE_DURATION;
    check(xrWaitSwapchainImage(swapchains_[i], &wait), "xrWaitSwapchainImage");
    glCopyImageSubData(display, GL_TEXTURE_2D, 0, 0, 0, 0, images_[i][index].image, GL_TEXTURE_2D, 0, 0, 0, 0,
                       width_, height_, 1);
    auto release = xr_struct<XrSwapchainImageReleaseInfo>(XR_TYPE_SWAPCHAIN_IMAGE_RELEASE_INFO);
    check(xrReleaseSwapchainImage(swapchains_[i], &release), "xrReleaseSwapchainImage");
  }

  void end_frame() override {
    std::array<XrCompositionLayerProjectionView, 2> projected{};
    auto layer = xr_struct<XrCompositionLayerProjection>(XR_TYPE_COMPOSITION_LAYER_PROJECTION);
    const XrCompositionLayerBaseHeader* layers[] = {reinterpret_cast<XrCompositionLayerBaseHeader*>(&layer)};
    auto end = xr_struct<XrFrameEndInfo>(XR_TYPE_FRAME_END_INFO);
    end.displayTime = state_.predictedDisplayTime;
    end.environmentBlendMode = XR_ENVIRONMENT_BLEND_MODE_OPAQUE;
    if (rendered_) {
      for (size_t i = 0; i < 2; ++i) {
        projected[i] = xr_struct<XrCompositionLayerProjectionView>(XR_TYPE_COMPOSITION_LAYER_PROJECTION_VIEW);
        projected[i].pose = views_[i].pose;
        projected[i].fov = views_[i].fov;
        projected[i].subImage.swapchain = swapchains_[i];
        projected[i].subImage.imageRect.extent = {int32_t(width_), int32_t(height_)};
      }
      layer.space = space_;
      layer.viewCount = 2;
      layer.views = projected.data();
      end.layerCount = 1;
      end.layers = layers;
    }
    check(xrEndFrame(session_, &end), "xrEndFrame");
  }

 private:
  XrInstance instance_ = XR_NULL_HANDLE;
  XrSystemId system_ = XR_NULL_SYSTEM_ID;
  XrSession session_ = XR_NULL_HANDLE;
  XrSpace space_ = XR_NULL_HANDLE;
  std::array<XrSwapchain, 2> swapchains_{XR_NULL_HANDLE, XR_NULL_HANDLE};
  std::array<std::vector<XrSwapchainImageOpenGLKHR>, 2> images_;
  std::array<XrView, 2> views_{};
  XrFrameState state_ = xr_struct<XrFrameState>(XR_TYPE_FRAME_STATE);
  int width_ = 0, height_ = 0;
  bool running_ = false, ended_ = false, rendered_ = false;
};

}  // namespace

std::unique_ptr<OpenXrProvider> make_openxr_provider() { return std::make_unique<Provider>(); }
bool built_with_openxr() { return true; }

}  // namespace atmos_view
