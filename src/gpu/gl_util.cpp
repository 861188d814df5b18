#include "gpu/gl_util.hpp"

#include <glm/gtc/packing.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <functional>
#include <initializer_list>
#include <map>
#include <mutex>
#include <sstream>

#include "atmos/colour.hpp"
#include "data/glsl_prune.hpp"
#include "physics/parameters.hpp"

namespace atmos::gpu {

namespace {

std::string to_string(double x) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%g", x);
  return buffer;
}


// One line out of a compiler info log: the first error lines, with the line
// numbers of the assembled source mapped back to the files
// ("0:1234(12): error: ..." -> "functions.glsl:57(12): error: ...";
// also NVIDIA's "0(1234) : error" and AMD's "ERROR: 0:1234:").
std::string summarize_log(const std::string& log, const AssembledSource* source) {
  auto digits_end = [](const std::string& s, size_t i) {
    while (i < s.size() && s[i] >= '0' && s[i] <= '9') ++i;
    return i;
  };
  std::vector<std::string> errors;
  std::vector<std::string> others;
  std::istringstream lines(log);
  std::string line;
  while (std::getline(lines, line)) {
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ')) line.pop_back();
    if (line.empty()) continue;
    // "<string>:<line>" or "<string>(<line>" at the start, after an optional "ERROR: ".
    const size_t start = line.rfind("ERROR: ", 0) == 0 ? 7 : 0;
    const size_t separator = digits_end(line, start);
    if (source != nullptr && separator > start && separator < line.size() &&
        (line[separator] == ':' || line[separator] == '(')) {
      const size_t end = digits_end(line, separator + 1);
      if (end > separator + 1 && end - separator <= 9) {
        std::string where = source->locate(std::stoi(line.substr(separator + 1, end - separator - 1)));
        if (line[separator] == '(') where[where.rfind(':')] = '(';  // NVIDIA style: "file(line) : error"
        line = line.substr(0, start) + where + line.substr(end);
      }
    }
    (line.find("error") != std::string::npos || line.find("ERROR") != std::string::npos ? errors : others)
        .push_back(line);
  }
  const std::vector<std::string>& chosen = errors.empty() ? others : errors;
  std::string s;
  for (size_t i = 0; i < chosen.size() && i < 2; ++i) s += (i > 0 ? " | " : "") + chosen[i];
  if (s.empty()) s = "(empty info log)";
  return s;
}

GLuint compile_shader(GLenum type, const AssembledSource& source, const char* what) {
  GLuint shader = glCreateShader(type);
  // Only the functions the program uses: the driver's front end parses and
  // optimises every function it is given. The lines keep their numbers, so
  // the log still maps back through `source`.
  const std::string pruned = data::prune_unreferenced_functions(source.text);
  const char* text = pruned.c_str();
  glShaderSource(shader, 1, &text, nullptr);
  glCompileShader(shader);
  GLint ok = GL_FALSE;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetShaderInfoLog(shader, length, nullptr, log.data());
    glDeleteShader(shader);
    throw Error(std::string(what) + " shader does not compile: " + summarize_log(log.c_str(), &source));
  }
  return shader;
}

// Texel data for an upload: floats as they are, or rounded to half floats on
// the CPU (half_texel_bits). Rounding here rather than in the driver makes
// the GPU's texels the same on every driver, and lets the tests give the CPU
// twin exactly the same half-rounded tables (half_texel).
struct TexelData {
  GLenum type = GL_FLOAT;
  const void* pixels = nullptr;
  std::vector<std::uint16_t> halves;
};

TexelData texel_data(const std::vector<glm::vec3>& texels, GLenum internal_format, bool srgb_channels) {
  TexelData data;
  if (internal_format != GL_RGB16F) {
    data.pixels = texels.data();
    return data;
  }
  data.type = GL_HALF_FLOAT;
  data.halves.resize(texels.size() * 3);
  for (size_t i = 0; i < texels.size(); ++i) {
    const std::array<std::uint16_t, 3> bits = half_texel_bits(texels[i], srgb_channels);
    std::copy(bits.begin(), bits.end(), data.halves.begin() + std::ptrdiff_t(3 * i));
  }
  data.pixels = data.halves.data();
  return data;
}

