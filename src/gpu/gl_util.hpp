// OpenGL plumbing shared by the GPU passes (the renderer, the engine
// plugin): shader compilation with messages mapped back to the source files,
// table textures with the sampling the CPU twin reproduces, error checks,
// timing, and the precomputed tables on the GPU with the per-frame sky-view
// table that both passes read.
//
// Everything here works on the CURRENT OpenGL context.
#pragma once

#include <epoxy/gl.h>

#include <glm/glm.hpp>

#include <array>
#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "atmos/atmosphere.hpp"
#include "atmos/renderer.hpp"
#include "atmos/tables.hpp"
#include "gpu/shader_source.hpp"
#include "physics/sky_view_table_cpp.hpp"

namespace atmos::gpu {

// The largest image width or height a pass draws, pixels: the smallest
// GL_MAX_TEXTURE_SIZE that OpenGL 4.5 allows an implementation.
inline constexpr int kMaxImageSize = 16384;

// Compiles and links a vertex + fragment program; throws atmos::Error with
// the first error lines of the info log, their line numbers mapped back to
// the files of the assembled source ("functions.glsl:57(12): error: ...").
GLuint link_program(const AssembledSource& vertex_source, const AssembledSource& fragment_source);
// The same for a compute shader.
GLuint link_compute_program(const AssembledSource& compute_source);

// Programs shared by source text: the program of these sources that is
// alive in the current context's share group, else a new link; each call
// owns one reference, which release_program() drops (deleting the program
// with the last). Programs depend on the atmosphere's structure alone
// (ParameterBlock), so passes of atmospheres that differ in values share
// them.
GLuint shared_program(const AssembledSource& vertex_source, const AssembledSource& fragment_source);
GLuint shared_compute_program(const AssembledSource& compute_source);
// Drops the caller's reference to a program of shared_program (or deletes
// any other program); sets `program` to 0.
void release_program(GLuint& program);

// The fixed-function state of atmos's full-screen passes: no blending,
// depth, stencil or scissor test, no culling, no sRGB conversion, every
// colour channel written.
void set_full_screen_state();

// A zeroed texture for a warm-up draw that a driver compiles for as it
// would for `like` (0: a 2D texture of `format`, `width` x `height`): the
// same target, internal format and sampling parameters, each side 2 where
// `like`'s is a power of two and 3 where not. llvmpipe keys the machine
// code of a shader by the formats and sampling state of the textures it
// samples and by whether their sides are powers of two (Mesa, lp_state_fs.h:
// lp_fragment_shader_variant_key).
GLuint warm_up_texture_like(GLuint like, GLint format, int width = 3, int height = 3);
// The programs link_program and link_compute_program have linked in this
// process.
long linked_program_count();

// GL_LINEAR + CLAMP_TO_EDGE, no mipmaps: the arithmetic that
// physics/shader_cpp.hpp reproduces on the CPU.
void set_table_sampling(GLuint texture);

// A table texel rounded to half floats (IEEE 754 binary16), as GL_RGB16F
// tables store it: each channel to the nearest half float, except that with
// `srgb_channels` (the spectral mode's linear sRGB channels) no CIE XYZ
// coordinate may fall below min(0, the texel's own), so that faint light
// stays light (see the .cpp). Throws atmos::Error beyond the half-float range.
std::array<std::uint16_t, 3> half_texel_bits(const glm::vec3& texel, bool srgb_channels);
glm::vec3 half_texel(const glm::vec3& texel, bool srgb_channels);

// RGB tables as textures: 32-bit floats, or half floats rounded on the CPU
// (GL_RGB16F, half_texel_bits). Throws atmos::Error when the size exceeds
// the driver's limit.
GLuint make_texture_2d(int width, int height, const std::vector<glm::vec3>& texels, GLenum internal_format,
                       bool srgb_channels);
GLuint make_texture_3d(int width, int height, int depth, const std::vector<glm::vec3>& texels,
                       GLenum internal_format, bool srgb_channels);

// Whether an OpenGL context is current on the calling thread.
bool gl_context_is_current();
// Throws atmos::Error ("<who> needs a current OpenGL 4.5 core context ...")
// unless an OpenGL 4.5 context is current on the calling thread: every GL
// class checks this before its first GL call (without a context GL calls are
// no-ops or crash through a null dispatch).
void require_gl_context(const char* who);

// Throws atmos::Error naming the pending GL error, if any ("OpenGL error
// 0x0505 (GL_OUT_OF_MEMORY) while uploading the tables").
void check_gl(const char* when);
// Drops pending GL errors (from the engine, before a pass starts).
void clear_gl_errors();

// Whether the current context is a software rasteriser (llvmpipe, softpipe,
// SwiftShader): their timer queries time only the submission of the deferred
// rasterisation (llvmpipe reports ~3 % of the real time), so GpuTimer uses
// the wall clock up to glFinish there.
bool is_software_rasterizer();

// Time of GPU work between begin() and end_ms(): a GL_TIME_ELAPSED query, or
// on software rasterisers the wall clock up to glFinish (the time the "GPU",
// i.e. the CPU, spent). end_ms() waits for the work.
class GpuTimer {
 public:
  GpuTimer();
  ~GpuTimer();
  GpuTimer(const GpuTimer&) = delete;
  GpuTimer& operator=(const GpuTimer&) = delete;
  void begin();
  double end_ms();

