#include "view_bench.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

namespace atmos_cli {

namespace {

// A word for the shell: single-quoted, its single quotes escaped.
std::string shell_word(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The standard output of `command` (its standard error discarded); ok is
// false when it could not be run or exited with an error.
std::string output_of(const std::string& command, bool& ok) {
  std::string out;
  FILE* pipe = popen((command + " 2>/dev/null").c_str(), "r");
  if (!pipe) {
    ok = false;
    return out;
  }
  std::array<char, 4096> buffer{};
  size_t n = 0;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), pipe)) > 0) out.append(buffer.data(), n);
  ok = pclose(pipe) == 0;
  return out;
}

// The number after `key` in the viewer's output (NaN if absent).
double figure_after(const std::string& out, const std::string& key) {
  const size_t at = out.find(key);
  if (at == std::string::npos) return std::nan("");
  return std::strtod(out.c_str() + at + key.size(), nullptr);
}

}  // namespace

void view_bench(const std::string& planet, const std::function<void(const atmos_bench::Figure&)>& sink) {
  std::error_code error;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) {
    std::fprintf(stderr, "atmos bench: no view.* lines (this executable's path is unknown)\n");
    return;
  }
  const char* display = std::getenv("DISPLAY");
  std::string window;
  if (!display || !*display) {
    if (std::system("command -v xvfb-run > /dev/null 2>&1") != 0) {
      std::fprintf(stderr, "atmos bench: no view.* lines (no display, and xvfb-run is not installed)\n");
      return;
    }
    window = "xvfb-run -a -s '-screen 0 1280x720x24' ";
  }
  const std::string view = window + shell_word(self.string()) + " view --planet " + shell_word(planet) +
                           " --width 1280 --height 720 ";
  // 2 m above the ground at the viewer's start, 40 frames: the median of
  // 39 (without the first, which compiles the programs).
  for (const char* surface : {"sphere", "globe"}) {
    bool ok = true;
    const std::string out = output_of(view + "--frames 40 --surface " + surface, ok);
    const double median = figure_after(out, "median ");
    if (!ok || !std::isfinite(median)) {
      std::fprintf(stderr, "atmos bench: atmos view --surface %s failed: no view.%s lines\n", surface, surface);
      continue;
    }
    sink({std::string("view.") + surface + ".median_frame", median, "ms"});
    sink({std::string("view.") + surface + ".fps", 1e3 / median, "fps"});
  }
  // Stereo: both eyes over the globe as a red-cyan anaglyph, each eye the
  // window's size (one tile selection, two draws of the terrain, two passes
  // of the plugin): against view.globe.median_frame, its cost.
  {
    bool ok = true;
    const std::string out = output_of(view + "--frames 40 --surface globe --stereo anaglyph", ok);
    const double median = figure_after(out, "median ");
    if (!ok || !std::isfinite(median)) {
      std::fprintf(stderr, "atmos bench: atmos view --stereo anaglyph failed: no view.stereo lines\n");
    } else {
      sink({"view.stereo.globe.anaglyph.median_frame", median, "ms"});
      sink({"view.stereo.globe.anaglyph.fps", 1e3 / median, "fps"});
    }
  }
  // The first frame as a session starts: a script of one frame that does
  // nothing, so that the globe streams its tiles as it does for a user
  // (--frames would build every tile the first frame needs before it).
  const std::filesystem::path script =
      std::filesystem::temp_directory_path() / ("atmos-view-bench-" + std::to_string(getpid()) + ".json");
  {
    std::ofstream(script) << R"({"events": [{"frame": 0, "mouse": [0, 0]}]})";
  }
  bool ok = true;
  const std::string out =
      output_of("MESA_SHADER_CACHE_DISABLE=true " + view + "--script " + shell_word(script.string()), ok);
  std::filesystem::remove(script, error);
  const double first = figure_after(out, "first frame: ");
  if (!ok || !std::isfinite(first)) {
    std::fprintf(stderr, "atmos bench: atmos view with a cold shader cache failed: no view.first_frame line\n");
    return;
  }
  sink({"view.first_frame.cold_shader_cache", first, "s"});
}

}  // namespace atmos_cli
