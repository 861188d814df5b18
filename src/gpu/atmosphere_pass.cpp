// The engine plugin (include/atmos/plugin.hpp): validation of the engine's
// input, the reduction of its double-precision frame to camera-relative
// floats, and the GPU passes (the sky-view table, the aerial-perspective
// volume, then composite.glsl over every pixel, class by class).
#include <epoxy/gl.h>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <functional>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include "atmos/plugin.hpp"
#include "gpu/atmosphere_pass.hpp"
#include "gpu/gl_util.hpp"
#include "gpu/instant.hpp"
#include "gpu/shader_source.hpp"
#include "gpu/star_catalogue_bins.hpp"
#include "physics/checks.hpp"
#include "physics/parameters.hpp"

namespace atmos {

namespace {

// Texture units of the pass (the layout(binding) of atmosphere_pass.frag.glsl;
// 0-7: the tables, gpu::TableUnit). Colour and albedo share a unit: a
// surface mode reads one of them. 16 units in all, the minimum GL 4.5
// guarantees per stage.
constexpr GLuint kDepthUnit = 8;
constexpr GLuint kColourUnit = 9;
constexpr GLuint kAlbedoUnit = 9;
constexpr GLuint kNormalUnit = 10;
constexpr GLuint kShadowUnit = 11;
constexpr GLuint kVolumeUnit = 12;  // 12..15: the aerial-perspective volume
constexpr GLuint kSpaceRegularColumnsUnit = 16;  // the space volume's regular columns
constexpr GLuint kInstantSpaceMultipleScatteringUnit = 17;  // instant mode, cameras above the atmosphere

// gpu::set_stencil_export (gpu/atmosphere_pass.hpp).
std::atomic<bool> stencil_export_enabled{true};

// Width, height and internal format of level 0 of an engine texture; throws
// when `name` is not a 2D texture.
struct TextureInfo {
  int width = 0;
  int height = 0;
  GLint format = 0;
};

TextureInfo texture_info(GLuint name, const char* what) {
  if (name == 0 || glIsTexture(name) != GL_TRUE)
    throw Error(std::string("plugin input: ") + what + " texture " + std::to_string(name) +
                " is not a texture of the current OpenGL context");
  GLint target = 0;
  glGetTextureParameteriv(name, GL_TEXTURE_TARGET, &target);
  if (target != GL_TEXTURE_2D)
    throw Error(std::string("plugin input: ") + what + " texture " + std::to_string(name) +
                " is not a GL_TEXTURE_2D (multisampled buffers must be resolved first)");
  TextureInfo info;
  glGetTextureLevelParameteriv(name, 0, GL_TEXTURE_WIDTH, &info.width);
  glGetTextureLevelParameteriv(name, 0, GL_TEXTURE_HEIGHT, &info.height);
  glGetTextureLevelParameteriv(name, 0, GL_TEXTURE_INTERNAL_FORMAT, &info.format);
  return info;
}

void check_size(const TextureInfo& info, const FrameInput& input, const char* what) {
  if (info.width != input.width || info.height != input.height)
    throw Error(std::string("plugin input: ") + what + " texture is " + std::to_string(info.width) + "x" +
                std::to_string(info.height) + ", the frame is " + std::to_string(input.width) + "x" +
                std::to_string(input.height));
}

bool is_depth_format(GLint format) {
  switch (format) {
    case GL_DEPTH_COMPONENT16:
    case GL_DEPTH_COMPONENT24:
    case GL_DEPTH_COMPONENT32:
    case GL_DEPTH_COMPONENT32F:
    case GL_DEPTH24_STENCIL8:
    case GL_DEPTH32F_STENCIL8:
    case GL_R32F:
      return true;
    default:
      return false;
  }
}

bool is_float_colour_format(GLint format) {
  switch (format) {
    case GL_RGB16F:
    case GL_RGBA16F:
    case GL_RGB32F:
    case GL_RGBA32F:
    case GL_R11F_G11F_B10F:
      return true;
    default:
      return false;
  }
}

}  // namespace

namespace gpu {
void set_stencil_export(bool enabled) { stencil_export_enabled.store(enabled, std::memory_order_relaxed); }
}  // namespace gpu

struct AtmospherePass::Impl {
  PlanetFrame frame;
  double bottom_radius_m = 0.0;
  std::unique_ptr<gpu::GpuTables> tables;
  // The tables and their ground response (set_ground_albedo), when they have one.
  std::unique_ptr<Tables> ground_response;
  glm::dvec3 ground_albedo{0.0};
  std::unique_ptr<gpu::GpuTimer> timer;
  // The program variants (gpu::PassVariant::index), compiled on first use.
  GLuint programs[gpu::PassVariant::kCount] = {};
  // The slots of all programs, guarded by the mutex, those some caller is
  // linking (link_programs(), render()), and the signal of a slot's
  // program published or given up.
  std::mutex link_mutex;
  std::set<const GLuint*> linking;
  std::condition_variable published;
  // The aerial-perspective volume: its compute programs (sun high, sun low,
  // eclipse) and textures (see composite.glsl).
  GLuint volume_programs[3] = {0, 0, 0};
  GLuint volume[4] = {0, 0, 0, 0};
  // The space volume (cameras above the atmosphere, see composite.glsl):
  // its compute program, textures and the buffer of its column list.
  GLuint space_program = 0;
  GLuint space_volume[4] = {0, 0, 0, 0};
  GLuint space_columns = 0;
  GLuint space_regular_columns = 0;  // 1 or 0 per column (composite.glsl: space_volume_covers)
  std::unique_ptr<physics::AtmosphereParams> params;
  GLuint vertex_array = 0;
  GLuint framebuffer = 0;
  GLuint own_output = 0;
  int own_width = 0;
  int own_height = 0;
  // The sky / surface mask (atmosphere_pass.frag.glsl), the frame's size.
  GLuint stencil = 0;
  int stencil_width = 0;
  int stencil_height = 0;
  GLuint depth_sampler = 0;   // nearest, no comparison: the engine's depth as a value
  GLuint shadow_sampler = 0;  // linear, clamped, with depth comparison (PCF)
  double own_sun_lux = 0.0;   // the atmosphere's sun illuminance
  bool stencil_export = false;  // GL_ARB_shader_stencil_export: one classifying draw
  PassTimings timings;
  // The instant mode (InstantTables): its volume's programs, without and
  // with the low-sun transmittance.
  bool instant = false;
  GLuint instant_volume_programs[2] = {0, 0};
  // The star catalogue (none: the procedural field), its irradiance in the
  // channels of the tables' wavelengths.
  std::vector<double> wavelengths_nm;
  gpu::StarCatalogueBuffers star_catalogue;

