// atmos — camera-like output: bloom, exposure (manual or automatic with eye
// adaptation) and tone mapping of an HDR image on the GPU (Collienne 2013,
// §4.6; Boody n.d., §1.11). For the engine plugin's output (AtmospherePass::render)
// or any HDR texture; the CLI uses it for `atmos render --tonemap/--bloom/
// --auto-exposure`.
//
//   atmos::PostProcess post;                    // once, GL 4.5 context current
//   atmos::PostSettings settings;               // exp tone map at EV 13, no bloom
//   settings.tone_mapping = atmos::ToneMapping::filmic;
//   settings.bloom.strength = 0.05;
//   settings.auto_exposure.enabled = true;
//   atmos::PostInput in{hdr_texture, width, height};
//   in.nits_per_unit = 1.0;                     // the plugin's FrameInput::nits_per_unit
//   in.dt_s = frame_seconds;                    // for the eye adaptation
//   GLuint ldr = post.process(in, settings);    // RGBA8, sRGB-encoded display values
//
// Units. The input holds linear sRGB (the plugin's and the renderer's
// colour space); a texel times nits_per_unit is in cd/m² (luminance by
// Collienne 2013, eq. 4.27). Exposure is an exposure value at ISO 100 (EV100) with
// the definition of write_png (below): a pixel of L cd/m² is exposed to
// x = L / L_sat, L_sat = 1.2 * 2^EV cd/m². The formulas are in
// src/post/tone_mapping.glsl, compiled both for the GPU and the CPU.
//
// OpenGL context: the rule of Renderer (renderer.hpp). Construct, use and
// destroy with the same OpenGL 4.5 core context current; the constructor
// throws atmos::Error without one. process() changes the bound program, texture unit 0,
// image units 0-2, shader storage bindings 0-1 and the pixel pack/unpack
// alignment; it restores none of them.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "atmos/image.hpp"

namespace atmos {

// Tone-mapping operators. Each maps an exposed value x per channel to a
// display value in [0, 1]:
enum class ToneMapping {
  // 1 - exp(-x) (Boody n.d., §1.11; Elek & Kmoch 2010): what write_png does; tends to 1.
  exp,
  // Bruneton's variant of Reinhard (Collienne 2013, eq. 4.25-4.26):
  // (0.38317 x)^(1/2.2) for x < 1.413, 1 - exp(-x) above; tends to 1. Includes
  // the display gamma (2.2).
  reinhard,
  // Hejl / Burgess-Dawson (Collienne 2013, eq. 4.29):
  // x (6.2 x + 0.5) / (x (6.2 x + 1.7) + 0.06); tends to 1. Includes the
  // display gamma (2.2).
  filmic,
  // Narkowicz's ACES fit (2016): x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14),
  // reaches 1 at x = 7.24.
  aces,
  // x itself (for engines with their own tone mapping; clamped in 8-bit output).
  linear,
};

// "exp", "reinhard", "filmic", "aces", "linear"; parse_tone_mapping throws
// atmos::Error for other names.
const char* tone_mapping_name(ToneMapping op);
ToneMapping parse_tone_mapping(const std::string& name);

// Glare: the part of each pixel above `threshold` is spread over the image
// by a mip pyramid of Gaussians (widths ~4 to ~2^(levels+1) pixels) and
// `strength` of it replaces the same fraction of the sharp image: light is
// moved, not added (the total is conserved up to float rounding, borders
// included, and a uniform image stays uniform: tests/post_test.cpp).
struct BloomSettings {
  double strength = 0.0;   // fraction of the bright light that is spread, [0, 1]; 0: no bloom (no GPU work)
  double threshold = 1.0;  // exposed luminance x above which light blooms (1: the saturation luminance); >= 0
};

// Exposure from the frame itself: the log-average luminance l_avg of the
// input (Collienne 2013, eq. 4.27 per pixel, averaged as
// exp(mean(log(1e-4 + l)))) is exposed to `key` (eq. 4.28), EV_target = log2(l_avg /
// (1.2 key)) - compensation_ev clamped to [min_ev, max_ev], and the exposure
// follows EV_target with exp(-dt / tau) per frame: tau = brightening_tau_s
// when the scene got brighter, darkening_tau_s when it got darker. The first
// frame after construction or reset() is exposed at its target directly.
// With bloom, the bloom's bright pass measures the frame as it reads it and
// so thresholds at the exposure the frame starts from (the previous frame's;
// the first frame after construction or reset() at its own): docs/post.md.
struct AutoExposureSettings {
  bool enabled = false;       // false: PostSettings::exposure_ev
  double key = 0.27818;       // exposed log-average luminance, 1 / (2^2.2 - 1) (Collienne 2013, eq. 4.28); > 0
  double compensation_ev = 0;  // EV added to the image's brightness (+1: twice as bright)
  double min_ev = -6.0;       // EV100 range the exposure is clamped to (starlit ... beyond sunlit snow)
  double max_ev = 18.0;
  double brightening_tau_s = 0.5;  // time constant (s) when the scene gets brighter (light adaptation); >= 0
  double darkening_tau_s = 2.0;    // time constant (s) when the scene gets darker (dark adaptation); >= 0
};

enum class PostOutputFormat {
  srgb8,         // GL_RGBA8 holding sRGB-encoded display values (ready for a PNG or an sRGB view)
  linear_half,   // GL_RGBA16F, display-linear values
  linear_float,  // GL_RGBA32F, display-linear values
};

struct PostSettings {
  ToneMapping tone_mapping = ToneMapping::exp;
  double exposure_ev = 13.0;  // EV100 when auto exposure is off (write_png's --exposure)
  BloomSettings bloom;
  AutoExposureSettings auto_exposure;
  PostOutputFormat output_format = PostOutputFormat::srgb8;
};

// One frame.
struct PostInput {
  std::uint32_t colour = 0;  // GL texture name: 2D, linear sRGB, width x height at level 0 (any float format)
  int width = 0;
  int height = 0;
  double nits_per_unit = 1.0;  // cd/m² per unit of `colour`; > 0
  double dt_s = 0.0;           // seconds since the previous frame (eye adaptation); >= 0
  // Measure the passes' GPU time (last_timings()); waits for the GPU.
  bool timed = false;
  // Where to write: a 2D texture of width x height with the internal format
  // of PostSettings::output_format, owned by the caller; 0: a texture of the
  // PostProcess (valid until the next process() or its destruction).
  std::uint32_t output = 0;
};

// GPU time of the last process() with PostInput::timed, milliseconds (wall
// clock up to glFinish on software rasterisers, like PassTimings); zero for
// untimed frames and for passes that did not run.
struct PostTimings {
  // Bright pass, pyramid, blurs; with auto exposure after the first frame
  // also the log-average reduction (done by the bright pass).
  double bloom_ms = 0.0;
  double exposure_ms = 0.0;  // log-average reduction (unless the bloom did it) and adaptation (auto exposure)
  double tone_map_ms = 0.0;  // bloom composite, exposure, operator, encoding
  double total_ms() const { return bloom_ms + exposure_ms + tone_map_ms; }
};

class PostProcess {
 public:
  // Compiles the passes in the CURRENT OpenGL 4.5 context. Throws atmos::Error.
  PostProcess();
  ~PostProcess();
  PostProcess(const PostProcess&) = delete;
  PostProcess& operator=(const PostProcess&) = delete;

