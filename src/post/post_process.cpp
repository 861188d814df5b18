// PostProcess: bloom, exposure and tone mapping on the GPU (include/atmos/post.hpp).
//
// A frame is a handful of compute dispatches:
//   exposure  (auto exposure only) reduce: log luminance summed per column
//             strip of kReduceRows pixels; adapt: one work group adds the
//             sums, EV target and adaptation into the ExposureState buffer
//             (manual exposure: the CPU writes the EV there instead, so the
//             other passes read it the same way);
//   bloom     (strength > 0 only) bright pass + tent to level 1, tent down to
//             level K, then from K up to 1: horizontal Gaussian, vertical
//             Gaussian mixed with the upsampled coarser level;
//   tone map  bloom composite, exposure, operator, encoding, one pass.
// The full-resolution input is read twice: with auto exposure and bloom the
// bright pass also does the reduction (then adapt runs after it; the first
// frame after a reset reduces first, bloom.comp.glsl), and the tone map.
// The formulas are in tone_mapping.glsl (shared with the CPU), the kernels
// in the *.comp.glsl files next to this one; they compute blocks of outputs
// per invocation (post_common.comp.glsl), hence the block sides in the
// dispatch sizes below.
#include "atmos/post.hpp"

#include <epoxy/gl.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "gpu/gl_util.hpp"
#include "gpu/shader_source.hpp"
#include "data/embedded_files.hpp"
#include "physics/checks.hpp"
#include "post/tone_mapping_cpp.hpp"

