// Headless OpenGL 4.5 core contexts through EGL, without any window system.
//
// EGL entry points beyond EGL 1.4 (eglGetPlatformDisplayEXT,
// eglQueryDevicesEXT) are fetched with eglGetProcAddress after checking the
// client extensions: libepoxy's own dispatch of them needs an initialised
// display to know the EGL version, and aborts the process when it cannot
// find a provider.
#include <epoxy/egl.h>
#include <epoxy/gl.h>

#include <functional>
#include <map>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "atmos/renderer.hpp"

namespace atmos {

namespace {

const char* egl_error_name(EGLint error) {
  switch (error) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
    case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
    default: return "unknown EGL error";
  }
}

std::string egl_failure(const char* call) {
  std::ostringstream s;
  s << call << " failed (" << egl_error_name(eglGetError()) << ")";
  return s.str();
}

bool has_extension(const char* extensions, const std::string& name) {
  if (extensions == nullptr) return false;
  std::istringstream words(extensions);
  std::string word;
  while (words >> word)
    if (word == name) return true;
  return false;
}

// eglTerminate is per display, not per context, and EGL returns the same
// display handle to every caller: a display is terminated only when its last
// GlContext goes away.
std::mutex display_mutex;
std::map<EGLDisplay, int> display_users;

void release_display(EGLDisplay display) {
  std::lock_guard<std::mutex> lock(display_mutex);
  if (--display_users[display] <= 0) {
    display_users.erase(display);
    eglTerminate(display);
  }
}

// Creates a 4.5 core context on `display` (in the share group of `share`
// unless it is EGL_NO_CONTEXT) and makes it current, or returns
// EGL_NO_CONTEXT with the reason in `problem`.
EGLContext create_context(EGLDisplay display, std::string& problem, EGLContext share = EGL_NO_CONTEXT) {
  if (display == EGL_NO_DISPLAY) {
    problem = egl_failure("getting the display");
    return EGL_NO_CONTEXT;
  }
  {
    std::lock_guard<std::mutex> lock(display_mutex);
    EGLint major = 0;
    EGLint minor = 0;
    if (eglInitialize(display, &major, &minor) != EGL_TRUE) {
      problem = egl_failure("eglInitialize");
      return EGL_NO_CONTEXT;
    }
    ++display_users[display];
  }
  auto fail = [&](const std::string& why) {
    problem = why;
    release_display(display);
    return EGL_NO_CONTEXT;
  };
  const char* extensions = eglQueryString(display, EGL_EXTENSIONS);
  if (!has_extension(extensions, "EGL_KHR_surfaceless_context"))
    return fail("EGL_KHR_surfaceless_context not supported");
  if (eglBindAPI(EGL_OPENGL_API) != EGL_TRUE) return fail(egl_failure("eglBindAPI(EGL_OPENGL_API)"));

  // Without a surface the config only matters for the context's type; skip it
  // where the display allows, otherwise take any desktop-GL-capable config.
  EGLConfig config = EGL_NO_CONFIG_KHR;
  if (!has_extension(extensions, "EGL_KHR_no_config_context") &&
      !has_extension(extensions, "EGL_MESA_configless_context")) {
    const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, 0, EGL_NONE};
    EGLint count = 0;
    if (eglChooseConfig(display, config_attributes, &config, 1, &count) != EGL_TRUE)
      return fail(egl_failure("eglChooseConfig"));
    if (count < 1) return fail("no EGL config supports desktop OpenGL");
  }
  const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION,
                                       4,
                                       EGL_CONTEXT_MINOR_VERSION,
                                       5,
                                       EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                       EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                                       EGL_NONE};
  EGLContext context = eglCreateContext(display, config, share, context_attributes);
  if (context == EGL_NO_CONTEXT) return fail(egl_failure("eglCreateContext(OpenGL 4.5 core)"));
  if (eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context) != EGL_TRUE) {
    std::string why = egl_failure("eglMakeCurrent(no surface)");
    eglDestroyContext(display, context);
    return fail(why);
  }
  // Drivers may hand out a higher version than asked for, never a lower one,
  // but check: the shaders need #version 450 and the 4.5 DSA entry points.
  if (!epoxy_is_desktop_gl() || epoxy_gl_version() < 45) {
    std::ostringstream why;
    why << "the driver gave " << (epoxy_is_desktop_gl() ? "OpenGL " : "OpenGL ES ") << epoxy_gl_version() / 10 << "."
        << epoxy_gl_version() % 10;
    eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
    eglDestroyContext(display, context);
    return fail(why.str());
  }
  return context;
}

}  // namespace

