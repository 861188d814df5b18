#include "viewer.hpp"

#include <epoxy/gl.h>
#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>
#include <glm/geometric.hpp>
#include <imgui.h>
#include <backends/imgui_impl_glfw.h>
#include <backends/imgui_impl_opengl3.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "atmos/image.hpp"
#include "atmos/planet_file.hpp"
#include "atmos/planet_parameters.hpp"
#include "atmos/post.hpp"
#include "atmos/renderer.hpp"
#include "atmos/stereo.hpp"
#include "scene.hpp"
#include "script.hpp"
#include "xr.hpp"

namespace atmos_view {

namespace {

constexpr double kDegree = M_PI / 180.0;
// The Moon's apparent angular radius from the Earth, rad (1737.4 km at 384 400 km).
constexpr double kMoonAngularRadius = 0.2590 * kDegree;

bool has_extension(const std::string& path, const std::string& ext) {
  if (path.size() < ext.size()) return false;
  std::string tail = path.substr(path.size() - ext.size());
  std::transform(tail.begin(), tail.end(), tail.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return tail == ext;
}

// The sun's azimuth (from north towards east) and elevation, degrees, in
// the local frame of the ground point below `position`.
void sun_angles(const glm::dvec3& position, const glm::dvec3& sun, double& azimuth_deg, double& elevation_deg) {
  glm::dvec3 east, north, up;
  local_frame(position, east, north, up);
  elevation_deg = std::asin(std::clamp(glm::dot(sun, up), -1.0, 1.0)) / kDegree;
  azimuth_deg = std::atan2(glm::dot(sun, east), glm::dot(sun, north)) / kDegree;
}

glm::dvec3 sun_from_angles(const glm::dvec3& position, double azimuth_deg, double elevation_deg) {
  glm::dvec3 east, north, up;
  local_frame(position, east, north, up);
  const double az = azimuth_deg * kDegree, el = elevation_deg * kDegree;
  return glm::normalize((north * std::cos(az) + east * std::sin(az)) * std::cos(el) + up * std::sin(el));
}

// Local solar time at the camera's longitude, hours in [0, 24): noon where
// the sun's hour angle is zero (the sun on the camera's meridian), 15
// degrees of longitude an hour.
double time_of_day_h(const glm::dvec3& position, const glm::dvec3& sun) {
  const double camera_longitude = std::atan2(position.y, position.x);
  const double subsolar_longitude = std::atan2(sun.y, sun.x);
  const double hours = 12.0 + (camera_longitude - subsolar_longitude) / kDegree / 15.0;
  return hours - 24.0 * std::floor(hours / 24.0);
}

// The sun at local solar time `hours` for the camera, with its declination kept.
glm::dvec3 sun_at_time(const glm::dvec3& position, const glm::dvec3& sun, double hours) {
  const double declination = std::asin(std::clamp(sun.z, -1.0, 1.0));
  const double subsolar_longitude = std::atan2(position.y, position.x) - (hours - 12.0) * 15.0 * kDegree;
  return {std::cos(declination) * std::cos(subsolar_longitude), std::cos(declination) * std::sin(subsolar_longitude),
          std::sin(declination)};
}

// The moon of LookSettings: the Moon's apparent size, `separation` from the
// sun's centre towards the local zenith (or any side for a sun at the zenith).
std::vector<atmos::Moon> look_moons(const LookSettings& look, const glm::dvec3& position, const glm::dvec3& sun,
                                    double top_radius_m) {
  if (!look.moon) return {};
  glm::dvec3 towards = glm::normalize(position) - sun * glm::dot(glm::normalize(position), sun);
  if (glm::length(towards) < 1e-6) towards = glm::cross(sun, glm::dvec3(1, 0, 0));
  if (glm::length(towards) < 1e-6) towards = glm::cross(sun, glm::dvec3(0, 1, 0));
  towards = glm::normalize(towards);
  const double s = look.moon_separation_deg * kDegree;
  const glm::dvec3 direction = glm::normalize(sun * std::cos(s) + towards * std::sin(s));
  std::vector<atmos::Moon> moons = {atmos::moon_in_sky(position, direction, kMoonAngularRadius)};
  // From far out (beyond the Moon's distance) the moon may be placed inside
  // the atmosphere: no moon then, rather than an error every frame.
  try {
    atmos::validate_moons(moons, top_radius_m);
  } catch (const atmos::Error&) {
    return {};
  }
  return moons;
}

// The moons of a frame: the look's, and the Moon of a date (its centre,
// planet-centred m) unless it would stand inside the atmosphere.
std::vector<atmos::Moon> place_moons(const LookSettings& look, const glm::dvec3& position, const glm::dvec3& sun,
                                     double top_radius_m, const std::optional<glm::dvec3>& moon_of_date_m) {
  std::vector<atmos::Moon> moons = look_moons(look, position, sun, top_radius_m);
  if (moon_of_date_m) {
    const atmos::Moon moon{*moon_of_date_m, atmos::kMoonRadiusM};
    try {
      atmos::validate_moons({moon}, top_radius_m);
      moons.push_back(moon);
    } catch (const atmos::Error&) {
    }
  }
  return moons;
}

atmos::PostSettings post_settings(const LookSettings& look) {
  atmos::PostSettings s;
  s.tone_mapping = look.tone_mapping;
  s.exposure_ev = look.exposure_ev;
  s.bloom.strength = std::clamp(look.bloom, 0.0, 1.0);
  s.auto_exposure.enabled = look.auto_exposure;
  s.auto_exposure.compensation_ev = look.compensation_ev;
  return s;
}

// The slider of a planet parameter as planet_parameters() describes it: its
// label, its value in its unit, its slider's range and scale. Ctrl+click
// types a value, which may lie outside the range: make_atmosphere checks it.
bool parameter_slider(const char* parameter, float& value) {
  const atmos::PlanetParameter& p = atmos::planet_parameter(parameter);
  const std::string format = std::string("%.4g") + (std::string(p.unit) == "1" ? "" : std::string(" ") + p.unit);
  return ImGui::SliderFloat(p.label, &value, float(p.slider_min), float(p.slider_max), format.c_str(),
                            p.logarithmic ? ImGuiSliderFlags_Logarithmic : ImGuiSliderFlags_None);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// ---------------------------------------------------------------------------
// The window

std::string& glfw_error() {
  static std::string message;
  return message;
}

void on_glfw_error(int code, const char* description) {
  glfw_error() = std::string(description ? description : "unknown error") + " (GLFW error " + std::to_string(code) + ")";
}

// GLFW and its window: terminated in the destructor, after everything
// that used the context.
struct Window {
  GLFWwindow* window = nullptr;
  GLFWwindow* shared = nullptr;  // nullptr if the context could not be shared

  Window(int width, int height, bool visible) {
    const char* display = std::getenv("DISPLAY");
    const char* wayland = std::getenv("WAYLAND_DISPLAY");
    if ((!display || !*display) && (!wayland || !*wayland))
      throw atmos::Error(
          "no display: atmos view opens a window (neither DISPLAY nor WAYLAND_DISPLAY is set); run it under "
          "xvfb-run, or replay a recorded flight headless with --replay");
    glfwSetErrorCallback(on_glfw_error);
    if (!glfwInit()) throw atmos::Error("cannot open a window: " + glfw_error());
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 4);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 5);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_VISIBLE, visible ? GLFW_TRUE : GLFW_FALSE);
    glfwWindowHint(GLFW_RESIZABLE, GLFW_TRUE);
    window = glfwCreateWindow(width, height, "atmos view", nullptr, nullptr);
    if (!window) {
      const std::string why = glfw_error();
      glfwTerminate();
      throw atmos::Error("cannot open an OpenGL 4.5 core window: " + why);
    }
    // A hidden window whose context shares the window's objects: a scene's
    // thread links programs in it (Scene::EarlyLink). Without it they are
    // linked on this thread.
    glfwWindowHint(GLFW_VISIBLE, GLFW_FALSE);
    shared = glfwCreateWindow(1, 1, "atmos view: programs", nullptr, window);
    glfwMakeContextCurrent(window);
    glfwSwapInterval(0);
    // Keys and buttons are polled once a frame: sticky ones report a press
    // released before the poll (a tap of 1-4 or Esc within a slow frame).
    glfwSetInputMode(window, GLFW_STICKY_KEYS, GLFW_TRUE);
    glfwSetInputMode(window, GLFW_STICKY_MOUSE_BUTTONS, GLFW_TRUE);
  }
  ~Window() {
    if (shared) glfwDestroyWindow(shared);
    glfwDestroyWindow(window);
    glfwTerminate();
  }
  Window(const Window&) = delete;
  Window& operator=(const Window&) = delete;
};

// Dear ImGui with the GLFW platform and OpenGL 3 renderer backends that
// Debian's libimgui-dev ships.
struct Gui {
  explicit Gui(GLFWwindow* window) {
    IMGUI_CHECKVERSION();
    ImGui::CreateContext();
    ImGui::GetIO().IniFilename = nullptr;  // no imgui.ini in the working directory
    ImGui::StyleColorsDark();
    ImGui_ImplGlfw_InitForOpenGL(window, true);
    ImGui_ImplOpenGL3_Init("#version 450 core");
  }
  ~Gui() {
    ImGui_ImplOpenGL3_Shutdown();
    ImGui_ImplGlfw_Shutdown();
    ImGui::DestroyContext();
  }
  Gui(const Gui&) = delete;
  Gui& operator=(const Gui&) = delete;
};

// Frame times and what happened in each frame.
struct FrameLog {
  std::vector<double> ms;
  std::vector<bool> dragging;
  std::vector<bool> swapped;