namespace atmos {

namespace {

// The bloom pyramid: at most 6 levels below the input (1920 x 1080: 961 x 541
// down to 31 x 18), none with a side below 8 texels. Each level is blurred by
// a Gaussian of 2 of its texels (13 taps), i.e. about 2^(k+1) input pixels at
// level k, and mixed half and half with the coarser levels: level k carries
// 2^-k of the bloom (the coarsest the rest), a heavy-tailed point spread like
// the eye's and a lens's glare.
constexpr int kMaxBloomLevels = 6;
constexpr int kMinBloomLevelSide = 8;
constexpr float kBloomSigma = 2.0f;
constexpr int kBloomRadius = 6;  // 3 sigma: the kernel is truncated there and renormalised
constexpr float kCoarserWeight = 0.5f;

// Work-group sides of the kernels (the local sizes in the shaders) and the
// blocks of outputs each invocation computes (DOWN_BLOCK, BLUR_BLOCK in
// bloom.comp.glsl, the 2 x 2 pixels of tone_map.comp.glsl).
constexpr int kGroup = 8;
constexpr int kDownBlock = 2;  // fixed by the 5 x 5 reads of bloom.comp.glsl
constexpr int kBlurBlock = 4;
constexpr int kToneMapBlock = 2;
// The reduction: work groups of 64 columns, each invocation summing a
// column strip of kReduceRows pixels.
constexpr int kReduceColumns = 64;
constexpr int kReduceRows = 32;

const char* embedded(const char* path) {
  const char* text = data::embedded_file(path);
  if (text == nullptr) throw Error(std::string("shader source not embedded in this build: ") + path);
  return text;
}

// "#version", the defines of the variant, the shared formulas (with the
// GLSL meaning of the subset's INLINE), the declarations of post_common and
// the stage's file.
gpu::AssembledSource compute_source(const std::string& defines, const char* stage_path, const char* stage_name) {
  gpu::AssembledSource s;
  s.append("header", "#version 450 core\n" + defines);
  s.append("macros", "#define INLINE\n");
  s.append("tone_mapping.glsl", embedded("src/post/tone_mapping.glsl"));
  s.append("post_common.comp.glsl", embedded("src/post/post_common.comp.glsl"));
  s.append(stage_name, embedded(stage_path));
  return s;
}

// "float[n + 1](k_0, ..., k_n)": the Gaussian of `sigma` texels truncated at
// `radius` taps each side, normalised so that its 2 radius + 1 taps sum to 1.
// The weights come from Turkowski's incremental Gaussian (Turkowski 2007;
// Collienne 2013, §4.6.1; tone_mapping.glsl: one exp, then products),
// evaluated once here with the shared code instead of in every invocation.
std::string bloom_kernel(float sigma, int radius) {
  std::vector<double> g;
  glm::vec3 state = post::incremental_gaussian_start(sigma);
  double sum = 0.0;
  for (int k = 0; k <= radius; ++k) {
    g.push_back(double(state.x));
    sum += (k == 0 ? 1.0 : 2.0) * double(state.x);
    state = post::incremental_gaussian_next(state);
  }
  std::string s = "float[" + std::to_string(radius + 1) + "](";
  for (int k = 0; k <= radius; ++k) s += (k > 0 ? ", " : "") + gpu::glsl_float(float(g[size_t(k)] / sum));
  return s + ")";
}

GLuint bloom_program(const std::string& stage_defines) {
  return gpu::link_compute_program(compute_source(stage_defines + "#define BLOOM_RADIUS " +
                                                      std::to_string(kBloomRadius) + "\n#define BLOOM_KERNEL " +
                                                      bloom_kernel(kBloomSigma, kBloomRadius) + "\n",
                                                  "src/post/bloom.comp.glsl", "bloom.comp.glsl"));
}

GLenum internal_format(PostOutputFormat f) {
  switch (f) {
    case PostOutputFormat::linear_half: return GL_RGBA16F;
    case PostOutputFormat::linear_float: return GL_RGBA32F;
    case PostOutputFormat::srgb8: break;
  }
  return GL_RGBA8;
}

const char* image_format_qualifier(PostOutputFormat f) {
  switch (f) {
    case PostOutputFormat::linear_half: return "rgba16f";
    case PostOutputFormat::linear_float: return "rgba32f";
    case PostOutputFormat::srgb8: break;
  }
  return "rgba8";
}

int tone_map_constant(ToneMapping op) {
  switch (op) {
    case ToneMapping::exp: return post::TONE_MAP_EXP;
    case ToneMapping::reinhard: return post::TONE_MAP_REINHARD;
    case ToneMapping::filmic: return post::TONE_MAP_FILMIC;
    case ToneMapping::aces: return post::TONE_MAP_ACES;
    case ToneMapping::linear: return post::TONE_MAP_LINEAR;
  }
  throw Error("post-process: unknown tone-mapping operator " + std::to_string(int(op)));
}

void require(bool ok, const std::string& message) {
  if (!ok) throw Error("post-process: " + message);
}

void require_finite(double v, const char* name) {
  require(std::isfinite(v), std::string(name) + " must be a finite number (got " + number_text(v) + ")");
}

void validate(const PostSettings& s) {
  (void)tone_map_constant(s.tone_mapping);
  require(s.output_format == PostOutputFormat::srgb8 || s.output_format == PostOutputFormat::linear_half ||
              s.output_format == PostOutputFormat::linear_float,
          "unknown output format " + std::to_string(int(s.output_format)));
  require_finite(s.exposure_ev, "exposure_ev");
  require_finite(s.bloom.strength, "bloom strength");
  require(s.bloom.strength >= 0.0 && s.bloom.strength <= 1.0,
          "bloom strength must be in [0, 1] (got " + number_text(s.bloom.strength) + ")");
  require_finite(s.bloom.threshold, "bloom threshold");
  require(s.bloom.threshold >= 0.0, "bloom threshold must be >= 0 (got " + number_text(s.bloom.threshold) + ")");
  const AutoExposureSettings& a = s.auto_exposure;
  require_finite(a.key, "auto-exposure key");
  require(a.key > 0.0, "auto-exposure key must be > 0 (got " + number_text(a.key) + ")");
  require_finite(a.compensation_ev, "exposure compensation");
  require_finite(a.min_ev, "auto-exposure min_ev");
  require_finite(a.max_ev, "auto-exposure max_ev");
  require(a.min_ev <= a.max_ev,
          "auto-exposure min_ev (" + number_text(a.min_ev) + ") is above max_ev (" + number_text(a.max_ev) + ")");
  require_finite(a.brightening_tau_s, "brightening time constant");
  require_finite(a.darkening_tau_s, "darkening time constant");
  require(a.brightening_tau_s >= 0.0 && a.darkening_tau_s >= 0.0,
          "adaptation time constants must be >= 0 s (got " + number_text(a.brightening_tau_s) + ", " +
              number_text(a.darkening_tau_s) + ")");
}

// A 2D texture of at least level 0 = width x height; returns its internal format.
GLint check_texture(std::uint32_t texture, int width, int height, const char* what) {
  require(texture != 0, std::string(what) + " texture is 0");
  require(glIsTexture(texture) == GL_TRUE, std::string(what) + " texture " + std::to_string(texture) +
                                               " is not a texture name of the current context");
  GLint target = 0, w = 0, h = 0, format = 0;
  glGetTextureParameteriv(texture, GL_TEXTURE_TARGET, &target);
  require(target == GL_TEXTURE_2D, std::string(what) + " texture " + std::to_string(texture) + " is not a 2D texture");
  glGetTextureLevelParameteriv(texture, 0, GL_TEXTURE_WIDTH, &w);
  glGetTextureLevelParameteriv(texture, 0, GL_TEXTURE_HEIGHT, &h);
  glGetTextureLevelParameteriv(texture, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
  require(w == width && h == height, std::string(what) + " texture is " + std::to_string(w) + "x" +
                                         std::to_string(h) + ", expected " + std::to_string(width) + "x" +
                                         std::to_string(height));
  return format;
}

GLuint make_storage(GLenum format, int width, int height) {
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  glTextureStorage2D(texture, 1, format, width, height);
  glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  return texture;
}

GLuint groups(int n, int side) { return GLuint((n + side - 1) / side); }

// The layout of ExposureState in post_common.comp.glsl (std430).
struct ExposureState {
  float frame_ev;
  float adapted_ev;
  float log_average_luminance;
  std::int32_t initialized;
  float bloom_ev;
};

}  // namespace

const char* tone_mapping_name(ToneMapping op) {
  switch (op) {
    case ToneMapping::exp: return "exp";
    case ToneMapping::reinhard: return "reinhard";
    case ToneMapping::filmic: return "filmic";
    case ToneMapping::aces: return "aces";
    case ToneMapping::linear: return "linear";
  }
  return "unknown";
}

ToneMapping parse_tone_mapping(const std::string& name) {
  for (ToneMapping op :
       {ToneMapping::exp, ToneMapping::reinhard, ToneMapping::filmic, ToneMapping::aces, ToneMapping::linear})
    if (name == tone_mapping_name(op)) return op;
  throw Error("unknown tone-mapping operator \"" + name + "\" (expected exp, reinhard, filmic, aces or linear)");
}

struct PostProcess::Impl {
  GLuint reduce_program = 0;
  GLuint adapt_program = 0;
  GLuint bright_program = 0;
  GLuint bright_reduce_program = 0;  // the bright pass that also does the exposure's reduction
  GLuint downsample_program = 0;
  GLuint blur_x_program = 0;
  GLuint blur_y_program = 0;        // the coarsest level
  GLuint blur_y_mix_program = 0;    // the others: mixed with the coarser level
  std::map<int, GLuint> tone_map_programs;  // by tone_map_key
  GLuint sampler = 0;               // GL_NEAREST: texelFetch of any input, mipmapped or not
  GLuint state_buffer = 0;          // ExposureState
  GLuint partial_buffer = 0;        // one float per reduction strip
  int partial_capacity = 0;