// The half float next to `bits` towards +infinity (up) or -infinity (down);
// finite inputs only, which texel_data guarantees. Half floats of one sign
// are ordered as their bit patterns; the two zeros step to the smallest
// subnormal of either sign.
std::uint16_t next_half(std::uint16_t bits, bool up) {
  const bool negative = (bits & 0x8000u) != 0;
  if ((bits & 0x7fffu) == 0) return up ? std::uint16_t(0x0001u) : std::uint16_t(0x8001u);
  return std::uint16_t(up != negative ? bits + 1u : bits - 1u);
}

}  // namespace

std::array<std::uint16_t, 3> half_texel_bits(const glm::vec3& texel, bool srgb_channels) {
  std::array<std::uint16_t, 3> nearest;
  for (int c = 0; c < 3; ++c) {
    if (!(std::abs(texel[c]) <= 65504.0f))
      throw Error("table value " + to_string(double(texel[c])) +
                  " is outside the half-float range; render with full texture precision");
    nearest[size_t(c)] = glm::packHalf1x16(texel[c]);
  }
  if (!srgb_channels) return nearest;
  // Light has non-negative CIE 1931 XYZ coordinates (integrals of the
  // non-negative colour-matching functions), while its linear sRGB channels
  // may be negative out of the gamut. Rounding each channel on its own can
  // push a faint texel beyond the spectral locus: among subnormal half
  // floats the rounding is absolute, up to 2^-25 = 3e-8, against channels
  // of ~1e-6 at night. Each coordinate must stay at or above min(0, the
  // float texel's own). All entries of the sRGB-to-XYZ matrix (IEC
  // 61966-2-1) are positive, so the texel with all three channels rounded
  // up satisfies this; the nearest such texel among the eight around the
  // float one is used.
  const glm::dvec3 exact(texel);
  const glm::dvec3 floor_xyz = glm::min(srgb_to_xyz(exact), glm::dvec3(0.0));
  auto value = [](const std::array<std::uint16_t, 3>& h) {
    return glm::dvec3(glm::unpackHalf1x16(h[0]), glm::unpackHalf1x16(h[1]), glm::unpackHalf1x16(h[2]));
  };
  auto allowed = [&](const std::array<std::uint16_t, 3>& h) {
    return glm::all(glm::greaterThanEqual(srgb_to_xyz(value(h)), floor_xyz));
  };
  if (allowed(nearest)) return nearest;
  std::array<std::uint16_t, 3> below, above;
  for (size_t c = 0; c < 3; ++c) {
    const double rounded = glm::unpackHalf1x16(nearest[c]);
    below[c] = rounded <= exact[int(c)] ? nearest[c] : next_half(nearest[c], false);
    above[c] = rounded >= exact[int(c)] ? nearest[c] : next_half(nearest[c], true);
  }
  std::array<std::uint16_t, 3> best = above;
  double best_distance = glm::length(value(above) - exact);
  for (int corner = 0; corner < 8; ++corner) {
    std::array<std::uint16_t, 3> h;
    for (size_t c = 0; c < 3; ++c) h[c] = (corner >> c) & 1 ? above[c] : below[c];
    const double distance = glm::length(value(h) - exact);
    if (distance < best_distance && allowed(h)) {
      best = h;
      best_distance = distance;
    }
  }
  return best;
}

glm::vec3 half_texel(const glm::vec3& texel, bool srgb_channels) {
  const std::array<std::uint16_t, 3> bits = half_texel_bits(texel, srgb_channels);
  return {glm::unpackHalf1x16(bits[0]), glm::unpackHalf1x16(bits[1]), glm::unpackHalf1x16(bits[2])};
}

namespace {

std::atomic<long> programs_linked{0};

GLuint link_shaders(std::initializer_list<GLuint> shaders) {
  GLuint program = glCreateProgram();
  for (GLuint shader : shaders) glAttachShader(program, shader);
  glLinkProgram(program);
  // The program keeps the compiled code; the shader objects can go.
  for (GLuint shader : shaders) glDeleteShader(shader);
  GLint ok = GL_FALSE;
  glGetProgramiv(program, GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &length);
    std::string log(size_t(std::max(length, 1)), '\0');
    glGetProgramInfoLog(program, length, nullptr, log.data());
    glDeleteProgram(program);
    throw Error("shader program does not link: " + summarize_log(log.c_str(), nullptr));
  }
  programs_linked.fetch_add(1, std::memory_order_relaxed);
  return program;
}

}  // namespace