  void release() {
    for (GLuint& program : programs) gpu::release_program(program);
    for (GLuint& program : volume_programs) gpu::release_program(program);
    for (GLuint& program : instant_volume_programs) gpu::release_program(program);
    glDeleteTextures(4, volume);
    for (GLuint& texture : volume) texture = 0;
    gpu::release_program(space_program);
    glDeleteTextures(4, space_volume);
    for (GLuint& texture : space_volume) texture = 0;
    if (space_columns != 0) glDeleteBuffers(1, &space_columns);
    space_columns = 0;
    if (space_regular_columns != 0) glDeleteTextures(1, &space_regular_columns);
    space_regular_columns = 0;
    if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
    if (framebuffer != 0) glDeleteFramebuffers(1, &framebuffer);
    if (own_output != 0) glDeleteTextures(1, &own_output);
    if (stencil != 0) glDeleteRenderbuffers(1, &stencil);
    stencil = 0;
    if (depth_sampler != 0) glDeleteSamplers(1, &depth_sampler);
    if (shadow_sampler != 0) glDeleteSamplers(1, &shadow_sampler);
    vertex_array = framebuffer = own_output = depth_sampler = shadow_sampler = 0;
    star_catalogue.release();
    timer.reset();
    tables.reset();
  }
};

namespace {

// What both modes' constructors do once the tables are on the GPU: the
// pass's own objects, and a first frame of the common variants.
void create_pass_objects(AtmospherePass& pass, AtmospherePass::Impl& p, const Atmosphere& atmosphere,
                         const PlanetFrame& frame, PassPrograms programs) {
  p.timer = std::make_unique<gpu::GpuTimer>();
  p.stencil_export = epoxy_has_gl_extension("GL_ARB_shader_stencil_export");
  p.own_sun_lux = gpu::own_sun_illuminance(p.tables->params(), p.tables->radiance_to_srgb());
  glCreateVertexArrays(1, &p.vertex_array);
  glCreateFramebuffers(1, &p.framebuffer);
  glCreateTextures(GL_TEXTURE_3D, 4, p.volume);
  for (GLuint texture : p.volume) {
    glTextureStorage3D(texture, 1, GL_RGBA32F, AP_WIDTH, AP_HEIGHT, AP_SLICES);
    gpu::set_table_sampling(texture);
  }
  // The space volume (9 MB), which the instant mode never reads.
  if (!p.instant) {
    glCreateTextures(GL_TEXTURE_3D, 4, p.space_volume);
    for (GLuint texture : p.space_volume) {
      glTextureStorage3D(texture, 1, GL_RGBA32F, SPACE_VOLUME_WIDTH, SPACE_VOLUME_HEIGHT, SPACE_VOLUME_SLICES);
      gpu::set_table_sampling(texture);
    }
    glCreateTextures(GL_TEXTURE_2D, 1, &p.space_regular_columns);
    glTextureStorage2D(p.space_regular_columns, 1, GL_RGBA32F, SPACE_VOLUME_WIDTH, SPACE_VOLUME_HEIGHT);
    gpu::set_table_sampling(p.space_regular_columns);
    glCreateBuffers(1, &p.space_columns);
    glNamedBufferStorage(p.space_columns, GLsizeiptr(sizeof(GLint)) * SPACE_VOLUME_WIDTH * SPACE_VOLUME_HEIGHT,
                         nullptr, GL_DYNAMIC_STORAGE_BIT);
  }
  glCreateSamplers(1, &p.depth_sampler);
  glSamplerParameteri(p.depth_sampler, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glSamplerParameteri(p.depth_sampler, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glSamplerParameteri(p.depth_sampler, GL_TEXTURE_COMPARE_MODE, GL_NONE);
  glCreateSamplers(1, &p.shadow_sampler);
  // Percentage-closer filtering by the texture unit (composite.glsl:
  // shadow_visibility); CLAMP_TO_EDGE as the CPU twin's texture().
  glSamplerParameteri(p.shadow_sampler, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glSamplerParameteri(p.shadow_sampler, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glSamplerParameteri(p.shadow_sampler, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(p.shadow_sampler, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glSamplerParameteri(p.shadow_sampler, GL_TEXTURE_COMPARE_MODE, GL_COMPARE_REF_TO_TEXTURE);
  glSamplerParameteri(p.shadow_sampler, GL_TEXTURE_COMPARE_FUNC, GL_LEQUAL);
  gpu::check_gl("while creating the atmosphere pass");

  if (programs == PassPrograms::none) return;
  // Drivers (llvmpipe's JIT in particular) compile shaders at their first
  // draw: draw the common variants once (lit colour, sun high, camera in
  // and above the atmosphere) over a small sky, so that the engine's first
  // frames and the timings measure frames, not compilation. The other
  // variants compile at their first use. llvmpipe compiles a fragment
  // shader again for each draw state it meets: its variants are keyed by
  // the formats of the render target and of the sampled textures, and by
  // whether those textures' sizes are powers of two (Mesa,
  // lp_state_fs.h: lp_fragment_shader_variant_key). So the sky is drawn
  // with the engine's textures of docs/plugin.md (depth
  // GL_DEPTH_COMPONENT32F, colour RGBA16F, the pass's own RGBA32F output)
  // at 3 x 3 pixels, a size that is not a power of two, as an engine's
  // frame usually is not.
  constexpr int kWarmUpSize = 3;
  GLuint warm_up_textures[2] = {0, 0};
  glCreateTextures(GL_TEXTURE_2D, 2, warm_up_textures);
  glTextureStorage2D(warm_up_textures[0], 1, GL_DEPTH_COMPONENT32F, kWarmUpSize, kWarmUpSize);
  glTextureStorage2D(warm_up_textures[1], 1, GL_RGBA16F, kWarmUpSize, kWarmUpSize);
  // Depth 1: the far plane of the standard encoding, the sky.
  const std::vector<float> sky_depth(kWarmUpSize * kWarmUpSize, 1.0f);
  const std::vector<float> black(4 * kWarmUpSize * kWarmUpSize, 0.0f);
  glTextureSubImage2D(warm_up_textures[0], 0, 0, 0, kWarmUpSize, kWarmUpSize, GL_DEPTH_COMPONENT, GL_FLOAT,
                      sky_depth.data());
  glTextureSubImage2D(warm_up_textures[1], 0, 0, 0, kWarmUpSize, kWarmUpSize, GL_RGBA, GL_FLOAT, black.data());
  try {
    FrameInput warm_up;
    warm_up.depth = warm_up_textures[0];
    warm_up.colour = warm_up_textures[1];
    warm_up.width = warm_up.height = kWarmUpSize;
    warm_up.projection = glm::perspective(1.0, 1.0, 1.0, 100.0);
    for (double altitude : {10.0, 1e7}) {
      warm_up.view = glm::translate(glm::dmat4(1.0), -(frame.centre + glm::dvec3(0.0, 0.0, 1.0) *
                                                       (atmosphere.bottom_radius_m + altitude) * frame.units_per_metre));
      pass.render(warm_up);
    }
  } catch (...) {
    glDeleteTextures(2, warm_up_textures);
    throw;
  }
  glDeleteTextures(2, warm_up_textures);
  p.timings = PassTimings{};
}

// The classes of the stencil mask's bits (atmosphere_pass.frag.glsl).
constexpr GLint kSkyBit = 1;
constexpr GLint kLowSunBit = 2;
constexpr GLint kSpaceBit = 4;
constexpr GLint kSpaceVolumeBit = 8;
constexpr GLint kNightBit = 16;  // set by the exporting classifying draw only
// A draw of the composite: the classifying ones set their bit where they
// keep the pixel (with `sky_only`, among the sky pixels alone); the shading
// ones draw where the mask's bits under `compare` equal `bits`. With
// `export_stencil`, the one classifying draw of every class
// (PIXELS_CLASSIFY_ALL), which writes its bits through the stencil
// reference it exports.
struct Draw {
  GLuint program;
  bool classify;
  GLint bits;
  bool sky_only = false;
  GLint compare = 0xFF;
  bool export_stencil = false;
};

// The programs of one frame: the aerial-perspective volume's (0 when the
// frame has none), the space volume's (0 when none), and the composite's
// draws in their order, each program passed through `resolve` with its
// slot in the pass and a function that links it: render() links the
// missing ones as it goes, link_programs() shares them among its callers,
// programs_linked() only looks.
struct FramePrograms {
  GLuint volume = 0;
  GLuint space = 0;
  std::vector<Draw> draws;
};

using ResolveProgram = std::function<GLuint(GLuint& slot, const std::function<GLuint()>& link)>;

FramePrograms frame_programs(AtmospherePass::Impl& p, const physics::PassFrame& frame, const FrameInput& input,
                             const ResolveProgram& resolve) {
  FramePrograms out;
  // The composite's low-sun integration (none in the instant mode, whose
  // sky-view table and volume integrate every ray).
  const bool low_sun = frame.low_sun && !p.instant;
  const bool eclipse = frame.moons.count > 0;
  const bool shadows = input.shadow_map != 0;
  const bool sky_view_camera = physics::camera_uses_sky_view(p.tables->params(), frame.camera);
  const physics::AtmosphereParams& params = p.tables->params();
  const physics::SpectralSets& spectral = p.tables->spectral();
  if (frame.volume && p.instant) {
    out.volume = resolve(p.instant_volume_programs[frame.low_sun ? 1 : 0], [&] {
      return gpu::shared_compute_program(
          gpu::instant_aerial_perspective_compute_shader_source(params, spectral, frame.low_sun));
    });
  } else if (frame.volume) {
    out.volume = resolve(p.volume_programs[eclipse ? 2 : low_sun ? 1 : 0], [&] {
      return gpu::shared_compute_program(
          gpu::aerial_perspective_compute_shader_source(params, spectral, low_sun, eclipse, false, true));
    });
  }
  if (frame.space_volume) {
    out.space = resolve(p.space_program, [&] {
      return gpu::shared_compute_program(
          gpu::aerial_perspective_compute_shader_source(params, spectral, false, false, true, false));
    });
  }
  const auto composite_program = [&](const gpu::PassVariant& v) {
    return resolve(p.programs[v.index()], [&] {
      return gpu::shared_program(gpu::atmosphere_pass_vertex_shader_source(),
                                 gpu::atmosphere_pass_fragment_shader_source(params, spectral, v));
    });
  };
  gpu::PassVariant variant;
  variant.sky_view_camera = sky_view_camera;
  variant.low_sun = low_sun;
  variant.shadows = shadows;
  variant.gbuffer = input.surfaces == SurfaceMode::gbuffer;
  variant.volume = frame.volume;
  variant.blend = frame.volume && frame.volume_weight < 1.0f;
  variant.stars = frame.stars.enabled;
  variant.eclipse = eclipse;
  // Which pixels need the low-sun integration, when some may and the
  // composite evaluates it: not with moons (every pixel integrates), nor for
  // cameras whose surfaces read the volume alone and whose sky reads the
  // sky-view table (the variant's low_sun changes nothing there).
  const bool classify_low_sun = low_sun && !eclipse && !(frame.volume && !variant.blend && sky_view_camera);
  // The sky beside the atmosphere, for cameras above it.
  const bool classify_space = !sky_view_camera && !p.instant;
  // The instant mode's pixels of a camera above the atmosphere: one draw
  // over all of them (instant_composite.glsl: instant_space_pixel).
  const bool instant_space = p.instant && !sky_view_camera;
  const auto program_of = [&](gpu::PassVariant::Pixels pixels, bool pixel_low_sun) {
    // The classifying programs read the frame's geometry alone: one program
    // each.
    const bool classifying = pixels == gpu::PassVariant::Pixels::classify ||
                             pixels == gpu::PassVariant::Pixels::classify_low_sun ||
                             pixels == gpu::PassVariant::Pixels::classify_space ||
                             pixels == gpu::PassVariant::Pixels::classify_space_volume;
    gpu::PassVariant v = classifying ? gpu::PassVariant{} : variant;
    v.pixels = pixels;
    if (!classifying) v.low_sun = pixel_low_sun;
    return composite_program(v);
  };
  std::vector<Draw>& draws = out.draws;
  const bool export_stencil = p.stencil_export && stencil_export_enabled.load(std::memory_order_relaxed);
  if (instant_space) {
    gpu::PassVariant v = variant;
    v.pixels = gpu::PassVariant::Pixels::instant_space;
    v.low_sun = frame.low_sun;
    v.shadows = false;
    v.volume = false;
    const GLuint program = composite_program(v);
    draws.push_back({program, false, 0, false, 0});
  } else if (export_stencil) {
    gpu::PassVariant v;
    v.pixels = gpu::PassVariant::Pixels::classify_all;
    v.low_sun = classify_low_sun;
    v.sky_view_camera = !classify_space;
    v.space_volume = frame.space_volume;
    const GLuint program = composite_program(v);
    draws.push_back({program, true, 0, false, 0xFF, true});
  } else {
    draws.push_back({program_of(gpu::PassVariant::Pixels::classify, false), true, kSkyBit});
    if (classify_low_sun)
      draws.push_back({program_of(gpu::PassVariant::Pixels::classify_low_sun, false), true, kLowSunBit});
    if (classify_space)
      draws.push_back({program_of(gpu::PassVariant::Pixels::classify_space, false), true, kSpaceBit, true});
    if (frame.space_volume)
      draws.push_back({program_of(gpu::PassVariant::Pixels::classify_space_volume, false), true, kSpaceVolumeBit});
  }
  // The surfaces the space volume covers (with or without the low-sun
  // bit), by the one program that reads it; the others never do.
  variant.space_volume = false;
  if (frame.space_volume) {
    gpu::PassVariant v = variant;
    v.pixels = gpu::PassVariant::Pixels::surface;
    v.low_sun = false;
    v.space_volume = true;
    const GLuint program = composite_program(v);
    draws.push_back({program, false, kSpaceVolumeBit, false, kSpaceVolumeBit | kSkyBit});
  }
  if (classify_low_sun) {
    // Without the integration where no pixel needs it, with it where some do.
    draws.push_back({program_of(gpu::PassVariant::Pixels::sky, false), false, kSkyBit});
    draws.push_back({program_of(gpu::PassVariant::Pixels::sky, true), false, kSkyBit | kLowSunBit});
    draws.push_back({program_of(gpu::PassVariant::Pixels::surface, false), false, 0});
    draws.push_back({program_of(gpu::PassVariant::Pixels::surface, true), false, kLowSunBit});
    if (export_stencil) {
      // The low-sun surfaces in the planet's shadow, without the integration.
      gpu::PassVariant v = variant;
      v.pixels = gpu::PassVariant::Pixels::surface;
      v.low_sun = false;
      v.night = true;
      const GLuint program = composite_program(v);
      draws.push_back({program, false, kLowSunBit | kNightBit});
    }
  } else if (!instant_space) {
    draws.push_back({program_of(gpu::PassVariant::Pixels::sky, low_sun), false, kSkyBit});
    draws.push_back({program_of(gpu::PassVariant::Pixels::surface, low_sun), false, 0});
  }
  if (classify_space)
    draws.push_back({program_of(gpu::PassVariant::Pixels::space, false), false, kSkyBit | kSpaceBit});

  return out;
}

// The uniforms of a composite draw's program for this frame (the moons'
// for the shading draws of an eclipse).
void set_composite_uniforms(const Draw& draw, const physics::PassFrame& frame, bool star_catalogue,
                            const glm::dmat3& world_from_star_catalogue) {
  const GLuint program = draw.program;
  glProgramUniform3f(program, 0, frame.camera.x, frame.camera.y, frame.camera.z);
  glProgramUniform3f(program, 1, frame.sun_direction.x, frame.sun_direction.y, frame.sun_direction.z);
  glProgramUniformMatrix4fv(program, 2, 1, GL_FALSE, glm::value_ptr(frame.inverse_projection));
  glProgramUniformMatrix3fv(program, 6, 1, GL_FALSE, glm::value_ptr(frame.view_to_world));
  glProgramUniform1i(program, 9, frame.depth_encoding);
  glProgramUniform1f(program, 10, frame.log2_depth_far);
  glProgramUniformMatrix3fv(program, 12, 1, GL_FALSE, glm::value_ptr(frame.radiance_to_srgb));
  glProgramUniform1f(program, 15, frame.light_scale);
  glProgramUniform1i(program, 16, frame.sun_disc ? 1 : 0);
  glProgramUniform1i(program, 18, frame.shadow_steps);
  glProgramUniformMatrix4fv(program, 19, 1, GL_FALSE, glm::value_ptr(frame.shadow_matrix));
  glProgramUniform1f(program, 24, frame.ap_t_far);
  glProgramUniform1f(program, 25, frame.ap_t_min);
  glProgramUniform1f(program, 27, frame.shadow_depth_bias);
  glProgramUniform1f(program, 28, frame.volume_weight);
  glProgramUniform3fv(program, 29, 1, glm::value_ptr(frame.inverse_sun_srgb));
  glProgramUniform4fv(program, 30, 1, glm::value_ptr(frame.depth_column));
  glProgramUniform1f(program, 31, frame.depth_column_view_z);
  glProgramUniform1f(program, 32, frame.stars.sigma);
  glProgramUniformMatrix4fv(program, 33, 1, GL_FALSE, glm::value_ptr(frame.world_to_clip));
  glProgramUniform1f(program, 37, frame.surface_shell_radius);
  gpu::set_sky_view_frame_uniforms(program, frame.sky_view);
  if (frame.moons.count > 0 && !draw.classify) gpu::set_moons_uniforms(program, frame.moons);
  gpu::set_star_catalogue_uniforms(program, star_catalogue, world_from_star_catalogue);
}

// One composite draw over the bound framebuffer, with its stencil state.
void draw_composite(const Draw& draw) {
  if (draw.export_stencil) {
    // Every pixel's bits, as the program exports them.
    glStencilMask(0xFF);
    glStencilFunc(GL_ALWAYS, 0, 0xFF);
    glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  } else if (draw.classify) {
    // Set this draw's bit where the classifying program keeps the pixel.
    glStencilMask(GLuint(draw.bits));
    if (draw.sky_only)
      glStencilFunc(GL_EQUAL, draw.bits | kSkyBit, GLuint(kSkyBit));
    else
      glStencilFunc(GL_ALWAYS, draw.bits, 0xFF);
    glStencilOp(GL_KEEP, GL_KEEP, GL_REPLACE);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  } else {
    glStencilMask(0);
    glStencilFunc(GL_EQUAL, draw.bits, GLuint(draw.compare));
    glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  }
  glUseProgram(draw.program);
  glDrawArrays(GL_TRIANGLES, 0, 3);
}

// The uniforms of the aerial-perspective volume's compute program for this
// frame (the moons' in an eclipse).
void set_volume_uniforms(GLuint program, const physics::PassFrame& frame) {
  if (frame.moons.count > 0) gpu::set_moons_uniforms(program, frame.moons);
  glProgramUniform3f(program, 0, frame.camera.x, frame.camera.y, frame.camera.z);
  glProgramUniform3f(program, 1, frame.sun_direction.x, frame.sun_direction.y, frame.sun_direction.z);
  glProgramUniform1f(program, 24, frame.ap_t_far);
  glProgramUniform1f(program, 25, frame.ap_t_min);
  gpu::set_sky_view_frame_uniforms(program, frame.sky_view);
}

// The textures a composite draw samples besides the tables: the sky-view
// table's, the engine's, the volume's and the space volume's regular
// columns (render(): this frame's; warm_up_programs: scratch ones like them).
struct CompositeTextures {
  GLuint sky_view[3] = {0, 0, 0};
  GLuint depth = 0;
  GLuint colour = 0;
  GLuint albedo = 0;
  GLuint normal = 0;
  GLuint shadow_map = 0;
  GLuint volume[4] = {0, 0, 0, 0};
  GLuint space_regular_columns = 0;
};

// Binds them and the tables on the units of atmosphere_pass.frag.glsl, with
// their sampler objects.
void bind_composite_textures(const AtmospherePass::Impl& p, SurfaceMode surfaces, const CompositeTextures& t) {
  p.tables->bind();
  for (GLuint unit = 0; unit < gpu::kTableUnitCount; ++unit) glBindSampler(unit, 0);
  for (GLuint i = 0; i < 3; ++i) glBindTextureUnit(gpu::kSkyViewRayleighUnit + i, t.sky_view[i]);
  glBindTextureUnit(kDepthUnit, t.depth);
  if (surfaces == SurfaceMode::lit_colour) {
    glBindTextureUnit(kColourUnit, t.colour);
    glBindTextureUnit(kNormalUnit, 0);
  } else {
    glBindTextureUnit(kAlbedoUnit, t.albedo);
    glBindTextureUnit(kNormalUnit, t.normal);
  }
  glBindTextureUnit(kShadowUnit, t.shadow_map);
  for (GLuint unit : {kDepthUnit, kColourUnit, kNormalUnit}) glBindSampler(unit, p.depth_sampler);
  glBindSampler(kShadowUnit, p.shadow_sampler);
  for (GLuint i = 0; i < 4; ++i) {
    glBindTextureUnit(kVolumeUnit + i, t.volume[i]);
    glBindSampler(kVolumeUnit + i, 0);
  }
  glBindTextureUnit(kSpaceRegularColumnsUnit, t.space_regular_columns);
  glBindSampler(kSpaceRegularColumnsUnit, 0);
  if (p.instant) {
    glBindTextureUnit(kInstantSpaceMultipleScatteringUnit, p.tables->instant_multiple_scattering_texture());
    glBindSampler(kInstantSpaceMultipleScatteringUnit, 0);
  }
}

// Draws and dispatches each program of `fresh` once, with the state
// render() would for this frame, over 3 x 3 pixels of scratch textures in
// the CURRENT context: drivers that compile a program's machine code at its
// first draw for the draw's state (llvmpipe) compile it here, and those with
// a shader cache (Mesa's, on by default) reuse that code in every context.
// It may run while other contexts render with these programs (a program is
// shared by the passes of an atmosphere's structure, gpu::shared_program):
// it sets no uniform, writes scratch objects only and reads the shared
// tables. The shading draws' stencil test fails at every pixel (the mask
// holds a bit no class has), so that they run no fragment; the classifying
// draws and the compute programs run over a few pixels with whatever
// uniforms the programs hold (no loop of theirs depends on one).
void warm_up_programs(AtmospherePass::Impl& p, const physics::PassFrame& frame, const FrameInput& input,
                      const FramePrograms& programs, const std::set<GLuint>& fresh) {
  if (fresh.empty()) return;
  std::vector<GLuint> textures;
  // The engine's textures given as 0 are taken as the frame's size.
  const auto scratch = [&textures, &input](GLuint like, GLint format) {
    textures.push_back(gpu::warm_up_texture_like(like, format, input.width, input.height));
    return textures.back();
  };
  GLuint framebuffer = 0, vertex_array = 0, stencil = 0, column_buffer = 0;
  const auto columns = [&column_buffer] {
    const std::vector<GLint> zeros(size_t(SPACE_VOLUME_WIDTH) * SPACE_VOLUME_HEIGHT, 0);
    glCreateBuffers(1, &column_buffer);
    glNamedBufferStorage(column_buffer, GLsizeiptr(sizeof(GLint) * zeros.size()), zeros.data(), 0);
    return column_buffer;
  };
  const auto release = [&] {
    if (column_buffer != 0) glDeleteBuffers(1, &column_buffer);
    glDeleteTextures(GLsizei(textures.size()), textures.data());
    if (framebuffer != 0) glDeleteFramebuffers(1, &framebuffer);
    if (vertex_array != 0) glDeleteVertexArrays(1, &vertex_array);
    if (stencil != 0) glDeleteRenderbuffers(1, &stencil);
  };
  try {
    const GLuint volume_like = p.volume[0];
    // The volumes' compute programs, over one work group.
    for (const GLuint program : {programs.volume, programs.space}) {
      if (program == 0 || fresh.count(program) == 0) continue;
      glUseProgram(program);
      p.tables->bind_integration_inputs();
      // The space volume's column list: zeros.
      if (program == programs.space) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, columns());
      for (GLuint i = 0; i < 4; ++i)
        glBindImageTexture(i, scratch(volume_like, GL_RGBA32F), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      glDispatchCompute(1, 1, 1);
      for (GLuint i = 0; i < 4; ++i) glBindImageTexture(i, 0, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    }

    // The composite's draws, each with its stencil state.
    std::vector<Draw> draws;
    for (const Draw& draw : programs.draws)
      if (fresh.count(draw.program) > 0) draws.push_back(draw);
    if (!draws.empty()) {
      const bool star_catalogue = frame.stars.enabled && !p.star_catalogue.empty();
      if (star_catalogue) p.star_catalogue.bind(double(frame.stars.sigma));
      // Every texture a frame writes (the sky-view table, the volumes) or
      // the engine owns: a scratch copy of its format, so that only the
      // shared tables are read.
      CompositeTextures t;
      for (int i = 0; i < 3; ++i) t.sky_view[i] = scratch(p.tables->sky_view_texture(i), GL_RGBA32F);
      t.depth = scratch(input.depth, GL_DEPTH_COMPONENT32F);
      if (input.surfaces == SurfaceMode::lit_colour) {
        t.colour = scratch(input.colour, GL_RGBA16F);
      } else {
        t.albedo = scratch(input.albedo, GL_RGBA16F);
        t.normal = scratch(input.normal, GL_RGBA16F);
      }
      if (input.shadow_map != 0) t.shadow_map = scratch(input.shadow_map, GL_DEPTH_COMPONENT32F);
      for (GLuint& texture : t.volume) texture = scratch(frame.space_volume ? p.space_volume[0] : volume_like, GL_RGBA32F);
      t.space_regular_columns = scratch(p.space_regular_columns, GL_RGBA32F);
      bind_composite_textures(p, input.surfaces, t);
      glCreateFramebuffers(1, &framebuffer);
      glNamedFramebufferTexture(framebuffer, GL_COLOR_ATTACHMENT0, scratch(input.output, GL_RGBA32F), 0);
      glCreateRenderbuffers(1, &stencil);
      glNamedRenderbufferStorage(stencil, GL_STENCIL_INDEX8, 3, 3);
      glNamedFramebufferRenderbuffer(framebuffer, GL_STENCIL_ATTACHMENT, GL_RENDERBUFFER, stencil);
      glNamedFramebufferDrawBuffer(framebuffer, GL_COLOR_ATTACHMENT0);
      glCreateVertexArrays(1, &vertex_array);
      glBindVertexArray(vertex_array);
      glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
      glViewport(0, 0, 3, 3);
      gpu::set_full_screen_state();
      glEnable(GL_STENCIL_TEST);
      glStencilMask(0xFF);
      const GLint no_class = 0x80;
      glClearNamedFramebufferiv(framebuffer, GL_STENCIL, 0, &no_class);
      for (const Draw& draw : draws) draw_composite(draw);
      glStencilMask(0xFF);
      glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
      glDisable(GL_STENCIL_TEST);
      glBindFramebuffer(GL_FRAMEBUFFER, 0);
      glBindVertexArray(0);
      if (star_catalogue) gpu::StarCatalogueBuffers::unbind();
    }
    gpu::check_gl("while drawing the atmosphere pass's new programs once");
  } catch (...) {
    release();
    throw;
  }
  release();
}

void check_planet_frame(const PlanetFrame& frame) {
  if (!is_finite(frame.centre))
    throw Error("invalid planet frame: centre is not finite");
  if (!(frame.units_per_metre > 0.0 && std::isfinite(frame.units_per_metre)))
    throw Error("invalid planet frame: units_per_metre " + number_text(frame.units_per_metre) + " must be > 0");
}

}  // namespace

AtmospherePass::AtmospherePass(const Atmosphere& atmosphere, const Tables& tables, const PlanetFrame& frame,
                               PassPrograms programs)
    : impl_(std::make_unique<Impl>()) {
  check_planet_frame(frame);
  check_tables_match(atmosphere, tables);
  gpu::require_gl_context("the engine plugin (atmos::AtmospherePass)");
  Impl& p = *impl_;
  p.frame = frame;
  p.bottom_radius_m = atmosphere.bottom_radius_m;
  p.wavelengths_nm = tables.wavelengths_nm;
  gpu::clear_gl_errors();
  try {
    p.tables = std::make_unique<gpu::GpuTables>(atmosphere, tables, TexturePrecision::full);
    p.ground_albedo = glm::dvec3(p.tables->params().ground_albedo);
    if (!tables.ground_response.empty()) {
      p.ground_response = std::make_unique<Tables>(tables);
      p.ground_albedo = glm::dvec3(tables.ground_response.planet_albedo);
    }
    create_pass_objects(*this, p, atmosphere, frame, programs);
  } catch (...) {
    p.release();
    throw;
  }
}

AtmospherePass::AtmospherePass(const Atmosphere& atmosphere, const InstantTables& tables, const PlanetFrame& frame,
                               PassPrograms programs)
    : impl_(std::make_unique<Impl>()) {
  check_planet_frame(frame);
  check_tables_match(atmosphere, tables);
  gpu::require_gl_context("the engine plugin (atmos::AtmospherePass)");
  Impl& p = *impl_;
  p.frame = frame;
  p.bottom_radius_m = atmosphere.bottom_radius_m;
  p.wavelengths_nm = tables.wavelengths_nm;
  p.instant = true;
  gpu::clear_gl_errors();
  try {
    p.tables = std::make_unique<gpu::GpuTables>(atmosphere, tables);
    p.ground_albedo = glm::dvec3(p.tables->params().ground_albedo);
    create_pass_objects(*this, p, atmosphere, frame, programs);
  } catch (...) {
    p.release();
    throw;
  }
}

bool AtmospherePass::instant() const { return impl_->instant; }

AtmospherePass::~AtmospherePass() {
  // With no current context the objects die with the engine's context.
  if (impl_ && gpu::gl_context_is_current()) impl_->release();
}

const PassTimings& AtmospherePass::last_timings() const { return impl_->timings; }

void AtmospherePass::set_ground_albedo(const glm::dvec3& albedo) {
  Impl& p = *impl_;
  if (p.instant)
    throw Error("AtmospherePass::set_ground_albedo: the instant mode has no ground albedo response (compute the "
                "instant tables of the atmosphere with that albedo)");
  if (!p.ground_response)
    throw Error("AtmospherePass::set_ground_albedo: the tables have no ground albedo response (precompute them "
                "with PrecomputeOptions::ground_albedo_response)");
  for (int c = 0; c < 3; ++c)
    if (!(albedo[c] >= 0.0 && albedo[c] <= 1.0))
      throw Error("AtmospherePass::set_ground_albedo: albedo " + number_text(albedo[c]) + " is outside [0, 1]");
  // Over Earth the scattering table's light moves by about 1 % per 0.01 of
  // albedo (tests/ground_albedo_test.cpp): a change of 0.001 or less, about
  // 0.1 %, keeps the tables.
  const glm::dvec3 change = glm::abs(albedo - p.ground_albedo);
  if (std::max({change.x, change.y, change.z}) <= 0.001) return;
  p.tables->replace_ground_dependent_tables(tables_for_ground_albedo(*p.ground_response, glm::vec3(albedo)));
  p.ground_albedo = albedo;
}

glm::dvec3 AtmospherePass::ground_albedo() const { return impl_->ground_albedo; }

void AtmospherePass::set_star_catalogue(const std::vector<Star>& stars) {
  impl_->star_catalogue.set(stars, impl_->wavelengths_nm);
}

const std::vector<Star>& AtmospherePass::star_catalogue() const { return impl_->star_catalogue.stars(); }

const PlanetFrame& AtmospherePass::frame() const { return impl_->frame; }

double AtmospherePass::bottom_radius_m() const { return impl_->bottom_radius_m; }

double AtmospherePass::sun_illuminance_lux() const { return impl_->own_sun_lux; }

namespace {

void check_parameters_binding(const char* who, int binding) {
  GLint bindings = 0;
  glGetIntegerv(GL_MAX_UNIFORM_BUFFER_BINDINGS, &bindings);
  if (binding < 0 || (bindings > 0 && binding >= bindings))
    throw Error(std::string(who) + ": uniform-buffer binding " + std::to_string(binding) + " outside the context's " +
                std::to_string(bindings));
}

}  // namespace

std::string AtmospherePass::glsl_library(int first_unit, int parameters_binding) const {
  GLint units = 0;
  glGetIntegerv(GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS, &units);
  if (first_unit < 0 || (units > 0 && first_unit + 5 > units))
    throw Error("glsl_library: texture units " + std::to_string(first_unit) + ".." + std::to_string(first_unit + 4) +
                " outside the context's " + std::to_string(units));
  check_parameters_binding("glsl_library", parameters_binding);
  return gpu::engine_library_source(impl_->tables->params(), impl_->tables->spectral(), first_unit,
                                    parameters_binding, impl_->instant);
}

void AtmospherePass::bind_textures(int first_unit, int parameters_binding) const {
  check_parameters_binding("bind_textures", parameters_binding);
  // The instant mode's library reads its multiple-scattering table on the
  // second unit and no 4D table (engine_library.glsl, ATMOS_INSTANT).
  const gpu::GpuTables& tables = *impl_->tables;
  for (int i = 0; i < 5; ++i) {
    const GLuint texture = impl_->instant && i == 1 ? tables.instant_multiple_scattering_texture() : tables.texture(i);
    glBindTextureUnit(GLuint(first_unit + i), texture);
    glBindSampler(GLuint(first_unit + i), 0);
  }
  impl_->tables->bind_parameters(GLuint(parameters_binding));
}

namespace {

void check_frame_size(const FrameInput& input) {
  if (input.width < 1 || input.height < 1 || input.width > gpu::kMaxImageSize || input.height > gpu::kMaxImageSize)
    throw Error("plugin input: frame size " + std::to_string(input.width) + "x" + std::to_string(input.height) +
                " outside 1.." + std::to_string(gpu::kMaxImageSize));
}

// The frame's PassFrame from its numbers (checked before), in the pass's
// mode: the instant mode has no volume of its own and draws no eclipses.
physics::PassFrame pass_frame_of(const AtmospherePass::Impl& p, const FrameInput& input) {
  physics::PassFrame frame =
      gpu::make_pass_frame(input, p.frame, p.tables->params(), p.tables->radiance_to_srgb(), p.own_sun_lux);
  if (p.instant) {
    if (frame.moons.count > 0)
      throw Error("plugin input: the instant mode draws no eclipses, and a moon hides part of the sun from the "
                  "atmosphere (use Tables)");
    gpu::make_instant_frame(p.tables->params(), frame);
  }
  return frame;
}

// The frame of an input whose textures are not read (link_programs,
// programs_linked): its numbers checked as render() checks them.
physics::PassFrame frame_without_textures(const AtmospherePass::Impl& p, const FrameInput& input) {
  check_frame_size(input);
  gpu::validate_frame_numbers(input);
  gpu::validate_star_orientation(input.world_from_star_catalogue, "plugin input");
  return pass_frame_of(p, input);
}

}  // namespace

bool AtmospherePass::programs_linked(const FrameInput& input) const {
  Impl& p = *impl_;
  const physics::PassFrame frame = frame_without_textures(p, input);
  std::lock_guard<std::mutex> lock(p.link_mutex);
  bool all = true;
  const ResolveProgram check = [&all](GLuint& slot, const std::function<GLuint()>&) {
    all = all && slot != 0;
    return slot;
  };
  if (physics::camera_uses_sky_view(p.tables->params(), frame.camera)) {
    GLuint& slot = p.tables->sky_view_program(frame.camera, frame.sun_direction, frame.moons);
    all = all && slot != 0;
  }
  (void)frame_programs(p, frame, input, check);
  return all;
}

namespace {

// The views link_programs(input, ProgramScope::flight) prepares: the input's
// camera moved along its vertical to an altitude in each of the pass's
// regimes (gpu/atmosphere_pass.hpp, make_pass_frame): on the ground (the
// aerial-perspective volume alone), in the band where the volume blends into
// the exact evaluation, higher in the atmosphere (the sky-view table and the
// exact evaluation), and above the atmosphere near it and far from it
// (the space volume, or none); the input's own view first, then the others
// by their distance in log-altitude from it, so that the nearest are
// prepared first.
std::vector<FrameInput> flight_views(const AtmospherePass::Impl& p, const FrameInput& input) {
  const physics::AtmosphereParams& params = p.tables->params();
  const glm::dvec3 eye = glm::dvec3(glm::inverse(input.view)[3]);  // engine units
  const glm::dvec3 offset = (eye - p.frame.centre) / p.frame.units_per_metre;
  const double radius = glm::length(offset);
  const glm::dvec3 up = radius > 0.0 ? offset / radius : glm::dvec3(0.0, 0.0, 1.0);
  const double bottom = double(params.bottom_radius);
  const double top = double(params.top_radius) - bottom;
  const double altitude = std::max(radius - bottom, 1.0);
  std::vector<double> altitudes = {10.0, 0.5 * (gpu::kVolumeBlendAltitude + gpu::kVolumeMaxAltitude),
                                   0.5 * (gpu::kVolumeMaxAltitude + top), 1.5 * top, 2.5 * bottom};
  std::sort(altitudes.begin(), altitudes.end(), [altitude](double a, double b) {
    return std::abs(std::log(a / altitude)) < std::abs(std::log(b / altitude));
  });
  std::vector<FrameInput> views = {input};
  for (double a : altitudes) {
    // The view's rotation about the moved eye: view' = view T(-delta).
    FrameInput moved = input;
    const glm::dvec3 delta = up * ((a - (radius - bottom)) * p.frame.units_per_metre);
    moved.view = input.view * glm::translate(glm::dmat4(1.0), -delta);
    views.push_back(moved);
  }
  return views;
}

}  // namespace

void AtmospherePass::link_programs(const FrameInput& input, ProgramScope scope, const std::atomic<bool>* stop) {
  Impl& p = *impl_;
  gpu::require_gl_context("the engine plugin (atmos::AtmospherePass::link_programs)");
  if (scope == ProgramScope::flight) (void)frame_without_textures(p, input);  // checked before its camera moves
  // The frames to prepare: with ProgramScope::flight, at each altitude also
  // the frame with the sun low somewhere in view if it is not (or not if
  // it is) and, above the atmosphere, with the space volume if without (or
  // without if with): a flight looks around, and a view's terminator or
  // regular columns change with its direction.
  std::vector<std::pair<FrameInput, physics::PassFrame>> frames;
  const std::vector<FrameInput> views = scope == ProgramScope::flight ? flight_views(p, input) : std::vector{input};
  for (const FrameInput& view : views) {
    const physics::PassFrame frame = frame_without_textures(p, view);
    frames.emplace_back(view, frame);
    if (scope != ProgramScope::flight) continue;
    physics::PassFrame other = frame;
    other.low_sun = !frame.low_sun;
    frames.emplace_back(view, other);
    if (!physics::camera_uses_sky_view(p.tables->params(), frame.camera) && frame.moons.count == 0 &&
        input.shadow_map == 0) {
      for (const bool low_sun : {frame.low_sun, !frame.low_sun}) {
        other.low_sun = low_sun;
        other.space_volume = !frame.space_volume;
        frames.emplace_back(view, other);
      }
    }
  }
  for (const auto& item : frames) {
    if (stop != nullptr && stop->load()) return;
    const FrameInput& view = item.first;
    const physics::PassFrame& frame = item.second;
    // Each missing program is claimed by the first caller that needs it
    // (render() waits for it, other link_programs() calls skip it), linked
    // and drawn once outside the lock, then published in its slot.
    std::vector<std::pair<GLuint*, GLuint>> claimed;
    std::set<GLuint> fresh;
    const ResolveProgram claim_and_link = [&](GLuint& slot, const std::function<GLuint()>& link) -> GLuint {
      if (stop != nullptr && stop->load()) return 0;
      {
        std::lock_guard<std::mutex> lock(p.link_mutex);
        if (slot != 0 || p.linking.count(&slot) > 0) return slot;
        p.linking.insert(&slot);
      }
      claimed.emplace_back(&slot, 0);
      claimed.back().second = link();
      fresh.insert(claimed.back().second);
      return claimed.back().second;
    };
    const auto give_up = [&p, &claimed] {
      std::lock_guard<std::mutex> lock(p.link_mutex);
      for (auto& [slot, program] : claimed) {
        gpu::release_program(program);
        p.linking.erase(slot);
      }
      p.published.notify_all();
    };
    try {
      if (physics::camera_uses_sky_view(p.tables->params(), frame.camera)) {
        const GLuint program =
            claim_and_link(p.tables->sky_view_program(frame.camera, frame.sun_direction, frame.moons), [&] {
              return p.tables->link_sky_view_program(frame.camera, frame.sun_direction, frame.moons);
            });
        if (fresh.count(program) > 0)
          p.tables->warm_up_sky_view(program);
      }
      const FramePrograms programs = frame_programs(p, frame, view, claim_and_link);
      warm_up_programs(p, frame, view, programs, fresh);
      gpu::check_gl("while linking the atmosphere pass's programs");
      // The programs are drawn with in another context of the share group:
      // its commands must have completed here (OpenGL 4.5 core, 5.3.1).
      glFinish();
    } catch (...) {
      give_up();
      throw;
    }
    std::lock_guard<std::mutex> lock(p.link_mutex);
    for (auto& [slot, program] : claimed) {
      *slot = program;
      p.linking.erase(slot);
    }
    p.published.notify_all();
  }
}

std::uint32_t AtmospherePass::render(const FrameInput& input) {
  Impl& p = *impl_;
  gpu::require_gl_context("the engine plugin (atmos::AtmospherePass)");
  // --- Validation: everything before the first state change. ---
  check_frame_size(input);
  if (input.depth == 0) throw Error("plugin input: no depth texture (FrameInput::depth is 0)");
  gpu::clear_gl_errors();
  const TextureInfo depth = texture_info(input.depth, "depth");
  check_size(depth, input, "depth");
  if (!is_depth_format(depth.format))
    throw Error("plugin input: the depth texture's format is not a depth format (GL_DEPTH_COMPONENT*, "
                "GL_DEPTH*_STENCIL8) nor GL_R32F");
  if (input.surfaces == SurfaceMode::lit_colour) {
    check_size(texture_info(input.colour, "colour"), input, "colour");
  } else {
    check_size(texture_info(input.albedo, "albedo"), input, "albedo");
    check_size(texture_info(input.normal, "normal"), input, "normal");
  }
  if (input.output != 0) {
    if (input.output == input.colour || input.output == input.depth || input.output == input.albedo ||
        input.output == input.normal)
      throw Error("plugin input: the output texture is also an input (a GL feedback loop); use another texture");
    const TextureInfo output = texture_info(input.output, "output");
    check_size(output, input, "output");
    if (!is_float_colour_format(output.format))
      throw Error("plugin input: the output texture must be RGBA16F or RGBA32F (HDR)");
  }
  gpu::validate_frame_numbers(input);
  gpu::validate_star_orientation(input.world_from_star_catalogue, "plugin input");
  const bool shadows = input.shadow_map != 0;
  if (shadows) {
    const TextureInfo shadow = texture_info(input.shadow_map, "shadow map");
    if (!is_depth_format(shadow.format) || shadow.format == GL_R32F)
      throw Error("plugin input: the shadow map's format is not a depth format (GL_DEPTH_COMPONENT*, "
                  "GL_DEPTH*_STENCIL8: it is read with depth comparison)");
  }

  physics::PassFrame frame = pass_frame_of(p, input);
  if (shadows) {
    const TextureInfo shadow = texture_info(input.shadow_map, "shadow map");
    gpu::set_shadow_depth_bias(input, shadow.width, shadow.height, frame);
  }
  const glm::vec3 camera_f = frame.camera;
  const glm::vec3 sun_f = frame.sun_direction;
  // The programs of this frame, linked now where they are not yet.
  // A program another thread is linking (link_programs) is waited for.
  const ResolveProgram link_or_wait = [&p](GLuint& slot, const std::function<GLuint()>& link) -> GLuint {
    std::unique_lock<std::mutex> lock(p.link_mutex);
    p.published.wait(lock, [&] { return slot != 0 || p.linking.count(&slot) == 0; });
    if (slot != 0) return slot;
    p.linking.insert(&slot);
    lock.unlock();
    GLuint program = 0;
    try {
      program = link();
    } catch (...) {
      lock.lock();
      p.linking.erase(&slot);
      p.published.notify_all();
      throw;
    }
    lock.lock();
    slot = program;
    p.linking.erase(&slot);
    p.published.notify_all();
    return program;
  };
  if (physics::camera_uses_sky_view(p.tables->params(), frame.camera)) {
    link_or_wait(p.tables->sky_view_program(frame.camera, frame.sun_direction, frame.moons),
                 [&] { return p.tables->link_sky_view_program(frame.camera, frame.sun_direction, frame.moons); });
  }
  const FramePrograms programs = frame_programs(p, frame, input, link_or_wait);

  // --- The output target. ---
  GLuint output = input.output;
  if (output == 0) {
    if (p.own_output == 0 || p.own_width != input.width || p.own_height != input.height) {
      if (p.own_output != 0) glDeleteTextures(1, &p.own_output);
      glCreateTextures(GL_TEXTURE_2D, 1, &p.own_output);
      glTextureStorage2D(p.own_output, 1, GL_RGBA32F, input.width, input.height);
      p.own_width = input.width;
      p.own_height = input.height;
    }
    output = p.own_output;
  }
  glNamedFramebufferTexture(p.framebuffer, GL_COLOR_ATTACHMENT0, output, 0);
  glNamedFramebufferDrawBuffer(p.framebuffer, GL_COLOR_ATTACHMENT0);
  gpu::check_gl("while preparing the plugin's output");
  if (glCheckNamedFramebufferStatus(p.framebuffer, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw Error("plugin: the output texture cannot be rendered to by this OpenGL driver");

  gpu::set_full_screen_state();

  // Pass 1: this frame's sky-view table, for cameras in the atmosphere
  // (eclipsed, over the full azimuth, with moons).
  PassTimings timings;
  const bool sky_view_camera = physics::camera_uses_sky_view(p.tables->params(), camera_f);
  if (sky_view_camera) {
    const double ms = p.tables->update_sky_view(camera_f, sun_f, frame.sky_view,
                                                input.timed ? p.timer.get() : nullptr, frame.moons);
    timings.sky_view_ms = ms;
  }

  // Pass 2: this frame's aerial-perspective volume, for cameras low in the
  // atmosphere.
  if (frame.volume) {
    const GLuint volume_program = programs.volume;
    glUseProgram(volume_program);
    set_volume_uniforms(volume_program, frame);
    p.tables->bind_integration_inputs();
    for (GLuint i = 0; i < 4; ++i) glBindImageTexture(i, p.volume[i], 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    if (input.timed) p.timer->begin();
    glDispatchCompute((AP_WIDTH + 7) / 8, (AP_HEIGHT + 7) / 8, 1);
    // The composite pass samples what the images wrote.
    glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
    if (input.timed) timings.volume_ms = p.timer->end_ms();
    for (GLuint i = 0; i < 4; ++i) glBindImageTexture(i, 0, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
  }

  // Pass 2': the space volume, for cameras above the atmosphere: its
  // regular columns (gpu::space_volume_columns, listed by the CPU), the only
  // ones that covered pixels read.
  if (frame.space_volume) {
    const gpu::SpaceVolumeColumns columns = gpu::space_volume_columns(p.tables->params(), frame);
    const int count = int(columns.order.size());
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
    glTextureSubImage2D(p.space_regular_columns, 0, 0, 0, SPACE_VOLUME_WIDTH, SPACE_VOLUME_HEIGHT, GL_RGB, GL_FLOAT,
                        columns.regular.data());
    if (count > 0) {
      glNamedBufferSubData(p.space_columns, 0, GLsizeiptr(sizeof(GLint)) * count, columns.order.data());
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, p.space_columns);
      p.tables->bind_integration_inputs();
      for (GLuint i = 0; i < 4; ++i)
        glBindImageTexture(i, p.space_volume[i], 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      const GLuint program = programs.space;
      glUseProgram(program);
      glProgramUniform3f(program, 0, frame.camera.x, frame.camera.y, frame.camera.z);
      glProgramUniform3f(program, 1, frame.sun_direction.x, frame.sun_direction.y, frame.sun_direction.z);
      glProgramUniformMatrix4fv(program, 2, 1, GL_FALSE, glm::value_ptr(frame.inverse_projection));
      glProgramUniformMatrix3fv(program, 6, 1, GL_FALSE, glm::value_ptr(frame.view_to_world));
      glProgramUniform1i(program, 9, frame.depth_encoding);
      glProgramUniform4fv(program, 30, 1, glm::value_ptr(frame.depth_column));
      glProgramUniform1f(program, 37, frame.surface_shell_radius);
      glProgramUniform1i(program, 38, 0);
      glProgramUniform1i(program, 39, count);
      if (input.timed) p.timer->begin();
      glDispatchCompute(GLuint((count + 63) / 64), 1, 1);
      glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
      if (input.timed) timings.volume_ms = p.timer->end_ms();
      for (GLuint i = 0; i < 4; ++i) glBindImageTexture(i, 0, 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_RGBA32F);
      glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, 0);
    }
  }

  // The composite: every pixel, sorted into classes in a stencil mask, each
  // class drawn by its own program (see atmosphere_pass.frag.glsl).
  if (p.stencil == 0 || p.stencil_width != input.width || p.stencil_height != input.height) {
    if (p.stencil != 0) glDeleteRenderbuffers(1, &p.stencil);
    glCreateRenderbuffers(1, &p.stencil);
    glNamedRenderbufferStorage(p.stencil, GL_STENCIL_INDEX8, input.width, input.height);
    p.stencil_width = input.width;
    p.stencil_height = input.height;
  }
  glNamedFramebufferRenderbuffer(p.framebuffer, GL_STENCIL_ATTACHMENT, GL_RENDERBUFFER, p.stencil);
  gpu::check_gl("while preparing the plugin's stencil mask");
  if (glCheckNamedFramebufferStatus(p.framebuffer, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw Error("plugin: this OpenGL driver cannot render to the output texture with an 8-bit stencil buffer");

  const std::vector<Draw>& draws = programs.draws;
  const bool star_catalogue = frame.stars.enabled && !p.star_catalogue.empty();
  for (const Draw& draw : draws)
    set_composite_uniforms(draw, frame, star_catalogue, input.world_from_star_catalogue);
  if (star_catalogue) p.star_catalogue.bind(double(frame.stars.sigma));
  CompositeTextures textures;
  for (int i = 0; i < 3; ++i) textures.sky_view[i] = p.tables->sky_view_texture(i);
  textures.depth = input.depth;
  textures.colour = input.colour;
  textures.albedo = input.albedo;
  textures.normal = input.normal;
  textures.shadow_map = shadows ? input.shadow_map : 0;
  for (GLuint i = 0; i < 4; ++i) textures.volume[i] = frame.space_volume ? p.space_volume[i] : p.volume[i];
  textures.space_regular_columns = p.space_regular_columns;
  bind_composite_textures(p, input.surfaces, textures);
  glBindVertexArray(p.vertex_array);
  glBindFramebuffer(GL_FRAMEBUFFER, p.framebuffer);
  glViewport(0, 0, input.width, input.height);
  if (input.timed) p.timer->begin();
  glEnable(GL_STENCIL_TEST);
  glStencilMask(0xFF);
  const GLint clear_stencil = 0;
  glClearNamedFramebufferiv(p.framebuffer, GL_STENCIL, 0, &clear_stencil);
  for (const Draw& draw : draws) draw_composite(draw);
  glStencilMask(0xFF);
  glDisable(GL_STENCIL_TEST);
  if (input.timed) timings.composite_ms = p.timer->end_ms();
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  if (star_catalogue) gpu::StarCatalogueBuffers::unbind();
  gpu::check_gl("while compositing the atmosphere");
  p.timings = timings;
  return output;
}

}  // namespace atmos