  // The pyramid for the current input size: level k (1..K) and its
  // horizontal-blur temporary (RGBA32F: colour and the texel's weight,
  // post_common.comp.glsl; on llvmpipe 16-bit formats read no faster, and
  // would keep only 11 significant bits of the light balance).
  int pyramid_width = 0, pyramid_height = 0;
  std::vector<int> level_width, level_height;
  std::vector<GLuint> level, temporary;

  GLuint output = 0;
  int output_width = 0, output_height = 0;
  PostOutputFormat output_format = PostOutputFormat::srgb8;

  GLuint upload = 0;  // process_image's input
  int upload_width = 0, upload_height = 0;

  bool have_frame = false;
  // An auto-exposed frame ran since construction or reset(): the GPU state
  // holds an adapted exposure (ExposureState::initialized).
  bool adaptation_started = false;
  PostTimings timings;
  gpu::GpuTimer timer;

  Impl() {
    reduce_program = gpu::link_compute_program(
        compute_source("#define STAGE_REDUCE\n#define REDUCE_ROWS " + std::to_string(kReduceRows) + "\n",
                       "src/post/exposure.comp.glsl", "exposure.comp.glsl"));
    adapt_program = gpu::link_compute_program(
        compute_source("#define STAGE_ADAPT\n", "src/post/exposure.comp.glsl", "exposure.comp.glsl"));
    bright_program = bloom_program("#define STAGE_BRIGHT\n");
    bright_reduce_program = bloom_program("#define STAGE_BRIGHT\n#define WITH_REDUCTION\n");
    downsample_program = bloom_program("#define STAGE_DOWNSAMPLE\n");
    blur_x_program = bloom_program("#define STAGE_BLUR_X\n");
    blur_y_program = bloom_program("#define STAGE_BLUR_Y\n");
    blur_y_mix_program = bloom_program("#define STAGE_BLUR_Y\n#define HAS_COARSER\n");
    glCreateSamplers(1, &sampler);
    glSamplerParameteri(sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glSamplerParameteri(sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glCreateBuffers(1, &state_buffer);
    const ExposureState initial{0.0f, 0.0f, 0.0f, 0, 0.0f};
    glNamedBufferData(state_buffer, sizeof initial, &initial, GL_DYNAMIC_DRAW);
    gpu::check_gl("creating the post-processing passes");
  }

  // False when destroyed without a current context: the objects die with it.
  bool delete_gl_objects = true;

  ~Impl() {
    if (!delete_gl_objects) return;
    for (GLuint p : {reduce_program, adapt_program, bright_program, bright_reduce_program, downsample_program,
                     blur_x_program, blur_y_program, blur_y_mix_program})
      glDeleteProgram(p);
    for (auto& [key, p] : tone_map_programs) glDeleteProgram(p);
    glDeleteSamplers(1, &sampler);
    glDeleteBuffers(1, &state_buffer);
    glDeleteBuffers(1, &partial_buffer);
    release_pyramid();
    glDeleteTextures(1, &output);
    glDeleteTextures(1, &upload);
  }

  void release_pyramid() {
    if (!level.empty()) glDeleteTextures(GLsizei(level.size()), level.data());
    if (!temporary.empty()) glDeleteTextures(GLsizei(temporary.size()), temporary.data());
    level.clear();
    temporary.clear();
    level_width.clear();
    level_height.clear();
    pyramid_width = pyramid_height = 0;
  }

  GLuint tone_map_program(ToneMapping op, bool bloom, PostOutputFormat format) {
    const int key = tone_map_constant(op) | (bloom ? 8 : 0) | (int(format) << 4);
    auto found = tone_map_programs.find(key);
    if (found != tone_map_programs.end()) return found->second;
    const std::string defines = "#define OPERATOR " + std::to_string(tone_map_constant(op)) +
                                "\n#define OUTPUT_FORMAT " + image_format_qualifier(format) + "\n#define ENCODED " +
                                (format == PostOutputFormat::srgb8 ? "1" : "0") + "\n#define BLOOM " +
                                (bloom ? "1" : "0") + "\n";
    const GLuint program = gpu::link_compute_program(
        compute_source(defines, "src/post/tone_map.comp.glsl", "tone_map.comp.glsl"));
    tone_map_programs[key] = program;
    return program;
  }

  void ensure_pyramid(int width, int height) {
    if (width == pyramid_width && height == pyramid_height) return;
    release_pyramid();
    int w = width, h = height;
    for (int k = 1; k <= kMaxBloomLevels; ++k) {
      // Texel i of the coarser level is centred on texel 2i of the finer one
      // (post_common.comp.glsl): floor(n / 2) + 1 texels cover all n.
      w = w / 2 + 1;
      h = h / 2 + 1;
      if (k > 1 && std::min(w, h) < kMinBloomLevelSide) break;
      level_width.push_back(w);
      level_height.push_back(h);
      level.push_back(make_storage(GL_RGBA32F, w, h));
      temporary.push_back(make_storage(GL_RGBA32F, w, h));
    }
    pyramid_width = width;
    pyramid_height = height;
  }

  GLuint ensure_output(int width, int height, PostOutputFormat format) {
    if (output == 0 || output_width != width || output_height != height || output_format != format) {
      glDeleteTextures(1, &output);
      output = make_storage(internal_format(format), width, height);
      output_width = width;
      output_height = height;
      output_format = format;
    }
    return output;
  }

  // The PartialSums buffer (post_common.comp.glsl) with room for `count`
  // sums, bound.
  void bind_partial_sums(int count) {
    if (count > partial_capacity) {
      glDeleteBuffers(1, &partial_buffer);
      glCreateBuffers(1, &partial_buffer);
      glNamedBufferData(partial_buffer, GLsizeiptr(sizeof(float)) * count, nullptr, GL_DYNAMIC_DRAW);
      partial_capacity = count;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, partial_buffer);
  }

  // The reduction on its own; returns the number of sums it wrote.
  int run_reduce(const PostInput& in) {
    const GLuint groups_x = groups(in.width, kReduceColumns), strips = groups(in.height, kReduceRows);
    const int partials = int(groups_x) * kReduceColumns * int(strips);
    bind_partial_sums(partials);
    glUseProgram(reduce_program);
    glProgramUniform1f(reduce_program, 0, float(in.nits_per_unit));
    glDispatchCompute(groups_x, strips, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    return partials;
  }

  // The exposure of the frame from the `partials` sums of the reduction.
  void run_adapt(const PostInput& in, const AutoExposureSettings& a, int partials) {
    glUseProgram(adapt_program);
    glProgramUniform1i(adapt_program, 0, partials);
    glProgramUniform1f(adapt_program, 1, float(double(in.width) * double(in.height)));
    glProgramUniform1f(adapt_program, 2, float(in.dt_s));
    glProgramUniform1f(adapt_program, 3, float(a.key));
    glProgramUniform1f(adapt_program, 4, float(a.compensation_ev));
    glProgramUniform1f(adapt_program, 5, float(a.min_ev));
    glProgramUniform1f(adapt_program, 6, float(a.max_ev));
    glProgramUniform1f(adapt_program, 7, float(a.brightening_tau_s));
    glProgramUniform1f(adapt_program, 8, float(a.darkening_tau_s));
    glDispatchCompute(1, 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
    adaptation_started = true;
  }

  // The bloom pyramid; with `reduce` the bright pass also writes the
  // exposure's partial sums. Returns their number (0 without `reduce`).
  int run_bloom(const PostInput& in, const BloomSettings& b, bool reduce) {
    ensure_pyramid(in.width, in.height);
    const int levels = int(level.size());
    auto barrier = [] { glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT); };
    // Work groups covering a level with blocks of bx x by outputs per invocation.
    auto dispatch = [&](int k, int bx, int by) {
      glDispatchCompute(groups(level_width[size_t(k)], kGroup * bx), groups(level_height[size_t(k)], kGroup * by), 1);
    };
    const GLuint bright = reduce ? bright_reduce_program : bright_program;
    int partials = 0;
    if (reduce) {
      partials = int(groups(level_width[0], kGroup * kDownBlock) * groups(level_height[0], kGroup * kDownBlock)) *
                 kGroup * kGroup;
      bind_partial_sums(partials);
    }
    glUseProgram(bright);
    glProgramUniform1f(bright, 0, float(in.nits_per_unit));
    glProgramUniform1f(bright, 1, float(b.threshold));
    glBindImageTexture(0, level[0], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(0, kDownBlock, kDownBlock);
    // Level 1, and the partial sums and bloom_ev (ExposureState) for the
    // adapt and tone-map passes.
    glMemoryBarrier(GL_SHADER_IMAGE_ACCESS_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
    glUseProgram(downsample_program);
    for (int k = 1; k < levels; ++k) {
      glBindImageTexture(0, level[size_t(k - 1)], 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
      glBindImageTexture(1, level[size_t(k)], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      dispatch(k, kDownBlock, kDownBlock);
      barrier();
    }
    for (int k = levels - 1; k >= 0; --k) {
      glUseProgram(blur_x_program);
      glBindImageTexture(0, level[size_t(k)], 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
      glBindImageTexture(1, temporary[size_t(k)], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      dispatch(k, kBlurBlock, 1);
      barrier();
      // The level's own blur mixed with the coarser level (already final)
      // replaces the level.
      const bool coarsest = k == levels - 1;
      const GLuint program = coarsest ? blur_y_program : blur_y_mix_program;
      glUseProgram(program);
      glBindImageTexture(0, temporary[size_t(k)], 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
      glBindImageTexture(1, level[size_t(k)], 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      if (!coarsest) {
        glBindImageTexture(2, level[size_t(k + 1)], 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
        glProgramUniform1f(program, 0, kCoarserWeight);
      }
      dispatch(k, 2, kBlurBlock);
      barrier();
    }
    return partials;
  }
};

PostProcess::PostProcess() {
  gpu::require_gl_context("atmos::PostProcess");
  impl_ = std::make_unique<Impl>();
}

PostProcess::~PostProcess() {
  if (impl_) impl_->delete_gl_objects = gpu::gl_context_is_current();
}

std::uint32_t PostProcess::process(const PostInput& in, const PostSettings& settings) {
  validate(settings);
  require(in.width >= 1 && in.height >= 1,
          "image size must be at least 1x1 (got " + std::to_string(in.width) + "x" + std::to_string(in.height) + ")");
  require_finite(in.nits_per_unit, "nits_per_unit");
  require(in.nits_per_unit > 0.0, "nits_per_unit must be > 0 (got " + number_text(in.nits_per_unit) + ")");
  require_finite(in.dt_s, "dt_s");
  require(in.dt_s >= 0.0, "dt_s must be >= 0 (got " + number_text(in.dt_s) + ")");
  gpu::clear_gl_errors();
  check_texture(in.colour, in.width, in.height, "input colour");
  GLuint output = 0;
  if (in.output != 0) {
    require(in.output != in.colour, "the output texture must not be the input texture");
    const GLint format = check_texture(in.output, in.width, in.height, "output");
    const GLenum expected = internal_format(settings.output_format);
    char found[16];
    std::snprintf(found, sizeof found, "0x%04X", unsigned(format));
    require(GLenum(format) == expected,
            std::string("output texture has internal format ") + found + ", expected " +
                (expected == GL_RGBA8 ? "GL_RGBA8" : expected == GL_RGBA16F ? "GL_RGBA16F" : "GL_RGBA32F"));
    output = in.output;
  } else {
    output = impl_->ensure_output(in.width, in.height, settings.output_format);
  }
  Impl& m = *impl_;
  m.timings = PostTimings{};
  const bool bloom = settings.bloom.strength > 0.0;
  const GLuint tone_map = m.tone_map_program(settings.tone_mapping, bloom, settings.output_format);

  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, m.state_buffer);
  glBindTextureUnit(0, in.colour);
  glBindSampler(0, m.sampler);

  // With auto exposure and bloom the bloom's bright pass does the reduction
  // (bloom.comp.glsl), thresholding at the exposure the frame starts from;
  // the first frame after construction or reset() has none and reduces
  // first, like frames without bloom.
  const bool auto_exposure = settings.auto_exposure.enabled;
  const bool reduce_in_bloom = auto_exposure && bloom && m.adaptation_started;
  if (auto_exposure && !reduce_in_bloom) {
    if (in.timed) m.timer.begin();
    m.run_adapt(in, settings.auto_exposure, m.run_reduce(in));
    if (in.timed) m.timings.exposure_ms = m.timer.end_ms();
  } else if (!auto_exposure) {
    // The passes read the exposure from the state buffer either way; the
    // adaptation state (adapted_ev) is kept for when auto exposure resumes.
    const float ev = float(settings.exposure_ev);
    glNamedBufferSubData(m.state_buffer, offsetof(ExposureState, frame_ev), sizeof ev, &ev);
  }

  if (bloom) {
    if (in.timed) m.timer.begin();
    const int partials = m.run_bloom(in, settings.bloom, reduce_in_bloom);
    if (in.timed) m.timings.bloom_ms = m.timer.end_ms();
    if (reduce_in_bloom) {
      if (in.timed) m.timer.begin();
      m.run_adapt(in, settings.auto_exposure, partials);
      if (in.timed) m.timings.exposure_ms = m.timer.end_ms();
    }
  }

  if (in.timed) m.timer.begin();
  glUseProgram(tone_map);
  glProgramUniform1f(tone_map, 0, float(in.nits_per_unit));
  if (bloom) {
    glProgramUniform1f(tone_map, 1, float(settings.bloom.strength));
    glProgramUniform1f(tone_map, 2, float(settings.bloom.threshold));
    glBindImageTexture(1, m.level[0], 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  }
  glBindImageTexture(0, output, 0, GL_FALSE, 0, GL_WRITE_ONLY, internal_format(settings.output_format));
  glDispatchCompute(groups(in.width, kGroup * kToneMapBlock), groups(in.height, kGroup * kToneMapBlock), 1);
  // The result is read as a texture, by glGetTextureImage or by the engine.
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT | GL_TEXTURE_UPDATE_BARRIER_BIT | GL_SHADER_IMAGE_ACCESS_BARRIER_BIT |
                  GL_FRAMEBUFFER_BARRIER_BIT);
  if (in.timed) m.timings.tone_map_ms = m.timer.end_ms();

  for (GLuint unit = 0; unit < 3; ++unit) glBindImageTexture(unit, 0, 0, GL_FALSE, 0, GL_READ_ONLY, GL_RGBA32F);
  glBindSampler(0, 0);
  gpu::check_gl("post-processing");
  m.have_frame = true;
  return output;
}

DisplayImage PostProcess::process_image(const Image& hdr, const PostSettings& settings, double dt_s) {
  require(settings.output_format == PostOutputFormat::srgb8, "process_image needs the srgb8 output format");
  require(hdr.width >= 1 && hdr.height >= 1 && hdr.rgb.size() == size_t(hdr.width) * size_t(hdr.height) * 3,
          "image of " + std::to_string(hdr.width) + "x" + std::to_string(hdr.height) + " pixels holds " +
              std::to_string(hdr.rgb.size()) + " values");
  Impl& m = *impl_;
  if (m.upload == 0 || m.upload_width != hdr.width || m.upload_height != hdr.height) {
    glDeleteTextures(1, &m.upload);
    m.upload = make_storage(GL_RGBA32F, hdr.width, hdr.height);
    m.upload_width = hdr.width;
    m.upload_height = hdr.height;
  }
  glPixelStorei(GL_UNPACK_ALIGNMENT, 4);  // rows of 3 floats per texel: always 4-byte aligned
  glTextureSubImage2D(m.upload, 0, 0, 0, hdr.width, hdr.height, GL_RGB, GL_FLOAT, hdr.rgb.data());
  PostInput in;
  in.colour = m.upload;
  in.width = hdr.width;
  in.height = hdr.height;
  in.dt_s = dt_s;
  return read_display_image(process(in, settings), hdr.width, hdr.height);
}

void PostProcess::reset() {
  const ExposureState initial{0.0f, 0.0f, 0.0f, 0, 0.0f};
  glNamedBufferSubData(impl_->state_buffer, 0, sizeof initial, &initial);
  impl_->have_frame = false;
  impl_->adaptation_started = false;
}

namespace {
ExposureState read_state(GLuint buffer) {
  ExposureState s{};
  glGetNamedBufferSubData(buffer, 0, sizeof s, &s);
  return s;
}
}  // namespace

double PostProcess::current_exposure_ev() const {
  if (!impl_->have_frame) return std::numeric_limits<double>::quiet_NaN();
  return double(read_state(impl_->state_buffer).frame_ev);
}

double PostProcess::last_log_average_luminance() const {
  const ExposureState s = read_state(impl_->state_buffer);
  return s.initialized != 0 ? double(s.log_average_luminance) : std::numeric_limits<double>::quiet_NaN();
}

const PostTimings& PostProcess::last_timings() const { return impl_->timings; }

namespace {

// The RGB of an RGBA texture's level 0, as `Pixels` (DisplayImage: bytes,
// Image: floats) of `type` (GL_UNSIGNED_BYTE, GL_FLOAT).
template <typename Pixels>
Pixels read_rgb(std::uint32_t texture, int width, int height, const char* kind, GLenum type) {
  require(width >= 1 && height >= 1, "cannot read back an image of " + std::to_string(width) + "x" +
                                         std::to_string(height) + " pixels");
  check_texture(texture, width, height, kind);
  using Value = typename decltype(Pixels::rgb)::value_type;
  std::vector<Value> rgba(size_t(width) * size_t(height) * 4);
  glPixelStorei(GL_PACK_ALIGNMENT, 4);
  glGetTextureImage(texture, 0, GL_RGBA, type, GLsizei(rgba.size() * sizeof(Value)), rgba.data());
  gpu::check_gl("reading the post-processed image back");
  Pixels image;
  image.width = width;
  image.height = height;
  image.rgb.resize(size_t(width) * size_t(height) * 3);
  for (size_t i = 0; i < size_t(width) * size_t(height); ++i)
    for (size_t c = 0; c < 3; ++c) image.rgb[3 * i + c] = rgba[4 * i + c];
  return image;
}

}  // namespace

DisplayImage read_display_image(std::uint32_t texture, int width, int height) {
  return read_rgb<DisplayImage>(texture, width, height, "display", GL_UNSIGNED_BYTE);
}

Image read_linear_image(std::uint32_t texture, int width, int height) {
  return read_rgb<Image>(texture, width, height, "linear", GL_FLOAT);
}

}  // namespace atmos