  void add(double frame_ms, bool drag, bool swap) {
    ms.push_back(frame_ms);
    dragging.push_back(drag);
    swapped.push_back(swap);
  }
  // The frames that count for the statistics: all but the first (its
  // programs are compiled at their first draw) and the table swaps (a new
  // scene compiles its programs).
  std::vector<double> steady() const {
    std::vector<double> out;
    for (size_t i = 1; i < ms.size(); ++i)
      if (!swapped[i]) out.push_back(ms[i]);
    return out;
  }
  // The frames that swap tables in and the `after` frames that follow each
  // (where a swap's cost would show: its new programs, its first draws).
  std::vector<double> around_swaps(size_t after) const {
    std::vector<double> out;
    size_t until = 0;
    for (size_t i = 1; i < ms.size(); ++i) {
      if (swapped[i]) until = i + after + 1;
      if (i < until) out.push_back(ms[i]);
    }
    return out;
  }
};

// Frames a scripted session draws after its last swap, so that the swap's
// cost on the frames that follow it is measured.
constexpr int kFramesAfterSwap = 5;

class Viewer {
 public:
  explicit Viewer(const ViewOptions& o) : o_(o) {}

  int run();

 private:
  Flight::GroundHeight ground() const {
    return [this](const glm::dvec3& p) { return scene_->ground_height_m(p); };
  }
  // New tables: their pass (or scene) built, its programs linked on the
  // scene's thread (swap_scene); swapped in once linked (finish_swap).
  void swap_scene(PlanetTables&& tables);
  bool swap_pending() const { return scene_->rebind_pending() || next_scene_ != nullptr; }
  bool swap_ready() const;
  void finish_swap(int frame);
  // The latest frame for the scene's thread to link the programs of new
  // tables for (none without a shared context).
  std::optional<Scene::EarlyLink> early_link(double top_radius_m);
  void set_slider(const std::string& name, double value);
  double slider_value(const std::string& name) const;
  void request_tables();
  void save_edited_planet(const std::string& path);
  FlightInput window_input();
  void panel();
  void loading_panel();
  void constituents_panel();
  void progress_bar();
  void write_screenshot(const std::string& path, GLuint hdr, int width, int height);

  // The frame's HDR image: the scene's, or its two eyes' in the stereo
  // layout; its width (twice an eye's side by side).
  GLuint render_frame(SceneFrame& sf, int width, int height, int& image_width);
  void stereo_panel();

  // The frame's inputs from the camera, the sun and the look.
  SceneFrame scene_frame(int width, int height, double top_radius_m);
  SceneFrame scene_frame_at(const CameraPose& pose, int width, int height, double top_radius_m);
  // The camera, sun and moons of the viewer's start over the planet of
  // `tables` (the ground at its datum until the globe is built).
  void place_camera(const PlanetTables& tables);

  // Jumps (keys 1-4, the panel's buttons): the programs of the view at the
  // destination are linked and compiled first on a thread in the shared
  // context (AtmospherePass::link_programs), while this thread draws on
  // where the camera is; the camera jumps once they are ready (a scripted
  // session waits for them, so that its path does not depend on the
  // machine). New tables are taken once no jump is being prepared, and no
  // jump is prepared while a swap is pending: both use the shared context.
  // Returns whether the jump was deferred.
  bool prepare_jump(int which, int width, int height, bool wait);
  void finish_jump();
  std::thread jump_linker_;
  std::atomic<bool> jump_linking_{false};
  std::exception_ptr jump_error_;
  int pending_jump_ = 0;
  double jump_start_s_ = 0.0;
  int requested_jump_ = 0;  // the panel's button, this frame