GLuint link_program(const AssembledSource& vertex_source, const AssembledSource& fragment_source) {
  GLuint vertex = compile_shader(GL_VERTEX_SHADER, vertex_source, "vertex");
  GLuint fragment = 0;
  try {
    fragment = compile_shader(GL_FRAGMENT_SHADER, fragment_source, "fragment");
  } catch (...) {
    glDeleteShader(vertex);
    throw;
  }
  return link_shaders({vertex, fragment});
}

GLuint link_compute_program(const AssembledSource& compute_source) {
  return link_shaders({compile_shader(GL_COMPUTE_SHADER, compute_source, "compute")});
}

long linked_program_count() { return programs_linked.load(std::memory_order_relaxed); }

namespace {

// The shared programs. A share group has no name in OpenGL, so each shared
// program carries a label unique in the process (GL 4.3 object labels):
// the program of an entry is the current context's when that context has a
// program of that name with that label, i.e. when it shares objects with the
// context that linked it. An entry lives while it has owners.
struct SharedPrograms {
  struct Entry {
    std::string key;
    GLuint program = 0;
    int owners = 0;
  };
  std::mutex mutex;
  long next_label = 0;
  std::map<std::string, Entry> by_label;
  std::multimap<std::string, std::string> labels_of_key;
};

SharedPrograms& shared_programs() {
  static SharedPrograms programs;
  return programs;
}

// The label of `program` in the current context ("" without one).
std::string program_label(GLuint program) {
  if (program == 0 || glIsProgram(program) != GL_TRUE) return "";
  char label[64] = {};
  GLsizei length = 0;
  glGetObjectLabel(GL_PROGRAM, program, GLsizei(sizeof label), &length, label);
  return std::string(label, size_t(std::max<GLsizei>(length, 0)));
}

GLuint acquire_program(const std::string& key, const std::function<GLuint()>& link) {
  SharedPrograms& shared = shared_programs();
  {
    std::lock_guard<std::mutex> lock(shared.mutex);
    const auto [first, last] = shared.labels_of_key.equal_range(key);
    for (auto i = first; i != last; ++i) {
      SharedPrograms::Entry& entry = shared.by_label.at(i->second);
      if (program_label(entry.program) == i->second) {
        ++entry.owners;
        return entry.program;
      }
    }
  }
  // Linking takes seconds on software rasterisers: not under the lock (two
  // threads may then link the same key; each gets an entry).
  const GLuint program = link();
  std::lock_guard<std::mutex> lock(shared.mutex);
  const std::string label = "atmos program " + std::to_string(shared.next_label++);
  glObjectLabel(GL_PROGRAM, program, GLsizei(label.size()), label.data());
  shared.by_label[label] = {key, program, 1};
  shared.labels_of_key.emplace(key, label);
  return program;
}

}  // namespace

GLuint shared_program(const AssembledSource& vertex_source, const AssembledSource& fragment_source) {
  return acquire_program("vertex\n" + vertex_source.text + "\nfragment\n" + fragment_source.text,
                         [&] { return link_program(vertex_source, fragment_source); });
}

GLuint shared_compute_program(const AssembledSource& compute_source) {
  return acquire_program("compute\n" + compute_source.text, [&] { return link_compute_program(compute_source); });
}

void set_full_screen_state() {
  glDisable(GL_BLEND);
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_STENCIL_TEST);
  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glDisable(GL_FRAMEBUFFER_SRGB);
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
}