 private:
  GLuint query_ = 0;
  bool software_ = false;
  std::chrono::steady_clock::time_point start_;
};

// Texture units of GpuTables::bind() (the layout(binding) of the shaders).
enum TableUnit : GLuint {
  kOpticalDepthUnit = 0,       // spectral optical depth (all wavelength triples side by side)
  kScatteringUnit = 1,         // single Rayleigh + multiple / P_R
  kSingleAerosolUnit = 2,      // single aerosol, phase-free
  kIrradianceUnit = 3,         // indirect (sky) irradiance
  kMultipleScatteringUnit = 4, // multiple scattering / P_R
  kSkyViewRayleighUnit = 5,    // this frame's sky-view table (functions.glsl: view_ray_terms)
  kSkyViewAerosolUnit = 6,
  kSkyViewSurfaceUnit = 7,
  kTableUnitCount = 8,
};

// The texture unit of the instant mode's multiple-scattering table in its
// sky-view and volume programs (instant_sky_view.frag.glsl).
constexpr GLuint kInstantMultipleScatteringUnit = 8;

// Uniform locations of the sky-view table's frame (table_bindings.glsl:
// uniform_sky_view_frame), the same in every program that reads the table.
constexpr GLint kSkyViewFrameLocation = 40;  // 40..44

// Sets those uniforms of `program` (a program without them ignores them).
void set_sky_view_frame_uniforms(GLuint program, const physics::SkyViewFrame& frame);

// The uniforms of the frame's moons (table_bindings.glsl: uniform_moons),
// the same in every program that draws eclipses.
constexpr GLint kMoonsLocation = 45;  // 45..49
void set_moons_uniforms(GLuint program, const physics::Moons& moons);

// The tables of one atmosphere on the GPU, its parameters as the shaders
// see them, and the per-frame sky-view table (functions.glsl: sky_view_frame)
// with its pass.
class GpuTables {
 public:
  GpuTables(const Atmosphere& atmosphere, const Tables& tables, TexturePrecision precision);
  // The instant mode's tables (InstantTables): the optical depth on unit 0,
  // the sky irradiance on unit 3, no 4D table (units 1, 2 and 4 unbound),
  // and its multiple-scattering table, which update_sky_view reads on
  // kInstantMultipleScatteringUnit.
  GpuTables(const Atmosphere& atmosphere, const InstantTables& tables);
  ~GpuTables();  // needs the context current
  GpuTables(const GpuTables&) = delete;
  GpuTables& operator=(const GpuTables&) = delete;

  const physics::AtmosphereParams& params() const { return *params_; }
  const physics::SpectralSets& spectral() const { return *spectral_; }
  // The tables' channels to linear sRGB on the cd/m² scale (column-major).
  const glm::mat3& radiance_to_srgb() const { return radiance_to_srgb_; }