  const ViewOptions& o_;
  GLFWwindow* shared_context_ = nullptr;
  std::unique_ptr<Scene> scene_;
  std::unique_ptr<Scene> next_scene_;  // new tables over another ground, linking its programs
  StereoSettings stereo_;
  std::unique_ptr<StereoComposer> composer_;
  std::unique_ptr<atmos::PostProcess> post_;
  std::unique_ptr<TableJob> job_;
  std::unique_ptr<Flight> flight_;
  GLFWwindow* window_ = nullptr;
  glm::dvec3 sun_{0, 0, 1};
  std::optional<glm::dvec3> moon_of_date_;  // planet-centred m
  LookSettings look_;
  PlanetParams edited_;  // the planet the panel shows (the scene's, or one being computed)
  std::string planet_file_;
  std::string save_file_;
  std::string message_;  // the last error or status, shown in the panel
  bool message_is_error_ = false;
  bool timed_ = true;
  bool awaiting_tables_ = false;  // requested tables not swapped in yet
  double last_swap_ms_ = 0.0, last_tables_s_ = 0.0;
  double pending_pass_ms_ = 0.0;  // a rebind prepared the frame before (Scene::prepare_rebind)
  std::string pending_status_;
  std::vector<float> plot_;
  FrameLog log_;
  FlightRecord record_;
  double mouse_x_ = 0.0, mouse_y_ = 0.0;
  bool dragging_view_ = false;
  std::array<bool, 4> jump_held_{};
  double start_s_ = 0.0;
  // The latest frame's camera, sun and look, for the job's warm-up.
  std::mutex warm_mutex_;
  SceneFrame warm_frame_;
  LookSettings warm_look_;
  LookSettings look_of_warm_frame() {
    std::lock_guard<std::mutex> lock(warm_mutex_);
    return warm_look_;
  }
};

SceneFrame Viewer::scene_frame(int width, int height, double top_radius_m) {
  return scene_frame_at(flight_->pose(), width, height, top_radius_m);
}

SceneFrame Viewer::scene_frame_at(const CameraPose& pose, int width, int height, double top_radius_m) {
  SceneFrame sf;
  sf.pose = pose;
  sf.fov_deg = look_.fov_deg;
  sf.width = width;
  sf.height = height;
  sf.sun = sun_;
  sf.stars = look_.stars || glm::dot(sun_, glm::normalize(sf.pose.position)) < 0.0;
  sf.moons = place_moons(look_, sf.pose.position, sun_, top_radius_m, moon_of_date_);
  sf.timed = timed_;
  return sf;
}

void Viewer::place_camera(const PlanetTables& tables) {
  const Flight::GroundHeight datum = [](const glm::dvec3&) { return 0.0; };
  const Flight::GroundHeight g = scene_ ? ground() : datum;
  flight_ = std::make_unique<Flight>(tables.planet.bottom_radius_m);
  flight_->place(o_.latitude_deg, o_.longitude_deg, o_.altitude_m, o_.heading_deg, o_.pitch_deg, g);
  sun_ = sun_from_angles(flight_->position(), o_.sun_azimuth_deg, o_.sun_elevation_deg);
  // The date's Moon seen from the starting ground point, where it stays.
  if (o_.moon_of_date_m)
    moon_of_date_ = glm::normalize(flight_->position()) * tables.planet.bottom_radius_m + *o_.moon_of_date_m;
}

std::optional<Scene::EarlyLink> Viewer::early_link(double top_radius_m) {
  if (!shared_context_) return std::nullopt;
  SceneFrame sf;
  {
    std::lock_guard<std::mutex> lock(warm_mutex_);
    sf = warm_frame_;
  }
  if (sf.width < 1 || sf.height < 1) return std::nullopt;
  sf.moons = place_moons(look_, sf.pose.position, sf.sun, top_radius_m, moon_of_date_);
  GLFWwindow* shared = shared_context_;
  return Scene::EarlyLink{[shared](bool current) { glfwMakeContextCurrent(current ? shared : nullptr); }, sf};
}

void Viewer::swap_scene(PlanetTables&& tables) {
  const double start = now_s();
  last_tables_s_ = tables.seconds;
  pending_status_ = tables.status;
  // The programs of the latest frame are linked for the new pass on the
  // scene's thread in the shared context, while this thread draws on with
  // the old tables; they are swapped in once it is done (finish_swap).
  const std::optional<Scene::EarlyLink> early = early_link(tables.planet.top_radius_m);
  // The same ground keeps its globe: the new pass now, the globe bound to
  // it once its programs are linked. Another ground needs a new scene,
  // built first: if it cannot be built the old one stays.
  if (scene_->prepare_rebind(tables, early ? &*early : nullptr)) {
    pending_pass_ms_ = (now_s() - start) * 1e3;
    return;
  }
  next_scene_ = std::make_unique<Scene>(tables, o_.globe, !o_.planet_albedo, o_.frames > 0,
                                        early ? atmos::PassPrograms::none : atmos::PassPrograms::common,
                                        early ? &*early : nullptr);
  pending_pass_ms_ = (now_s() - start) * 1e3;
}

bool Viewer::swap_ready() const {
  return (scene_->rebind_pending() && !scene_->linking()) || (next_scene_ && !next_scene_->linking());
}

bool Viewer::prepare_jump(int which, int width, int height, bool wait) {
  if (!shared_context_ || width < 1 || height < 1 || swap_pending() || scene_->linking()) return false;
  if (jump_linking_.load()) return true;  // one jump at a time: this one is dropped
  Flight destination = *flight_;
  destination.jump(which, ground());
  const SceneFrame sf = scene_frame_at(destination.pose(), width, height, scene_->top_radius_m());
  if (scene_->programs_linked(sf)) return false;
  if (jump_linker_.joinable()) jump_linker_.join();
  pending_jump_ = which;
  jump_start_s_ = now_s();
  jump_error_ = nullptr;
  jump_linking_ = true;
  const Scene* scene = scene_.get();
  GLFWwindow* shared = shared_context_;
  jump_linker_ = std::thread([this, scene, shared, input = scene->link_input(sf)] {
    glfwMakeContextCurrent(shared);
    try {
      scene->link_programs(input);
    } catch (...) {
      jump_error_ = std::current_exception();
    }
    glfwMakeContextCurrent(nullptr);
    jump_linking_ = false;
  });
  const char* names[] = {"", "the ground", "10 km", "orbit", "2.5 radii"};
  message_ = std::string("jump to ") + names[which] + ": compiling its view's programs";
  message_is_error_ = false;
  if (wait) finish_jump();
  return true;
}

void Viewer::finish_jump() {
  if (jump_linker_.joinable()) jump_linker_.join();
  const int which = pending_jump_;
  pending_jump_ = 0;
  message_.clear();
  if (jump_error_) {
    // Not prepared: the jump's first frame links them on this thread, as
    // without a shared context.
    try {
      std::rethrow_exception(jump_error_);
    } catch (const std::exception& e) {
      message_ = e.what();
      message_is_error_ = true;
    }
  } else {
    std::printf("jump %d: its programs prepared in %.2f s\n", which, now_s() - jump_start_s_);
    std::fflush(stdout);
  }
  flight_->jump(which, ground());
}

void Viewer::finish_swap(int frame) {
  const double start = now_s();
  // Whether this frame's programs were all linked before the swap (none
  // is then linked on this thread).
  SceneFrame latest;
  {
    std::lock_guard<std::mutex> lock(warm_mutex_);
    latest = warm_frame_;
  }
  if (next_scene_) {
    std::unique_ptr<Scene> scene = std::move(next_scene_);
    scene->join_linker();
    const bool linked = latest.width > 0 && scene->programs_linked(latest);
    const double altitude = flight_ ? flight_->altitude_m(ground()) : 0.0;
    scene_ = std::move(scene);
    if (flight_) flight_->set_bottom_radius(scene_->bottom_radius_m(), altitude, ground());
    last_swap_ms_ = pending_pass_ms_ + (now_s() - start) * 1e3;
    std::printf("tables: %s in %.2f s; swapped in at frame %d (%.0f ms to build the scene; programs linked "
                "beforehand: %s)\n",
                pending_status_.c_str(), last_tables_s_, frame, pending_pass_ms_, linked ? "yes" : "no");
    std::fflush(stdout);
    return;
  }
  const bool linked = latest.width > 0 && !scene_->linking() && scene_->programs_linked(latest);
  scene_->finish_rebind();
  const double rebind_ms = (now_s() - start) * 1e3;
  last_swap_ms_ = pending_pass_ms_ + rebind_ms;
  std::printf("tables: %s in %.2f s; swapped in at frame %d (%.0f ms for their pass before, %.0f ms to "
              "rebind the scene; programs linked beforehand: %s)\n",
              pending_status_.c_str(), last_tables_s_, frame, pending_pass_ms_, rebind_ms, linked ? "yes" : "no");
  std::fflush(stdout);
}

void Viewer::request_tables() {
  try {
    (void)make_atmosphere(edited_);  // bad values are reported now, the old tables stay
    job_->request(edited_);
    awaiting_tables_ = true;
    message_.clear();
  } catch (const std::exception& e) {
    message_ = e.what();
    message_is_error_ = true;
    edited_ = scene_->params();
    std::fprintf(stderr, "atmos: error: %s (the tables on screen are kept)\n", e.what());
  }
}

void Viewer::save_edited_planet(const std::string& path) {
  try {
    save_planet(edited_, path);
    message_ = "saved the planet to " + path;
    message_is_error_ = false;
    std::printf("saved the planet: %s\n", path.c_str());
  } catch (const std::exception& e) {
    message_ = e.what();
    message_is_error_ = true;
    std::fprintf(stderr, "atmos: error: %s\n", e.what());
  }
}

double Viewer::slider_value(const std::string& name) const {
  double az = 0.0, el = 0.0;
  sun_angles(flight_->position(), sun_, az, el);
  const atmos::Atmosphere& a = scene_->planet();
  if (name == "sun_elevation") return el;
  if (name == "sun_azimuth") return az;
  if (name == "time_of_day") return time_of_day_h(flight_->position(), sun_);
  if (name == "exposure_ev") return look_.exposure_ev;
  if (name == "compensation_ev") return look_.compensation_ev;
  if (name == "bloom") return look_.bloom;
  if (name == "fov_deg") return look_.fov_deg;
  if (name == "interpupillary_m") return stereo_.interpupillary_m;
  if (name == "convergence_m") return stereo_.convergence_m;
  if (name == "moon_separation_deg") return look_.moon_separation_deg;
  if (name == "density_scale") return edited_.density_scale;
  if (name == "ground_albedo") return edited_.ground_albedo.value_or(a.ground_albedo.at(550.0));
  if (name == "wavelengths") return double(edited_.wavelengths ? edited_.wavelengths : int(a.wavelengths_nm.size()));
  if (name == "orders") return double(edited_.orders);
  if (name == "bottom_radius_km") return edited_.bottom_radius_m.value_or(a.bottom_radius_m) * 1e-3;
  if (name == "thickness_km") return edited_.thickness_m.value_or(a.top_radius_m - a.bottom_radius_m) * 1e-3;
  return 0.0;
}

void Viewer::set_slider(const std::string& name, double v) {
  double az = 0.0, el = 0.0;
  sun_angles(flight_->position(), sun_, az, el);
  if (name == "sun_elevation") sun_ = sun_from_angles(flight_->position(), az, std::clamp(v, -90.0, 90.0));
  if (name == "sun_azimuth") sun_ = sun_from_angles(flight_->position(), v, el);
  if (name == "time_of_day") sun_ = sun_at_time(flight_->position(), sun_, v);
  if (name == "exposure_ev") look_.exposure_ev = std::clamp(v, -10.0, 25.0);
  if (name == "compensation_ev") look_.compensation_ev = std::clamp(v, -10.0, 10.0);
  if (name == "bloom") look_.bloom = std::clamp(v, 0.0, 1.0);
  if (name == "fov_deg") look_.fov_deg = std::clamp(v, 5.0, 120.0);
  if (name == "interpupillary_m") stereo_.interpupillary_m = std::clamp(v, 1e-3, 1e7);
  if (name == "convergence_m") stereo_.convergence_m = std::max(v, 0.1);
  if (name == "moon_separation_deg") look_.moon_separation_deg = std::clamp(v, 0.0, 10.0);
  if (name == "density_scale") edited_.density_scale = v;
  if (name == "ground_albedo") edited_.ground_albedo = v;
  if (name == "wavelengths") edited_.wavelengths = int(std::lround(v));
  if (name == "orders") edited_.orders = int(std::lround(v));
  if (name == "bottom_radius_km") edited_.bottom_radius_m = v * 1e3;
  if (name == "thickness_km") edited_.thickness_m = v * 1e3;
}

FlightInput Viewer::window_input() {
  FlightInput in;
  const ImGuiIO& io = ImGui::GetIO();
  if (!io.WantCaptureKeyboard) {
    const auto down = [this](int key) { return glfwGetKey(window_, key) == GLFW_PRESS; };
    in.forward = down(GLFW_KEY_W);
    in.back = down(GLFW_KEY_S);
    in.left = down(GLFW_KEY_A);
    in.right = down(GLFW_KEY_D);
    in.down = down(GLFW_KEY_Q);
    in.up = down(GLFW_KEY_E);
    if (down(GLFW_KEY_ESCAPE)) glfwSetWindowShouldClose(window_, GLFW_TRUE);
    if (down(GLFW_KEY_LEFT_SHIFT) || down(GLFW_KEY_RIGHT_SHIFT)) in.speed_multiplier = 10.0;
    if (down(GLFW_KEY_LEFT_CONTROL) || down(GLFW_KEY_RIGHT_CONTROL)) in.speed_multiplier = 0.1;
    // A jump on the press of its key, not on every frame it is held.
    for (int k = 0; k < 4; ++k) {
      const bool held = down(GLFW_KEY_1 + k);
      if (held && !jump_held_[size_t(k)]) in.jump = k + 1;
      jump_held_[size_t(k)] = held;
    }
  }
  double x = 0.0, y = 0.0;
  glfwGetCursorPos(window_, &x, &y);
  const bool pressed = glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS ||
                       glfwGetMouseButton(window_, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  // A drag that starts outside the panel turns the view.
  if (pressed && !dragging_view_ && !io.WantCaptureMouse) dragging_view_ = true;
  if (!pressed) dragging_view_ = false;
  if (dragging_view_) {
    in.look_dx = x - mouse_x_;
    in.look_dy = y - mouse_y_;
  }
  mouse_x_ = x;
  mouse_y_ = y;
  return in;
}

void Viewer::panel() {
  ImGui::SetNextWindowPos(ImVec2(8, 8), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSize(ImVec2(420, 0), ImGuiCond_FirstUseEver);
  ImGui::SetNextWindowSizeConstraints(ImVec2(200, 100), ImVec2(10000, ImGui::GetIO().DisplaySize.y - 16.0f));
  ImGui::Begin("atmos view");
  const Flight::GroundHeight g = ground();

  // Frame times.
  const double last = log_.ms.empty() ? 0.0 : log_.ms.back();
  ImGui::Text("frame %.1f ms (%.1f fps)", last, last > 0.0 ? 1e3 / last : 0.0);
  if (!plot_.empty())
    ImGui::PlotLines("##frames", plot_.data(), int(plot_.size()), 0, "frame time, ms", 0.0f,
                     float(*std::max_element(plot_.begin(), plot_.end()) * 1.2), ImVec2(0, 60));
  ImGui::Checkbox("GPU times", &timed_);
  if (timed_) {
    const atmos::PassTimings& p = scene_->pass_timings();
    const atmos::PostTimings& q = post_->last_timings();
    if (scene_->has_globe()) {
      if (std::isnan(scene_->terrain_ms()))
        ImGui::TextUnformatted("terrain       ... ms");
      else
        ImGui::Text("terrain    %6.2f ms", scene_->terrain_ms());
    }
    ImGui::Text("sky-view   %6.2f ms", p.sky_view_ms);
    ImGui::Text("volume     %6.2f ms", p.volume_ms);
    ImGui::Text("composite  %6.2f ms", p.composite_ms);
    ImGui::Text("post       %6.2f ms", q.total_ms());
    ImGui::Text("  bloom %.2f, exposure %.2f, tone map %.2f ms", q.bloom_ms, q.exposure_ms, q.tone_map_ms);
  }
  if (const atmos::GlobeStats* s = scene_->globe_stats())
    ImGui::Text("tiles %d (%d pending), %lld triangles", s->tiles_drawn, s->tiles_pending, s->triangles);

  // The camera.
  if (ImGui::CollapsingHeader("Camera", ImGuiTreeNodeFlags_DefaultOpen)) {
    const double altitude = flight_->altitude_m(g);
    ImGui::Text("altitude %.6g m  speed %.3g m/s", altitude, flight_->speed_m_per_s(g));
    ImGui::Text("lat %.4f  lon %.4f  heading %.1f  pitch %.1f", flight_->latitude_deg(), flight_->longitude_deg(),
                flight_->heading_deg(), flight_->pitch_deg());
    const char* jumps[] = {"1 ground", "2 10 km", "3 orbit", "4 2.5 radii"};
    for (int k = 0; k < 4; ++k) {
      if (k) ImGui::SameLine();
      if (ImGui::Button(jumps[k])) requested_jump_ = k + 1;
    }
    ImGui::TextDisabled("drag: look; WASD, Q/E: fly; Esc: quit");
    ImGui::TextDisabled("Shift: 10x faster, Ctrl: 10x slower");
    float fov = float(look_.fov_deg);
    if (ImGui::SliderFloat("field of view", &fov, 5.0f, 120.0f, "%.1f deg")) set_slider("fov_deg", double(fov));
  }

  stereo_panel();

  // The sun and the sky.
  if (ImGui::CollapsingHeader("Sun and sky", ImGuiTreeNodeFlags_DefaultOpen)) {
    float az = float(slider_value("sun_azimuth")), el = float(slider_value("sun_elevation"));
    float hours = float(slider_value("time_of_day"));
    if (ImGui::SliderFloat("sun azimuth", &az, -180.0f, 180.0f, "%.1f deg")) set_slider("sun_azimuth", double(az));
    if (ImGui::SliderFloat("sun elevation", &el, -90.0f, 90.0f, "%.2f deg")) set_slider("sun_elevation", double(el));
    if (ImGui::SliderFloat("time of day", &hours, 0.0f, 24.0f, "%.2f h")) set_slider("time_of_day", double(hours));
    ImGui::Checkbox("stars by day", &look_.stars);
    ImGui::Checkbox("moon", &look_.moon);
    if (look_.moon) {
      float sep = float(look_.moon_separation_deg);
      if (ImGui::SliderFloat("moon from sun", &sep, 0.0f, 3.0f, "%.3f deg")) set_slider("moon_separation_deg", double(sep));
    }
  }

  // The camera-like output.
  if (ImGui::CollapsingHeader("Exposure and tone mapping", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::Checkbox("auto exposure", &look_.auto_exposure);
    if (look_.auto_exposure) {
      float c = float(look_.compensation_ev);
      if (ImGui::SliderFloat("compensation", &c, -5.0f, 5.0f, "%.1f EV")) set_slider("compensation_ev", double(c));
      ImGui::Text("exposure EV100 %.2f", post_->current_exposure_ev());
    } else {
      float ev = float(look_.exposure_ev);
      if (ImGui::SliderFloat("exposure", &ev, -6.0f, 18.0f, "EV100 %.1f")) set_slider("exposure_ev", double(ev));
    }
    const atmos::ToneMapping ops[] = {atmos::ToneMapping::exp, atmos::ToneMapping::reinhard, atmos::ToneMapping::filmic,
                                      atmos::ToneMapping::aces, atmos::ToneMapping::linear};
    if (ImGui::BeginCombo("tone mapper", atmos::tone_mapping_name(look_.tone_mapping))) {
      for (atmos::ToneMapping op : ops)
        if (ImGui::Selectable(atmos::tone_mapping_name(op), op == look_.tone_mapping)) look_.tone_mapping = op;
      ImGui::EndCombo();
    }
    float bloom = float(look_.bloom);
    if (ImGui::SliderFloat("bloom", &bloom, 0.0f, 0.5f, "%.3f")) set_slider("bloom", double(bloom));
  }

  // The planet: new tables in the background.
  if (ImGui::CollapsingHeader("Planet and tables", ImGuiTreeNodeFlags_DefaultOpen)) {
    const std::vector<std::string> presets = atmos::preset_names();
    if (ImGui::BeginCombo("preset", edited_.planet.c_str())) {
      for (const std::string& name : presets)
        if (ImGui::Selectable(name.c_str(), name == edited_.planet)) {
          edited_ = PlanetParams{};
          edited_.planet = name;
          edited_.table_sizes = scene_->params().table_sizes;
          request_tables();
        }
      ImGui::EndCombo();
    }
    char path[512];
    std::snprintf(path, sizeof path, "%s", planet_file_.c_str());
    if (ImGui::InputText("file", path, sizeof path)) planet_file_ = path;
    ImGui::SameLine();
    if (ImGui::Button("load") && !planet_file_.empty()) {
      edited_ = PlanetParams{};
      edited_.planet = planet_file_;
      edited_.table_sizes = scene_->params().table_sizes;
      request_tables();
    }
    char save_path[512];
    std::snprintf(save_path, sizeof save_path, "%s", save_file_.c_str());
    if (ImGui::InputText("save as", save_path, sizeof save_path)) save_file_ = save_path;
    ImGui::SameLine();
    if (ImGui::Button("save") && !save_file_.empty()) save_edited_planet(save_file_);
    // Each slider asks for new tables when it is released.
    const auto slider = [this](const char* parameter, const char* name) {
      float v = float(slider_value(name));
      if (parameter_slider(parameter, v)) set_slider(name, double(v));
      if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
    };
    const atmos::PlanetParameter& count = atmos::planet_parameter("wavelengths");
    int wavelengths = int(slider_value("wavelengths"));
    if (ImGui::SliderInt(count.label, &wavelengths, int(count.slider_min), int(count.slider_max)))
      set_slider("wavelengths", double(wavelengths));
    if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
    int orders = edited_.orders;
    if (ImGui::SliderInt("scattering orders", &orders, 1, 12)) set_slider("orders", double(orders));
    if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
    slider("density_scale", "density_scale");
    slider("ground_albedo", "ground_albedo");
    slider("bottom_radius", "bottom_radius_km");
    slider("atmosphere_thickness", "thickness_km");
    constituents_panel();
    if (job_->progress().busy) {
      progress_bar();
      ImGui::TextUnformatted(scene_->instant() ? "(the instant approximation is on screen)"
                                               : "(the old tables stay on screen)");
    } else if (last_swap_ms_ > 0.0) {
      ImGui::Text("last tables: %.2f s, swapped in %.0f ms", last_tables_s_, last_swap_ms_);
    }
  }
  if (!message_.empty()) {
    if (message_is_error_)
      ImGui::TextColored(ImVec4(1.0f, 0.45f, 0.4f, 1.0f), "%s", message_.c_str());
    else
      ImGui::TextUnformatted(message_.c_str());
  }
  ImGui::End();
}

// Stereo: the layout, the eyes' distance and the distance of zero
// disparity (the screen's plane), each with its unit and range (those of
// atmos view's --ipd and --convergence; Ctrl+click types a value).
void Viewer::stereo_panel() {
  if (!ImGui::CollapsingHeader("Stereo", ImGuiTreeNodeFlags_DefaultOpen)) return;
  const char* modes[] = {"none", "side by side", "anaglyph (red-cyan)"};
  int mode = int(stereo_.mode);
  if (ImGui::Combo("stereo", &mode, modes, 3)) stereo_.mode = StereoSettings::Mode(mode);
  if (stereo_.mode == StereoSettings::Mode::none) return;
  float ipd = float(stereo_.interpupillary_m);
  if (ImGui::SliderFloat("eye distance", &ipd, 0.001f, 1e5f, "%.4g m", ImGuiSliderFlags_Logarithmic))
    set_slider("interpupillary_m", double(ipd));
  float convergence = float(std::min(stereo_.convergence_m, 1e7));
  if (ImGui::SliderFloat("convergence", &convergence, 0.1f, 1e7f, "%.4g m", ImGuiSliderFlags_Logarithmic))
    set_slider("convergence_m", double(convergence));
  // A point at infinity: ipd / convergence in tangent units (stereo.hpp).
  ImGui::TextDisabled("sky disparity %.1f px", stereo_.interpupillary_m / stereo_.convergence_m *
                                                   ImGui::GetIO().DisplaySize.y /
                                                   (2.0 * std::tan(0.5 * look_.fov_deg * kDegree)));
}

GLuint Viewer::render_frame(SceneFrame& sf, int width, int height, int& image_width) {
  image_width = width;
  if (stereo_.mode == StereoSettings::Mode::none) return scene_->render(sf);
  const bool side_by_side = stereo_.mode == StereoSettings::Mode::side_by_side;
  const int eye_width = side_by_side ? std::max(1, width / 2) : width;
  atmos::Camera head;
  head.position = sf.pose.position;
  head.forward = sf.pose.forward;
  head.up = sf.pose.up;
  head.fov_deg = sf.fov_deg;
  head.width = eye_width;
  head.height = height;
  const std::array<atmos::Eye, 2> eyes =
      atmos::stereo_eyes(head, {stereo_.interpupillary_m, stereo_.convergence_m});
  sf.width = eye_width;
  const std::array<GLuint, 2> hdr = scene_->render_eyes(sf, eyes);
  if (!composer_) composer_ = std::make_unique<StereoComposer>();
  image_width = side_by_side ? 2 * eye_width : eye_width;
  return composer_->compose(side_by_side ? StereoComposer::Layout::side_by_side : StereoComposer::Layout::anaglyph,
                            hdr[0], hdr[1], eye_width, height);
}

// One tree node per constituent of the planet on screen: its scattering
// and absorption (factors on the file's coefficients), the scale height of
// an exponential profile and the asymmetry parameter of a non-Rayleigh
// phase function. Each asks for new tables when released.
void Viewer::constituents_panel() {
  const atmos::Atmosphere& a = scene_->planet();
  const auto edit = [this](size_t i) -> ConstituentEdit& {
    if (edited_.constituents.size() <= i) edited_.constituents.resize(i + 1);
    return edited_.constituents[i];
  };
  const auto current = [this](size_t i) {
    return i < edited_.constituents.size() ? edited_.constituents[i] : ConstituentEdit{};
  };
  for (size_t i = 0; i < a.constituents.size(); ++i) {
    const atmos::Constituent& c = a.constituents[i];
    ImGui::PushID(int(i));
    if (ImGui::TreeNode("constituent", "constituent: %s", c.name.c_str())) {
      const ConstituentEdit now = current(i);
      float scattering = float(now.scattering_scale.value_or(1.0));
      if (parameter_slider("constituents[].scattering_scale", scattering)) edit(i).scattering_scale = double(scattering);
      if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
      float absorption = float(now.absorption_scale.value_or(1.0));
      if (parameter_slider("constituents[].absorption_scale", absorption)) edit(i).absorption_scale = double(absorption);
      if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
      if (c.density.kind == atmos::DensityProfile::Kind::exponential) {
        float height_km = float(now.scale_height_m.value_or(c.density.scale_height_m) * 1e-3);
        if (parameter_slider("constituents[].density.scale_height", height_km))
          edit(i).scale_height_m = double(height_km) * 1e3;
        if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
      } else {
        ImGui::TextDisabled("density: piecewise linear profile");
      }
      if (c.phase.kind != atmos::PhaseFunction::Kind::rayleigh) {
        float g = float(now.phase_g.value_or(c.phase.g.at(550.0)));
        if (parameter_slider("constituents[].phase_function.g", g)) edit(i).phase_g = double(g);
        if (ImGui::IsItemDeactivatedAfterEdit()) request_tables();
      }
      ImGui::TreePop();
    }
    ImGui::PopID();
  }
}

void Viewer::progress_bar() {
  const TableJob::Progress p = job_->progress();
  if (p.fraction >= 0.0) {
    ImGui::ProgressBar(float(p.fraction), ImVec2(-1, 0), p.step.c_str());
  } else {
    // No fraction (a cache look-up, the shaders' compilation): a bar that
    // sweeps while the thread works.
    const double phase = std::fmod(p.elapsed_s, 1.5) / 1.5;
    ImGui::ProgressBar(float(phase), ImVec2(-1, 0), p.step.empty() ? "loading the tables" : p.step.c_str());
  }
  ImGui::Text("new tables: %.1f s", p.elapsed_s);
}

void Viewer::loading_panel() {
  const ImVec2 size = ImGui::GetIO().DisplaySize;
  ImGui::SetNextWindowPos(ImVec2(size.x * 0.5f, size.y * 0.5f), ImGuiCond_Always, ImVec2(0.5f, 0.5f));
  ImGui::SetNextWindowSize(ImVec2(std::min(420.0f, size.x - 16.0f), 0), ImGuiCond_Always);
  // Its own name: ImGui keeps a window's place and size by its name, and
  // the panel's are its own.
  ImGui::Begin("atmos view: loading", nullptr, ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoMove);
  ImGui::Text("%s: its tables and shaders", o_.planet.planet.c_str());
  if (job_->progress().busy)
    progress_bar();
  else
    ImGui::TextUnformatted("compiling the shaders");
  ImGui::End();
}

void Viewer::write_screenshot(const std::string& path, GLuint hdr, int width, int height) {
  if (has_extension(path, ".exr")) {
    atmos::write_exr(read_hdr(hdr, width, height), path);
  } else {
    // The window as it is shown: the back buffer before the swap.
    atmos::DisplayImage image;
    image.width = width;
    image.height = height;
    image.rgb.resize(size_t(width) * size_t(height) * 3);
    glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
    glReadBuffer(GL_BACK);
    glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);
    glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    glReadPixels(0, 0, width, height, GL_RGB, GL_UNSIGNED_BYTE, image.rgb.data());
    flip_rows(image.rgb, width, height);
    atmos::write_png(image, path);
  }
  std::printf("screenshot: %s\n", path.c_str());
}

int Viewer::run() {
  const double run_start_s = now_s();
  std::optional<Script> script;
  if (!o_.script.empty()) script = Script::read(o_.script);
  // Bad parameters and planet files are reported before the window opens.
  (void)make_atmosphere(o_.planet);
  if (o_.globe) (void)atmos::load_surface(o_.planet.planet);

  Window window(o_.width, o_.height, true);
  window_ = window.window;
  shared_context_ = window.shared;
  Gui gui(window_);
  const bool regional = o_.globe && !o_.planet_albedo;
  // The precomputation keeps one core of two free for the frames.
  const int threads = std::max(1, int(std::thread::hardware_concurrency()) - 1);
  // The warm-up draws the new scene once, small, from the camera of the
  // latest frame, in a headless context on the job's thread (TableJob::WarmUp).
  const auto warm_up = [this, regional](const PlanetTables& tables) {
    SceneFrame sf;
    {
      std::lock_guard<std::mutex> lock(warm_mutex_);
      sf = warm_frame_;
    }
    sf.width = 64;
    sf.height = 36;
    sf.timed = false;
    const double start = now_s();
    const auto context = atmos::GlContext::create_headless();
    // The globe's programs do not depend on its relief: a flat one opens no
    // raster (GDAL and netCDF stay on the viewer's thread).
    PlanetTables flat = tables;
    flat.surface = atmos::PlanetSurface{};
    Scene scene(flat, o_.globe, regional, true, atmos::PassPrograms::none);
    sf.moons = place_moons(look_of_warm_frame(), sf.pose.position, sf.sun, scene.top_radius_m(), moon_of_date_);
    (void)scene.render(sf);
    glFinish();
    std::printf("shaders of the new tables compiled in %.2f s\n", now_s() - start);
    std::fflush(stdout);
  };
  job_ = std::make_unique<TableJob>(o_.cache, o_.globe, regional, threads, warm_up, o_.instant_preview);
  // Destroyed before the window (the GL objects need its context): the
  // job's thread has no GL, but the scene and the post-processing do.
  struct Release {
    Viewer& v;
    ~Release() {
      if (v.jump_linker_.joinable()) v.jump_linker_.join();  // it links for the scene's pass
      v.job_.reset();
      v.next_scene_.reset();
      v.scene_.reset();
      v.post_.reset();
      v.composer_.reset();
    }
  } release{*this};

  // The first tables come from the job too, so that the window shows their
  // progress from its first frame; their programs are compiled here (the
  // warm-up would only compile them twice: nothing is on screen yet).
  job_->request(o_.planet, false);
  std::optional<PlanetTables> first;
  for (int shown = 0; !first || shown < 2; ++shown) {
    if (glfwWindowShouldClose(window_)) return 0;
    if (std::optional<std::string> error = job_->take_error()) throw atmos::Error(*error);
    // Once the tables are there, one more frame says what the wait is for.
    if (!first) {
      first = job_->take_result();
      shown = 0;
    }
    glfwWaitEventsTimeout(0.05);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();
    loading_panel();
    ImGui::Render();
    int width = 0, height = 0;
    glfwGetFramebufferSize(window_, &width, &height);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glViewport(0, 0, width, height);
    glClearColor(0.0f, 0.0f, 0.0f, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);
    ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
    glfwSwapBuffers(window_);
  }
  std::printf("tables: %s in %.2f s\n", first->status.c_str(), first->seconds);
  edited_ = o_.planet;
  look_ = o_.look;
  stereo_ = o_.stereo;
  record_.globe = o_.globe;
  record_.planet_albedo = o_.planet_albedo;
  // The first frame's pass programs alone are linked before it: on a
  // thread of the scene's in the hidden shared context from the moment the
  // pass exists (while this thread builds the globe), and here for the
  // camera on the globe. Where no context could be shared, here alone.
  int first_width = 0, first_height = 0;
  glfwGetFramebufferSize(window_, &first_width, &first_height);
  first_width = std::max(first_width, 1);
  first_height = std::max(first_height, 1);
  place_camera(*first);
  std::optional<Scene::EarlyLink> early;
  if (shared_context_) {
    GLFWwindow* shared = shared_context_;
    early = Scene::EarlyLink{[shared](bool current) { glfwMakeContextCurrent(current ? shared : nullptr); },
                             scene_frame(first_width, first_height, first->planet.top_radius_m)};
  }
  scene_ = std::make_unique<Scene>(*first, o_.globe, regional, o_.frames > 0, atmos::PassPrograms::none,
                                   early ? &*early : nullptr);
  place_camera(*first);
  scene_->link_programs(scene_frame(first_width, first_height, scene_->top_radius_m()));
  scene_->join_linker();
  post_ = std::make_unique<atmos::PostProcess>();

  GLuint blit = 0;
  glCreateFramebuffers(1, &blit);
  struct BlitRelease {
    GLuint& fb;
    ~BlitRelease() { glDeleteFramebuffers(1, &fb); }
  } blit_release{blit};

  start_s_ = now_s();
  double previous_s = start_s_;
  // Scripted sessions advance the flight by a fixed step, so that the
  // same script flies the same path on any machine.
  constexpr double kScriptStepS = 1.0 / 30.0;
  // A script runs past its last event (or --frames, if more), then on
  // until the tables it asked for are swapped in (at most three minutes
  // more), so that the swap is measured.
  const int frames = std::max(o_.frames, script ? script->length() + 1 : 0);
  constexpr double kMaxWaitForTablesS = 180.0;
  double waited_from = -1.0;
  int settle_until = 0;  // a scripted session runs up to this frame after a swap
  bool first_linked = false;  // the first frame's programs, linked before it
  for (int frame = 0; !glfwWindowShouldClose(window_); ++frame) {
    if (frames > 0 && frame >= frames) {
      if (!script || (!awaiting_tables_ && !swap_pending() && frame >= settle_until)) break;
      if (waited_from < 0.0) waited_from = now_s();
      if (now_s() - waited_from > kMaxWaitForTablesS) break;
    }
    const double frame_start = now_s();
    const double dt = frame == 0 ? 0.0 : frame_start - previous_s;
    previous_s = frame_start;
    glfwPollEvents();
    // The frame's size, before the input: a jump prepares its view at it.
    int width = 0, height = 0;
    glfwGetFramebufferSize(window_, &width, &height);
    ImGui_ImplOpenGL3_NewFrame();
    ImGui_ImplGlfw_NewFrame();
    ImGui::NewFrame();

    // New tables: swapped in on this thread, the GL context's.
    bool swapped = false;
    if (swap_pending()) {
      if (swap_ready()) {
        try {
          finish_swap(frame);
        } catch (const std::exception& e) {
          next_scene_.reset();
          message_ = e.what();
          message_is_error_ = true;
          edited_ = scene_->params();
        }
        swapped = true;
        settle_until = frame + 1 + kFramesAfterSwap;
      }
    } else if (std::optional<PlanetTables> t = pending_jump_ == 0 ? job_->take_result() : std::nullopt) {
      try {
        swap_scene(std::move(*t));
        message_.clear();
      } catch (const std::exception& e) {
        message_ = e.what();
        message_is_error_ = true;
        edited_ = scene_->params();
      }
      swapped = true;
      awaiting_tables_ = job_->progress().busy;
      settle_until = frame + 2 + kFramesAfterSwap;
    }
    if (std::optional<std::string> error = job_->take_error()) {
      awaiting_tables_ = job_->progress().busy;
      message_ = *error;
      message_is_error_ = true;
      edited_ = scene_->params();
      std::fprintf(stderr, "atmos: error: %s\n", error->c_str());
    }

    FlightInput input;
    bool dragging = false;
    if (script) {
      input = script->input(frame);
      for (const ScriptEvent& e : script->events) {
        if (frame < e.frame || frame >= e.frame + e.frames) continue;
        if (e.kind == ScriptEvent::Kind::slider) {
          const double t = e.frames > 1 ? double(frame - e.frame) / double(e.frames - 1) : 1.0;
          set_slider(e.slider, e.from + (e.to - e.from) * t);
          if (is_planet_slider(e.slider) && frame == e.frame + e.frames - 1) request_tables();
        } else if (e.kind == ScriptEvent::Kind::planet && frame == e.frame) {
          edited_ = PlanetParams{};
          edited_.planet = e.planet;
          edited_.table_sizes = o_.planet.table_sizes;
          request_tables();
        } else if (e.kind == ScriptEvent::Kind::save && frame == e.frame) {
          save_edited_planet(e.save);
        }
      }
      dragging = script->dragging(frame);
      if (input.jump != jump_none && prepare_jump(input.jump, width, height, true)) input.jump = jump_none;
      flight_->update(input, frame == 0 ? 0.0 : kScriptStepS, ground());
    } else {
      input = window_input();
      if (input.jump == jump_none) input.jump = std::exchange(requested_jump_, 0);
      if (input.jump != jump_none && prepare_jump(input.jump, width, height, false)) input.jump = jump_none;
      if (pending_jump_ != 0 && !jump_linking_.load()) finish_jump();
      flight_->update(input, dt, ground());
    }
    if (o_.ui) panel();
    if (!script) dragging = ImGui::IsAnyItemActive();

    GLuint hdr = 0;
    bool recorded = false;
    if (width > 0 && height > 0) {
      SceneFrame sf = scene_frame(width, height, scene_->top_radius_m());
      if (frame == 0) first_linked = scene_->programs_linked(sf);
      int image_width = width;
      hdr = render_frame(sf, width, height, image_width);
      {
        std::lock_guard<std::mutex> lock(warm_mutex_);
        warm_frame_ = sf;
        warm_look_ = look_;
      }
      atmos::PostInput pin;
      pin.colour = hdr;
      pin.width = image_width;
      pin.height = height;
      pin.nits_per_unit = Scene::kNitsPerUnit;
      pin.dt_s = frame == 0 ? 0.0 : (script ? kScriptStepS : dt);
      pin.timed = timed_;
      const GLuint ldr = post_->process(pin, post_settings(look_));
      glNamedFramebufferTexture(blit, GL_COLOR_ATTACHMENT0, ldr, 0);
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      if (image_width != width) {
        const float black[4] = {0, 0, 0, 1};
        glClearNamedFramebufferfv(0, GL_COLOR, 0, black);
      }
      glBlitNamedFramebuffer(blit, 0, 0, 0, image_width, height, 0, 0, image_width, height, GL_COLOR_BUFFER_BIT,
                             GL_NEAREST);
      glViewport(0, 0, width, height);
      ImGui::Render();
      ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
      const bool last =
          frames > 0 && frame >= frames - 1 &&
          !(script && (awaiting_tables_ || swap_pending() || frame + 1 < settle_until));
      if (last)
        for (const std::string& path : o_.screenshots)
          write_screenshot(path, hdr, has_extension(path, ".exr") ? image_width : width, height);

      FrameRecord fr;
      fr.time_s = script ? frame * kScriptStepS : frame_start - start_s_;
      fr.pose = sf.pose;
      fr.sun = sun_;
      fr.moon_of_date_m = moon_of_date_;
      fr.look = look_;
      fr.planet = scene_->params();
      record_.frames.push_back(fr);
      recorded = true;
      record_.width = width;
      record_.height = height;
    } else {
      ImGui::Render();
    }
    glfwSwapBuffers(window_);
    // The frame's time includes the GPU's work: on a software rasteriser
    // the swap waits for it.
    glFinish();
    const double frame_ms = (now_s() - frame_start) * 1e3;
    if (frame == 0) {
      std::printf("first frame: %.2f s after the start (programs linked beforehand: %s)\n", now_s() - run_start_s,
                  first_linked ? "yes" : "no");
      std::fflush(stdout);
    }
    log_.add(frame_ms, dragging, swapped);
    if (recorded) record_.frames.back().frame_ms = frame_ms;
    plot_.push_back(float(frame_ms));
    if (plot_.size() > 240) plot_.erase(plot_.begin());
  }

  const std::vector<double> steady = log_.steady();
  const double med = median(steady);
  std::printf("frames: %zu, median %.1f ms, max %.1f ms (first frame %.1f ms)\n", log_.ms.size(), med,
              steady.empty() ? 0.0 : *std::max_element(steady.begin(), steady.end()),
              log_.ms.empty() ? 0.0 : log_.ms.front());
  double drag_max = 0.0;
  size_t drag_frames = 0;
  for (size_t i = 1; i < log_.ms.size(); ++i)
    if (log_.dragging[i] && !log_.swapped[i]) {
      drag_max = std::max(drag_max, log_.ms[i]);
      ++drag_frames;
    }
  if (drag_frames > 0)
    std::printf("drag: %zu frames, max %.1f ms, max/median %.2f\n", drag_frames, drag_max, drag_max / med);
  const std::vector<double> swaps = log_.around_swaps(kFramesAfterSwap);
  if (!swaps.empty()) {
    const double swap_max = *std::max_element(swaps.begin(), swaps.end());
    std::printf("swap: %zu frames from the swaps on, max %.1f ms, swap max/median %.2f\n", swaps.size(), swap_max,
                swap_max / med);
  }
  const Flight::GroundHeight g = ground();
  std::printf("camera: altitude %.6g m, latitude %.6f, longitude %.6f, heading %.3f, pitch %.3f\n",
              flight_->altitude_m(g), flight_->latitude_deg(), flight_->longitude_deg(), flight_->heading_deg(),
              flight_->pitch_deg());
  if (!o_.record.empty()) {
    write_flight(record_, o_.record);
    std::printf("recorded %zu frames: %s\n", record_.frames.size(), o_.record.c_str());
  }
  return 0;
}

}  // namespace

int run_viewer(const ViewOptions& options) {
  Viewer viewer(options);
  return viewer.run();
}

int run_replay(const ViewOptions& o) {
  const FlightRecord record = read_flight(o.replay);
  if (o.frame_format != "png" && o.frame_format != "exr" && o.frame_format != "both")
    throw atmos::Error("frame format must be png, exr or both, got \"" + o.frame_format + "\"");
  std::filesystem::create_directories(o.output_dir);
  auto context = atmos::GlContext::create_headless();
  const bool regional = record.globe && !record.planet_albedo;
  std::unique_ptr<Scene> scene;
  std::unique_ptr<atmos::PostProcess> post = std::make_unique<atmos::PostProcess>();
  double previous_time = record.frames.front().time_s;
  for (size_t i = 0; i < record.frames.size(); ++i) {
    const FrameRecord& f = record.frames[i];
    if (!scene || !(scene->params() == f.planet)) {
      // Every tile is built before its frame: the images do not depend on
      // the machine's speed.
      scene.reset();
      const PlanetTables tables = load_planet_tables(f.planet, record.globe, regional, o.cache);
      scene = std::make_unique<Scene>(tables, record.globe, regional, true);
    }
    SceneFrame sf;
    sf.pose = f.pose;
    sf.fov_deg = f.look.fov_deg;
    sf.width = record.width;
    sf.height = record.height;
    sf.sun = glm::normalize(f.sun);
    sf.stars = f.look.stars || glm::dot(sf.sun, glm::normalize(f.pose.position)) < 0.0;
    sf.moons = place_moons(f.look, f.pose.position, sf.sun, scene->top_radius_m(), f.moon_of_date_m);
    const GLuint hdr = scene->render(sf);
    char name[64];
    std::snprintf(name, sizeof name, "frame-%05zu", i);
    const std::filesystem::path base = std::filesystem::path(o.output_dir) / name;
    if (o.frame_format != "png") atmos::write_exr(read_hdr(hdr, record.width, record.height), base.string() + ".exr");
    if (o.frame_format != "exr") {
      atmos::PostInput pin;
      pin.colour = hdr;
      pin.width = record.width;
      pin.height = record.height;
      pin.nits_per_unit = Scene::kNitsPerUnit;
      pin.dt_s = std::max(0.0, f.time_s - previous_time);
      const GLuint ldr = post->process(pin, post_settings(f.look));
      atmos::write_png(read_display(ldr, record.width, record.height), base.string() + ".png");
    }
    previous_time = f.time_s;
  }
  std::printf("replayed %zu frames into %s\n", record.frames.size(), o.output_dir.c_str());
  post.reset();
  scene.reset();
  return 0;
}

int run_headset(const ViewOptions& o) {
  const double run_start_s = now_s();
  // The provider first: no runtime, no headset or a bad mock file fail now,
  // before any window, context or tables.
  std::unique_ptr<OpenXrProvider> xr;
  std::unique_ptr<MockViewProvider> mock;
  if (o.xr)
    xr = make_openxr_provider();
  else
    mock = std::make_unique<MockViewProvider>(MockViewProvider::read(o.xr_mock));
  ViewProvider& provider = xr ? static_cast<ViewProvider&>(*xr) : *mock;
  (void)make_atmosphere(o.planet);
  if (o.globe) (void)atmos::load_surface(o.planet.planet);

  // OpenXR binds its session to a GLX context: a hidden window's. The mock
  // draws headless.
  std::unique_ptr<Window> window;
  std::unique_ptr<atmos::GlContext> context;
  if (xr) {
    window = std::make_unique<Window>(64, 64, false);
    xr->start();
  } else {
    context = atmos::GlContext::create_headless();
  }
  const bool regional = o.globe && !o.planet_albedo;
  const PlanetTables tables = load_planet_tables(o.planet, o.globe, regional, o.cache);
  std::printf("tables: %s in %.2f s\n", tables.status.c_str(), tables.seconds);
  // The mock's images do not depend on the machine's speed: every tile is
  // built before it is drawn. A headset streams them.
  auto scene = std::make_unique<Scene>(tables, o.globe, regional, mock != nullptr);
  auto post = std::make_unique<atmos::PostProcess>();
  Flight flight(scene->bottom_radius_m());
  const Flight::GroundHeight ground = [&scene](const glm::dvec3& p) { return scene->ground_height_m(p); };
  flight.place(o.latitude_deg, o.longitude_deg, o.altitude_m, o.heading_deg, o.pitch_deg, ground);
  SceneFrame sf;
  sf.pose = flight.pose();
  sf.sun = sun_from_angles(flight.position(), o.sun_azimuth_deg, o.sun_elevation_deg);
  sf.stars = o.look.stars || glm::dot(sf.sun, glm::normalize(sf.pose.position)) < 0.0;
  std::optional<glm::dvec3> moon_of_date;
  if (o.moon_of_date_m) moon_of_date = glm::normalize(flight.position()) * scene->bottom_radius_m() + *o.moon_of_date_m;
  sf.moons = place_moons(o.look, sf.pose.position, sf.sun, scene->top_radius_m(), moon_of_date);

  HeadsetRenderer headset;
  std::vector<double> ms;
  double previous = now_s();
  int frames = 0;
  while (o.frames == 0 || frames < o.frames) {
    const double start = now_s();
    if (!headset.frame(provider, *scene, *post, sf, post_settings(o.look), frames == 0 ? 0.0 : start - previous))
      break;
    glFinish();
    previous = start;
    ms.push_back((now_s() - start) * 1e3);
    if (frames == 0) std::printf("first frame: %.2f s after the start\n", now_s() - run_start_s);
    ++frames;
  }
  std::vector<double> steady(ms.size() > 1 ? ms.begin() + 1 : ms.end(), ms.end());
  std::printf("headset: %d frames of %dx%d per eye, median %.1f ms\n", frames, provider.eye_width(),
              provider.eye_height(), median(steady));
  if (mock && mock->frames_ended() > 0) {
    std::filesystem::create_directories(o.output_dir);
    const char* names[] = {"eye-left", "eye-right"};
    for (int i = 0; i < 2; ++i) {
      const std::filesystem::path base = std::filesystem::path(o.output_dir) / names[i];
      if (o.frame_format != "png") atmos::write_exr(mock->hdr(i), base.string() + ".exr");
      if (o.frame_format != "exr") atmos::write_png(mock->display(i), base.string() + ".png");
    }
    std::printf("eyes: %s/eye-left, eye-right\n", o.output_dir.c_str());
  }
  post.reset();
  scene.reset();
  return 0;
}

}  // namespace atmos_view