GLuint warm_up_texture_like(GLuint like, GLint format, int width, int height) {
  GLint target = GL_TEXTURE_2D;
  GLint depth = 1;
  if (like != 0 && glIsTexture(like) == GL_TRUE) {
    glGetTextureParameteriv(like, GL_TEXTURE_TARGET, &target);
    glGetTextureLevelParameteriv(like, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
    glGetTextureLevelParameteriv(like, 0, GL_TEXTURE_WIDTH, &width);
    glGetTextureLevelParameteriv(like, 0, GL_TEXTURE_HEIGHT, &height);
    glGetTextureLevelParameteriv(like, 0, GL_TEXTURE_DEPTH, &depth);
  }
  const auto side = [](GLint n) { return n > 0 && (n & (n - 1)) == 0 ? 2 : 3; };
  GLuint texture = 0;
  glCreateTextures(GLenum(target), 1, &texture);
  if (target == GL_TEXTURE_3D)
    glTextureStorage3D(texture, 1, GLenum(format), side(width), side(height), side(depth));
  else
    glTextureStorage2D(texture, 1, GLenum(format), side(width), side(height));
  // The sampling state, also part of that key where no sampler object is bound.
  if (like != 0 && glIsTexture(like) == GL_TRUE) {
    for (const GLenum parameter : {GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER, GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T,
                                   GL_TEXTURE_WRAP_R, GL_TEXTURE_COMPARE_MODE, GL_TEXTURE_COMPARE_FUNC}) {
      GLint value = 0;
      glGetTextureParameteriv(like, parameter, &value);
      glTextureParameteri(texture, parameter, value);
    }
  }
  const bool depth_format = format == GL_DEPTH_COMPONENT16 || format == GL_DEPTH_COMPONENT24 ||
                            format == GL_DEPTH_COMPONENT32 || format == GL_DEPTH_COMPONENT32F;
  const bool depth_stencil = format == GL_DEPTH24_STENCIL8 || format == GL_DEPTH32F_STENCIL8;
  if (depth_format) {
    const float one = 1.0f;
    glClearTexImage(texture, 0, GL_DEPTH_COMPONENT, GL_FLOAT, &one);
  } else if (depth_stencil) {
    glClearTexImage(texture, 0, GL_DEPTH_STENCIL, GL_UNSIGNED_INT_24_8, nullptr);
  } else {
    glClearTexImage(texture, 0, GL_RGBA, GL_FLOAT, nullptr);
  }
  return texture;
}

void release_program(GLuint& program) {
  if (program == 0) return;
  bool last = true;
  {
    SharedPrograms& shared = shared_programs();
    std::lock_guard<std::mutex> lock(shared.mutex);
    const auto entry = shared.by_label.find(program_label(program));
    if (entry != shared.by_label.end()) {
      last = --entry->second.owners == 0;
      if (last) {
        const auto [first, end] = shared.labels_of_key.equal_range(entry->second.key);
        for (auto i = first; i != end; ++i)
          if (i->second == entry->first) {
            shared.labels_of_key.erase(i);
            break;
          }
        shared.by_label.erase(entry);
      }
    }
  }
  if (last) glDeleteProgram(program);
  program = 0;
}

void set_table_sampling(GLuint texture) {
  glTextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(texture, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glTextureParameteri(texture, GL_TEXTURE_WRAP_R, GL_CLAMP_TO_EDGE);
}

GLuint make_texture_2d(int width, int height, const std::vector<glm::vec3>& texels, GLenum internal_format,
                       bool srgb_channels) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_TEXTURE_SIZE, &max_size);
  if (width > max_size || height > max_size)
    throw Error("table of " + std::to_string(width) + "x" + std::to_string(height) +
                " texels exceeds GL_MAX_TEXTURE_SIZE " + std::to_string(max_size));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_2D, 1, &texture);
  // Rows of RGB half floats are 6 bytes per texel: not always 4-byte aligned.
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureStorage2D(texture, 1, internal_format, width, height);
  const TexelData data = texel_data(texels, internal_format, srgb_channels);
  glTextureSubImage2D(texture, 0, 0, 0, width, height, GL_RGB, data.type, data.pixels);
  set_table_sampling(texture);
  return texture;
}

GLuint make_texture_3d(int width, int height, int depth, const std::vector<glm::vec3>& texels,
                       GLenum internal_format, bool srgb_channels) {
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_size);
  if (width > max_size || height > max_size || depth > max_size)
    throw Error("table of " + std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(depth) +
                " texels exceeds GL_MAX_3D_TEXTURE_SIZE " + std::to_string(max_size));
  GLuint texture = 0;
  glCreateTextures(GL_TEXTURE_3D, 1, &texture);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureStorage3D(texture, 1, internal_format, width, height, depth);
  const TexelData data = texel_data(texels, internal_format, srgb_channels);
  glTextureSubImage3D(texture, 0, 0, 0, 0, width, height, depth, GL_RGB, data.type, data.pixels);
  set_table_sampling(texture);
  return texture;
}