  // Processes one frame; returns the texture written. Throws atmos::Error
  // (one line, nothing drawn) on invalid settings or input: NaN or infinite
  // values, bloom strength outside [0, 1], a negative threshold, time
  // constant or dt, key <= 0, min_ev > max_ev, nits_per_unit <= 0, a zero
  // size, a missing or mismatched texture.
  std::uint32_t process(const PostInput& input, const PostSettings& settings);

  // Convenience for tools: uploads `hdr` (cd/m², nits_per_unit 1), processes
  // it (settings.output_format must be srgb8) and reads the display image back.
  DisplayImage process_image(const Image& hdr, const PostSettings& settings, double dt_s = 0.0);

  // Forgets the eye adaptation: the next auto-exposed frame starts at its target.
  void reset();
  // The EV100 the last process() exposed at (with auto exposure: the adapted
  // value); NaN before the first frame and after reset(). Reads from the GPU.
  double current_exposure_ev() const;
  // The log-average luminance (cd/m²) measured in the last auto-exposed
  // frame; NaN if none since the last reset(). Reads from the GPU.
  double last_log_average_luminance() const;

  const PostTimings& last_timings() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

// 8-bit sRGB PNG. Each channel L (cd/m²) is exposed and tone mapped as
//   display = 1 - exp(-L / L_sat),  L_sat = 1.2 * 2^exposure_ev,
// where L_sat is the saturation luminance of a camera at exposure value
// `exposure_ev` (EV100; 78 / (100 * 0.65) = 1.2), then clamped to [0, 1] and
// encoded with the sRGB OETF (IEC 61966-2-1). Throws atmos::Error like write_exr.
void write_png(const Image& image, const std::string& path, double exposure_ev);

// write_png or write_exr by the extension of `path` (.png / .exr, any case);
// any other extension throws atmos::Error "unsupported output format ...".
// `exposure_ev` is used by PNG only.
void write_image(const Image& image, const std::string& path, double exposure_ev);

// Reads an srgb8 result back (row y of the texture is row y of the image,
// as the upload in process_image writes it). Throws atmos::Error.
DisplayImage read_display_image(std::uint32_t texture, int width, int height);
// Reads a float result (linear_half / linear_float) back as RGB.
Image read_linear_image(std::uint32_t texture, int width, int height);

}  // namespace atmos