  // Binds the five tables to units first_unit + 0..4, the sky-view table
  // to first_unit + 5..7 (see TableUnit) and the parameter block to
  // kParametersBinding.
  void bind(GLuint first_unit = 0) const;
  // Binds the buffer of the programs' parameter block (parameter_block:
  // ATMOSPHERE, SPECTRAL, the colour matrix) to a uniform-buffer binding.
  void bind_parameters(GLuint binding = kParametersBinding) const;
  // Binds what the programs that integrate along rays read (the sky-view
  // table's, the aerial-perspective volumes'): the five tables on units
  // 0..4 without sampler objects, the instant mode's multiple-scattering
  // table on kInstantMultipleScatteringUnit, and the parameter block.
  void bind_integration_inputs() const;
  GLuint texture(int index) const { return textures_[index]; }
  // Whether these are the instant mode's tables, and their multiple-scattering table.
  bool instant() const { return instant_multiple_scattering_ != 0; }
  GLuint instant_multiple_scattering_texture() const { return instant_multiple_scattering_; }
  GLuint sky_view_texture(int index) const { return sky_view_textures_[index]; }

  // Replaces the tables that depend on the ground's albedo (sky
  // irradiance, scattering, multiple scattering) with those of `set`, of the
  // same sizes (tables_for_ground_albedo).
  void replace_ground_dependent_tables(const TableSet& set);

  // The frame of the sky-view table for a camera (m, planet-centred, in the
  // atmosphere; below the ground counts as on it) and the sun's direction:
  // computed once per frame here, uploaded to the table's pass and to its
  // readers alike.
  physics::SkyViewFrame sky_view_frame(const glm::vec3& camera, const glm::vec3& sun) const;

  // Draws `program` (a sky-view program of sky_view_program's) once over 3x3
  // pixels of scratch targets of the table's formats in the CURRENT
  // context, with the state of update_sky_view: drivers that compile
  // machine code at the first draw compile it here (see
  // AtmospherePass::link_programs). It sets no uniform (other contexts may
  // be drawing with the program): the draw runs with those the program
  // holds, over pixels nobody reads.
  void warm_up_sky_view(GLuint program) const;
  // Computes this frame's sky-view table for a camera in the atmosphere
  // (camera_uses_sky_view) at `camera` (m, planet-centred) with the sun in
  // direction `sun`, in the frame `frame` (sky_view_frame); returns its GPU
  // time in ms (0 without a timer). Leaves the sky-view framebuffer bound and
  // the tables bound to units 0..4. With moons, the eclipsed table (the
  // frame must then have full_azimuth). The instant mode's tables compute
  // the instant mode's table (without moons).
  double update_sky_view(const glm::vec3& camera, const glm::vec3& sun, const physics::SkyViewFrame& frame,
                         GpuTimer* timer, const physics::Moons& moons = physics::no_moons());
  // The slot of the program update_sky_view draws with for that camera,
  // sun and moons (0 until linked), and a new link of that program (which
  // the caller stores in the slot): the variant without or with the low-sun
  // integration, or eclipsed. The link needs a current context of the
  // tables' share group, not necessarily the one that draws.
  GLuint& sky_view_program(const glm::vec3& camera, const glm::vec3& sun, const physics::Moons& moons);
  GLuint link_sky_view_program(const glm::vec3& camera, const glm::vec3& sun, const physics::Moons& moons) const;

 private:
  // bind_integration_inputs, and the sky-view table's own units unbound:
  // its programs draw to it.
  void bind_sky_view_inputs() const;

  void release();
  void create_sky_view_target();
  void create_parameter_buffer();
  std::unique_ptr<physics::AtmosphereParams> params_;
  std::unique_ptr<physics::SpectralSets> spectral_;
  glm::mat3 radiance_to_srgb_{1.0f};
  TableSizes sizes_;
  GLenum format_ = 0;  // of the radiance tables 1..4
  bool srgb_channels_ = false;  // physics::srgb_channels of the tables' wavelengths
  GLuint textures_[5] = {0, 0, 0, 0, 0};
  GLuint parameter_buffer_ = 0;  // parameter_block's values
  // Without, with the low-sun integration, and eclipsed (compiled on first use).
  GLuint sky_view_programs_[3] = {0, 0, 0};
  GLuint sky_view_framebuffer_ = 0;
  // Single Rayleigh + multiple / P_R, single aerosol, the ray's end (RGBA32F).
  GLuint sky_view_textures_[3] = {0, 0, 0};
  GLuint vertex_array_ = 0;
  // The instant mode: its multiple-scattering table, and its sky-view
  // programs without and with the low-sun transmittance.
  GLuint instant_multiple_scattering_ = 0;
  GLuint instant_sky_view_programs_[2] = {0, 0};
};

}  // namespace atmos::gpu