void check_gl(const char* when) {
  GLenum error = glGetError();
  if (error == GL_NO_ERROR) return;
  while (glGetError() != GL_NO_ERROR) {
  }
  char code[16];
  std::snprintf(code, sizeof code, "0x%04X", error);
  const char* name = error == GL_OUT_OF_MEMORY       ? " (GL_OUT_OF_MEMORY)"
                     : error == GL_INVALID_OPERATION ? " (GL_INVALID_OPERATION)"
                     : error == GL_INVALID_VALUE     ? " (GL_INVALID_VALUE)"
                     : error == GL_INVALID_ENUM      ? " (GL_INVALID_ENUM)"
                                                     : "";
  throw Error(std::string("OpenGL error ") + code + name + " " + when);
}


void clear_gl_errors() {
  while (glGetError() != GL_NO_ERROR) {
  }
}

bool gl_context_is_current() { return epoxy_gl_version() > 0; }

void require_gl_context(const char* who) {
  const int version = epoxy_gl_version();
  if (version < 45)
    throw Error(std::string(who) + " needs a current OpenGL 4.5 core context (" +
                (version == 0 ? std::string("none is current") :
                                "found version " + std::to_string(version / 10) + "." + std::to_string(version % 10)) +
                ")");
}

bool is_software_rasterizer() {
  const GLubyte* name = glGetString(GL_RENDERER);
  const std::string renderer_name = name != nullptr ? reinterpret_cast<const char*>(name) : "";
  for (const char* software : {"llvmpipe", "softpipe", "SwiftShader", "swrast"})
    if (renderer_name.find(software) != std::string::npos) return true;
  return false;
}

GpuTimer::GpuTimer() : software_(is_software_rasterizer()) {
  if (!software_) glCreateQueries(GL_TIME_ELAPSED, 1, &query_);
}

GpuTimer::~GpuTimer() {
  if (query_ != 0) glDeleteQueries(1, &query_);
}

void GpuTimer::begin() {
  if (software_) {
    // Work queued before belongs to someone else.
    glFinish();
    start_ = std::chrono::steady_clock::now();
  } else {
    glBeginQuery(GL_TIME_ELAPSED, query_);
  }
}

double GpuTimer::end_ms() {
  if (software_) {
    glFinish();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }
  glEndQuery(GL_TIME_ELAPSED);
  GLuint64 nanoseconds = 0;
  glGetQueryObjectui64v(query_, GL_QUERY_RESULT, &nanoseconds);
  return double(nanoseconds) * 1e-6;
}

// --- The tables on the GPU -------------------------------------------------