std::unique_ptr<GlContext> GlContext::create_headless() {
  // Client extensions (EGL_EXT_client_extensions); null on EGL 1.4 without it.
  const char* client = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (client == nullptr) eglGetError();  // clear EGL_BAD_DISPLAY
  PFNEGLGETPLATFORMDISPLAYEXTPROC get_platform_display = nullptr;
  if (has_extension(client, "EGL_EXT_platform_base"))
    get_platform_display =
        reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));

  // Candidate displays, in order of preference; each is tried only if the
  // previous ones failed (so a working surfaceless Mesa never touches devices).
  std::vector<std::pair<std::string, std::function<EGLDisplay()>>> candidates;
  if (get_platform_display != nullptr && has_extension(client, "EGL_MESA_platform_surfaceless")) {
    candidates.emplace_back("surfaceless", [=] {
      return get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    });
  }
  std::vector<EGLDeviceEXT> devices;
  if (get_platform_display != nullptr && has_extension(client, "EGL_EXT_platform_device")) {
    auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    EGLint count = 0;
    if (query_devices != nullptr && query_devices(0, nullptr, &count) == EGL_TRUE && count > 0) {
      devices.resize(size_t(count));
      if (query_devices(count, devices.data(), &count) != EGL_TRUE) count = 0;
      devices.resize(size_t(count));
    }
    for (size_t i = 0; i < devices.size(); ++i) {
      EGLDeviceEXT device = devices[i];
      candidates.emplace_back("EGL device " + std::to_string(i), [=] {
        return get_platform_display(EGL_PLATFORM_DEVICE_EXT, device, nullptr);
      });
    }
  }
  candidates.emplace_back("default display", [] { return eglGetDisplay(EGL_DEFAULT_DISPLAY); });

  std::string problems;
  for (auto& [name, get_display] : candidates) {
    EGLDisplay display = get_display();
    std::string problem;
    EGLContext context = create_context(display, problem);
    if (context != EGL_NO_CONTEXT) return std::unique_ptr<GlContext>(new GlContext(display, context));
    problems += (problems.empty() ? "" : "; ") + (candidates.size() > 1 ? name + ": " : "") + problem;
  }
  throw Error("no OpenGL 4.5 context: " + problems);
}

std::unique_ptr<GlContext> GlContext::create_shared() {
  // Created current on this thread (as create_context checks its version),
  // then this context made current again.
  const EGLContext previous = eglGetCurrentContext();
  std::string problem;
  EGLContext context = create_context(display_, problem, context_);
  if (previous != EGL_NO_CONTEXT) eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, previous);
  else eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  if (context == EGL_NO_CONTEXT) throw Error("no shared OpenGL 4.5 context: " + problem);
  return std::unique_ptr<GlContext>(new GlContext(display_, context));
}

GlContext::~GlContext() {
  if (eglGetCurrentContext() == context_)
    eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display_, context_);
  release_display(display_);
}

void GlContext::make_current() {
  // The bound API is per thread (EGL 1.5, 3.7): a new thread starts with
  // OpenGL ES's.
  eglBindAPI(EGL_OPENGL_API);
  if (eglGetCurrentContext() == context_) return;
  if (eglMakeCurrent(display_, EGL_NO_SURFACE, EGL_NO_SURFACE, context_) != EGL_TRUE)
    throw Error("cannot make the OpenGL context current on this thread: " + egl_failure("eglMakeCurrent") +
                " (it may be current on another thread)");
}

std::string GlContext::renderer_string() {
  make_current();
  auto text = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s == nullptr ? std::string("?") : std::string(reinterpret_cast<const char*>(s));
  };
  return text(GL_RENDERER) + ", OpenGL " + text(GL_VERSION);
}

}  // namespace atmos