// The sky-view table: recomputed every frame, read with GL_LINEAR +
// CLAMP_TO_EDGE like the precomputed tables.
void GpuTables::create_sky_view_target() {
  glCreateTextures(GL_TEXTURE_2D, 3, sky_view_textures_);
  glCreateFramebuffers(1, &sky_view_framebuffer_);
  for (int i = 0; i < 3; ++i) {
    glTextureStorage2D(sky_view_textures_[i], 1, GL_RGBA32F, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT);
    set_table_sampling(sky_view_textures_[i]);
    glNamedFramebufferTexture(sky_view_framebuffer_, GLenum(GL_COLOR_ATTACHMENT0 + i), sky_view_textures_[i], 0);
  }
  const GLenum attachments[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  glNamedFramebufferDrawBuffers(sky_view_framebuffer_, 3, attachments);
  check_gl("while creating the sky-view table");
  if (glCheckNamedFramebufferStatus(sky_view_framebuffer_, GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw Error("the RGBA32F sky-view target is not supported by this OpenGL driver");
  // Core profile draws need a vertex array object, even an empty one.
  glCreateVertexArrays(1, &vertex_array_);
}

// The parameter block's values, uploaded once: every program of these
// tables reads them at draw time (ParameterBlock, shader_source.hpp).
void GpuTables::create_parameter_buffer() {
  const ParameterBlock block = parameter_block(*params_, *spectral_, radiance_to_srgb_);
  const GLsizeiptr bytes = GLsizeiptr(block.values.size() * sizeof(float));
  GLint max_bytes = 0;
  glGetIntegerv(GL_MAX_UNIFORM_BLOCK_SIZE, &max_bytes);
  if (bytes > max_bytes)
    throw Error("the atmosphere's parameters take " + std::to_string(bytes) +
                " bytes, more than this driver's GL_MAX_UNIFORM_BLOCK_SIZE " + std::to_string(max_bytes) +
                " (fewer wavelengths would fit)");
  glCreateBuffers(1, &parameter_buffer_);
  glNamedBufferStorage(parameter_buffer_, bytes, block.values.data(), 0);
  check_gl("while uploading the atmosphere's parameters");
}

void GpuTables::bind_parameters(GLuint binding) const {
  glBindBufferBase(GL_UNIFORM_BUFFER, binding, parameter_buffer_);
}

GpuTables::GpuTables(const Atmosphere& atmosphere, const InstantTables& tables) {
  check_tables_match(atmosphere, tables);
  params_ = std::make_unique<physics::AtmosphereParams>(physics::make_render_params(atmosphere, tables.sizes));
  spectral_ = physics::make_spectral_sets(atmosphere, tables.sizes);
  radiance_to_srgb_ = physics::channels_to_srgb_matrix(tables.wavelengths_nm);
  clear_gl_errors();
  try {
    create_sky_view_target();
    create_parameter_buffer();
    const TableSizes& s = tables.sizes;
    sizes_ = s;
    format_ = GL_RGB32F;
    srgb_channels_ = physics::srgb_channels(tables.wavelengths_nm);
    textures_[0] = make_texture_2d(s.transmittance_mu * tables.transmittance_tiles(), s.transmittance_r,
                                   tables.spectral_optical_depth, GL_RGB32F, false);
    textures_[3] = make_texture_2d(s.irradiance_mu_s, s.irradiance_r, tables.indirect_irradiance, GL_RGB32F, false);
    instant_multiple_scattering_ =
        make_texture_2d(tables.multiple_scattering_mu_s * tables.spectral_sets(), tables.multiple_scattering_r,
                        tables.multiple_scattering, GL_RGB32F, false);
    check_gl("while uploading the instant tables");
  } catch (...) {
    release();
    throw;
  }
}

GpuTables::GpuTables(const Atmosphere& atmosphere, const Tables& tables, TexturePrecision precision) {
  check_tables_match(atmosphere, tables);
  params_ = std::make_unique<physics::AtmosphereParams>(physics::make_render_params(atmosphere, tables.sizes));
  spectral_ = physics::make_spectral_sets(atmosphere, tables.sizes);
  radiance_to_srgb_ = physics::channels_to_srgb_matrix(tables.wavelengths_nm);
  clear_gl_errors();
  try {
    create_sky_view_target();
    create_parameter_buffer();

    const TableSizes& s = tables.sizes;
    const TableSet& t = tables.set;
    const GLenum format = precision == TexturePrecision::half ? GL_RGB16F : GL_RGB32F;
    sizes_ = s;
    format_ = format;
    srgb_channels_ = physics::srgb_channels(tables.wavelengths_nm);
    // The optical depth of every wavelength triple, side by side (32-bit
    // whatever the precision, see TexturePrecision).
    textures_[0] = make_texture_2d(s.transmittance_mu * tables.transmittance_tiles(), s.transmittance_r,
                                   tables.spectral_optical_depth, GL_RGB32F, false);
    textures_[1] = make_texture_3d(tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                                   t.scattering, format, srgb_channels_);
    textures_[2] = make_texture_3d(tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                                   t.single_aerosol, format, srgb_channels_);
    textures_[3] = make_texture_2d(s.irradiance_mu_s, s.irradiance_r, t.indirect_irradiance, format,
                                   srgb_channels_);
    textures_[4] = make_texture_3d(tables.scattering_width(), tables.scattering_height(), tables.scattering_depth(),
                                   t.multiple_scattering, format, srgb_channels_);
    check_gl("while uploading the tables");
  } catch (...) {
    release();
    throw;
  }
}

GpuTables::~GpuTables() { release(); }

void GpuTables::replace_ground_dependent_tables(const TableSet& set) {
  const TableSizes& s = sizes_;
  const int width = s.scattering_nu * s.scattering_mu_s;
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  const TexelData irradiance = texel_data(set.indirect_irradiance, format_, srgb_channels_);
  glTextureSubImage2D(textures_[3], 0, 0, 0, s.irradiance_mu_s, s.irradiance_r, GL_RGB, irradiance.type,
                      irradiance.pixels);
  for (const auto& [index, texels] : {std::pair{1, &set.scattering}, std::pair{4, &set.multiple_scattering}}) {
    const TexelData data = texel_data(*texels, format_, srgb_channels_);
    glTextureSubImage3D(textures_[index], 0, 0, 0, 0, width, s.scattering_mu, s.scattering_r, GL_RGB, data.type,
                        data.pixels);
  }
  check_gl("while replacing the ground-dependent tables");
}

void GpuTables::release() {
  for (GLuint& program : sky_view_programs_) release_program(program);
  for (GLuint& program : instant_sky_view_programs_) release_program(program);
  if (parameter_buffer_ != 0) glDeleteBuffers(1, &parameter_buffer_);
  parameter_buffer_ = 0;
  if (instant_multiple_scattering_ != 0) glDeleteTextures(1, &instant_multiple_scattering_);
  instant_multiple_scattering_ = 0;
  if (sky_view_framebuffer_ != 0) glDeleteFramebuffers(1, &sky_view_framebuffer_);
  if (vertex_array_ != 0) glDeleteVertexArrays(1, &vertex_array_);
  glDeleteTextures(3, sky_view_textures_);
  glDeleteTextures(5, textures_);
  sky_view_framebuffer_ = vertex_array_ = 0;
  for (GLuint& t : sky_view_textures_) t = 0;
  for (GLuint& t : textures_) t = 0;
}

void GpuTables::bind(GLuint first_unit) const {
  for (GLuint unit = 0; unit < 5; ++unit) glBindTextureUnit(first_unit + unit, textures_[unit]);
  glBindTextureUnit(first_unit + kSkyViewRayleighUnit, sky_view_textures_[0]);
  glBindTextureUnit(first_unit + kSkyViewAerosolUnit, sky_view_textures_[1]);
  glBindTextureUnit(first_unit + kSkyViewSurfaceUnit, sky_view_textures_[2]);
  bind_parameters();
}

physics::SkyViewFrame GpuTables::sky_view_frame(const glm::vec3& camera, const glm::vec3& sun) const {
  return physics::sky_view_frame(*params_, physics::camera_above_ground(*params_, camera), sun);
}

void set_sky_view_frame_uniforms(GLuint program, const physics::SkyViewFrame& frame) {
  glProgramUniform3fv(program, kSkyViewFrameLocation + 0, 1, &frame.zenith.x);
  glProgramUniform3fv(program, kSkyViewFrameLocation + 1, 1, &frame.sun_side.x);
  glProgramUniform3fv(program, kSkyViewFrameLocation + 2, 1, &frame.across.x);
  glProgramUniform1f(program, kSkyViewFrameLocation + 3, frame.theta_horizon);
  glProgramUniform1i(program, kSkyViewFrameLocation + 4, frame.full_azimuth ? 1 : 0);
}

void set_moons_uniforms(GLuint program, const physics::Moons& moons) {
  glProgramUniform1i(program, kMoonsLocation + 0, moons.count);
  glProgramUniform4fv(program, kMoonsLocation + 1, MOON_CAPACITY, &moons.sphere[0].x);
}

namespace {

// The sky-view variant of a frame: eclipsed with moons, else with the
// low-sun integration where the sun may be low on some view ray.
bool sky_view_low_sun(const physics::AtmosphereParams& params, const glm::vec3& camera, const glm::vec3& sun,
                      const physics::Moons& moons) {
  return moons.count > 0 || physics::sun_may_be_low_on_view_rays(params, camera, sun);
}

}  // namespace

GLuint& GpuTables::sky_view_program(const glm::vec3& camera, const glm::vec3& sun, const physics::Moons& moons) {
  const bool eclipse = moons.count > 0;
  if (instant() && eclipse) throw Error("the instant mode's sky-view table has no eclipses");
  const bool low_sun = sky_view_low_sun(*params_, camera, sun, moons);
  return instant() ? instant_sky_view_programs_[low_sun ? 1 : 0] : sky_view_programs_[eclipse ? 2 : low_sun ? 1 : 0];
}

GLuint GpuTables::link_sky_view_program(const glm::vec3& camera, const glm::vec3& sun,
                                        const physics::Moons& moons) const {
  const bool eclipse = moons.count > 0;
  if (instant() && eclipse) throw Error("the instant mode's sky-view table has no eclipses");
  const bool low_sun = sky_view_low_sun(*params_, camera, sun, moons);
  AssembledSource vertex;
  vertex.append("vertex shader", fullscreen_vertex_shader_source());
  return shared_program(vertex, instant() ? instant_sky_view_fragment_shader_source(*params_, *spectral_, low_sun)
                                          : sky_view_fragment_shader_source(*params_, *spectral_, low_sun, eclipse));
}

void GpuTables::bind_integration_inputs() const {
  for (GLuint unit = 0; unit < 5; ++unit) {
    glBindTextureUnit(unit, textures_[unit]);
    glBindSampler(unit, 0);
  }
  bind_parameters();
  if (instant()) {
    glBindTextureUnit(kInstantMultipleScatteringUnit, instant_multiple_scattering_);
    glBindSampler(kInstantMultipleScatteringUnit, 0);
  }
}

void GpuTables::bind_sky_view_inputs() const {
  bind_integration_inputs();
  // The table's own textures must not be bound for reading while drawn to.
  for (GLuint unit : {kSkyViewRayleighUnit, kSkyViewAerosolUnit, kSkyViewSurfaceUnit}) glBindTextureUnit(unit, 0);
}

void GpuTables::warm_up_sky_view(GLuint program) const {
  GLuint textures[3] = {0, 0, 0};
  GLuint framebuffer = 0, vertex_array = 0;
  for (int i = 0; i < 3; ++i) textures[i] = warm_up_texture_like(sky_view_textures_[i], GL_RGBA32F);
  glCreateFramebuffers(1, &framebuffer);
  const GLenum buffers[3] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1, GL_COLOR_ATTACHMENT2};
  for (int i = 0; i < 3; ++i) glNamedFramebufferTexture(framebuffer, buffers[i], textures[i], 0);
  glNamedFramebufferDrawBuffers(framebuffer, 3, buffers);
  glCreateVertexArrays(1, &vertex_array);
  glUseProgram(program);
  bind_sky_view_inputs();
  set_full_screen_state();
  glBindVertexArray(vertex_array);
  glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
  glViewport(0, 0, 3, 3);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glBindVertexArray(0);
  glDeleteVertexArrays(1, &vertex_array);
  glDeleteFramebuffers(1, &framebuffer);
  glDeleteTextures(3, textures);
}

double GpuTables::update_sky_view(const glm::vec3& camera, const glm::vec3& sun, const physics::SkyViewFrame& frame,
                                  GpuTimer* timer, const physics::Moons& moons) {
  const bool eclipse = moons.count > 0;
  GLuint& program = sky_view_program(camera, sun, moons);
  if (program == 0) program = link_sky_view_program(camera, sun, moons);
  glUseProgram(program);
  glProgramUniform3f(program, 0, camera.x, camera.y, camera.z);
  glProgramUniform3f(program, 7, sun.x, sun.y, sun.z);
  set_sky_view_frame_uniforms(program, frame);
  if (eclipse) set_moons_uniforms(program, moons);
  bind_sky_view_inputs();
  glBindVertexArray(vertex_array_);
  glBindFramebuffer(GL_FRAMEBUFFER, sky_view_framebuffer_);
  glViewport(0, 0, SKY_VIEW_WIDTH, SKY_VIEW_HEIGHT);
  if (timer == nullptr) {
    glDrawArrays(GL_TRIANGLES, 0, 3);
    return 0.0;
  }
  timer->begin();
  glDrawArrays(GL_TRIANGLES, 0, 3);
  return timer->end_ms();
}

}  // namespace atmos::gpu
