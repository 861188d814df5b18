#include "gpu/shader_source.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "atmos/atmosphere.hpp"
#include "data/embedded_files.hpp"

namespace atmos::gpu {

namespace {

// The generator below spells every field of AtmosphereParams in declaration
// order (GLSL struct constructors are positional). A field added to or
// removed from definitions.glsl changes the size and stops the build here
// rather than producing a shader with shifted parameters; a reordering of
// same-typed fields is caught by the GPU's read-back of every field
// (tests/gpu_test.cpp, Gpu.ParameterBlockMatchesTheDriversLayout).
static_assert(sizeof(physics::DensityProfile) == 4 * (2 + 2 * MAX_DENSITY_KNOTS),
              "DensityProfile changed: update glsl_density_profile()");
static_assert(sizeof(physics::AtmosphereParams) ==
                  4 * (3 + 1 + 3 * 3 + 2 * 3 + 2 + 8 + 6 + SCATTERING_R_AXIS_KNOTS + 2) +
                      MAX_CONSTITUENTS * (sizeof(physics::DensityProfile) + 4 * (3 + 3 + 1)),
              "AtmosphereParams changed: update atmosphere_params_expression()");

std::string glsl_int(int value) { return std::to_string(value); }

// "T[n](a, b, ...)" from n already formatted elements.
template <typename Format>
std::string glsl_array(const char* type, int n, Format element) {
  std::string s = std::string(type) + "[" + std::to_string(n) + "](";
  for (int i = 0; i < n; ++i) s += (i > 0 ? ", " : "") + element(i);
  return s + ")";
}

const char* embedded(const char* path) {
  const char* text = data::embedded_file(path);
  // Only a build that forgot to embed the file gets here.
  if (text == nullptr) throw Error(std::string("shader source not embedded in this build: ") + path);
  return text;
}

}  // namespace

std::string glsl_float(float value) {
  if (!std::isfinite(value)) throw Error("atmosphere parameter is not finite (" + std::to_string(value) + ")");
  char buffer[32];
  // 9 significant digits identify every float (FLT_DECIMAL_DIG).
  std::snprintf(buffer, sizeof buffer, "%.9g", double(value));
  std::string s = buffer;
  // "6371000" or "-2" would be int literals. GLSL 4.50 converts them where a
  // float is expected, but GLSL ES and stricter front ends do not: spell
  // every float as a float.
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

namespace {

// The float values of a parameter block in the order of their first use,
// and the GLSL that reads each: value i is component i % 4 of element i / 4
// of the block's vec4 array (std140 gives a vec4 array a stride of 16 bytes,
// so the packing is the floats back to back).
class BlockWriter {
 public:
  std::string value(float v) {
    if (!std::isfinite(v)) throw Error("atmosphere parameter is not finite (" + std::to_string(v) + ")");
    const size_t i = values.size();
    values.push_back(v);
    return std::string(kParameterArray) + "[" + std::to_string(i / 4) + "]." + "xyzw"[i % 4];
  }
  // A value whose zero the shaders test for (a weight that switches a
  // mapping off): zero is a literal, which the compiler folds, and belongs
  // to the atmosphere's structure; any other value is read from the block.
  std::string value_or_zero(float v) { return v == 0.0f ? "0.0" : value(v); }
  std::string vec3(const physics::vec3& v) {
    return "vec3(" + value(v.x) + ", " + value(v.y) + ", " + value(v.z) + ")";
  }
  // A constituent's coefficients: a literal when all three are zero (an
  // absorber that does not scatter, a scatterer that does not absorb), so
  // that the compiler drops their terms from the medium's sums.
  std::string coefficients(const physics::vec3& v) {
    return v == physics::vec3(0.0f) ? std::string("vec3(0.0)") : vec3(v);
  }
  std::string mat3(const physics::mat3& m) {
    std::string s = "mat3(";
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) s += value(m[c][r]) + (c == 2 && r == 2 ? ")" : ", ");
    return s;
  }
  // A wavelength triple's conversion to the tables' channels: the identity
  // of the three-wavelength mode is a literal.
  std::string to_channels(const physics::mat3& m) {
    return m == physics::mat3(1.0f) ? std::string("mat3(1.0)") : mat3(m);
  }
  std::vector<float> values;
};

// "DensityProfile(...)": the kind and the knot count are literals; the
// scale height of an exponential profile and the knots of a piecewise-linear
// one are values (the other fields are never read and spelt 0).
std::string glsl_density_profile(const physics::DensityProfile& d, BlockWriter& w) {
  const bool exponential = d.knot_count == 0;
  const auto knots = [&](const float* x) {
    return glsl_array("float", MAX_DENSITY_KNOTS,
                      [&](int i) { return !exponential && i < d.knot_count ? w.value(x[i]) : std::string("0.0"); });
  };
  return "DensityProfile(" + (exponential ? w.value(d.scale_height) : std::string("0.0")) + ", " +
         glsl_int(d.knot_count) + ", " + knots(d.knot_altitude) + ", " + knots(d.knot_density) + ")";
}

// "AtmosphereParams(...)", every field in declaration order: the integers
// (counts, kinds, table sizes, tiles) as literals, the floats as values of
// the block.
std::string atmosphere_params_expression(const physics::AtmosphereParams& p, BlockWriter& w) {
  const int n = MAX_CONSTITUENTS;
  const int count = p.constituent_count;
  // Constituents beyond the count are never read (CONSTITUENT_COUNT).
  const auto constituent_vec3 = [&](const physics::vec3* v) {
    return glsl_array("vec3", n, [&](int i) { return i < count ? w.coefficients(v[i]) : std::string("vec3(0.0)"); });
  };
  std::string s = "AtmosphereParams(\n";
  s += "    " + w.value(p.bottom_radius) + ", " + w.value(p.top_radius) + ", " + glsl_int(count) + ",\n";
  s += "    " + glsl_array("DensityProfile", n, [&](int i) {
         const std::string zeros = glsl_array("float", MAX_DENSITY_KNOTS, [](int) { return std::string("0.0"); });
         return i < count ? glsl_density_profile(p.density[i], w)
                          : "DensityProfile(0.0, 0, " + zeros + ", " + zeros + ")";
       }) + ",\n";
  s += "    " + constituent_vec3(p.scattering) + ",\n";
  s += "    " + constituent_vec3(p.absorption) + ",\n";
  s += "    " + glsl_array("int", n, [&](int i) { return glsl_int(i < count ? p.is_aerosol[i] : 0); }) + ",\n";
  s += "    " + glsl_int(p.aerosol_phase_kind) + ", " + w.vec3(p.aerosol_g) + ", " + w.vec3(p.aerosol_g_back) + ", " +
       w.vec3(p.aerosol_forward_weight) + ",\n";
  s += "    " + w.vec3(p.ground_albedo) + ", " + w.vec3(p.solar_irradiance) + ",\n";
  s += "    " + w.value(p.sun_angular_radius) + ", " + w.value(p.mu_s_min) + ",\n";
  s += "    " + glsl_int(p.transmittance_mu_size) + ", " + glsl_int(p.transmittance_r_size) + ", " +
       glsl_int(p.irradiance_mu_s_size) + ", " + glsl_int(p.irradiance_r_size) + ", " +
       glsl_int(p.scattering_nu_size) + ", " + glsl_int(p.scattering_mu_s_size) + ", " +
       glsl_int(p.scattering_mu_size) + ", " + glsl_int(p.scattering_r_size) + ",\n";
  s += "    " + glsl_int(p.transmittance_tile) + ", " + glsl_int(p.transmittance_tiles) + ", " +
       glsl_int(p.single_scattering_tile) + ", " + glsl_int(p.scattering_nu_in_angle) + ", " +
       w.value_or_zero(p.scattering_mu_log_weight) + ",\n";
  // The r axis's knots are read only where its weight is not 0.
  const bool r_axis = p.scattering_r_optical_depth_weight != 0.0f;
  s += "    " + w.value_or_zero(p.scattering_r_optical_depth_weight) + ", " +
       glsl_array("float", SCATTERING_R_AXIS_KNOTS,
                  [&](int i) { return r_axis ? w.value(p.scattering_r_axis[i]) : std::string("0.0"); }) +
       ",\n";
  s += "    " + w.value_or_zero(p.source_flat_optical_depth) + ", " + w.value(p.scattering_row_1_height) + ")";
  return s;
}

}  // namespace

// The block's values: the colour matrix of glsl_library, then ATMOSPHERE,
// then SPECTRAL.
ParameterBlock parameter_block(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                               const physics::mat3& radiance_to_srgb, int binding) {
  BlockWriter w;
  const std::string matrix = w.mat3(radiance_to_srgb);
  const std::string atmosphere = atmosphere_params_expression(params, w);
  const int n = spectral.count;
  const std::string sets =
      glsl_array("AtmosphereParams", n, [&](int i) { return atmosphere_params_expression(spectral.set[i], w); });
  const std::string to_channels =
      glsl_array("mat3", n, [&](int i) { return w.to_channels(spectral.to_channels[i]); });
  const size_t elements = std::max<size_t>(1, (w.values.size() + 3) / 4);
  ParameterBlock block;
  block.glsl = "layout(std140, binding = " + std::to_string(binding) + ") uniform " + kParameterBlock + " { vec4 " +
               kParameterArray + "[" + std::to_string(elements) + "]; };\n" +
               "mat3 atmos_radiance_to_srgb() { return " + matrix + "; }\n" +
               "AtmosphereParams atmos_atmosphere() {\n  return " + atmosphere + ";\n}\n" +
               "SpectralSets atmos_spectral_sets() {\n  return SpectralSets(" + glsl_int(n) + ",\n" + sets + ",\n" +
               to_channels + ");\n}\n" +
               "#define ATMOSPHERE atmos_atmosphere()\n#define SPECTRAL atmos_spectral_sets()\n";
  block.values = std::move(w.values);
  block.values.resize(elements * 4, 0.0f);
  return block;
}

std::string fullscreen_vertex_shader_source() {
  return "#version 450 core\n"
         "// Vertices (-1,-1), (3,-1), (-1,3): one triangle that covers the viewport.\n"
         "void main() {\n"
         "  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
         "  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n"
         "}\n";
}

void AssembledSource::append(const std::string& name, const std::string& part_text) {
  const int line = 1 + int(std::count(text.begin(), text.end(), '\n'));
  parts.push_back({line, name});
  text += part_text;
  if (!text.empty() && text.back() != '\n') text += '\n';
}

std::string AssembledSource::locate(int line) const {
  for (size_t i = parts.size(); i-- > 0;)
    if (line >= parts[i].first_line) return parts[i].name + ":" + std::to_string(line - parts[i].first_line + 1);
  return "line " + std::to_string(line);
}

// No #line directives: Mesa 22 reports source string 0 whatever "#line 1 N"
// sets, while drivers agree on counting the lines of the whole string, which
// locate() maps back to the files.
namespace {

// The GLSL meaning of the subset macros (the C++ one is in physics/shader_cpp.hpp).
const char* const kSubsetMacros =
    "#define IN(T) in T\n#define OUT(T) out T\n#define INOUT(T) inout T\n#define INLINE\n";

// The plugin's per-pixel part after the physics: the table bindings, the
// pixel ray and composite.glsl (the pass's fragment and compute shaders).
void append_composite(AssembledSource& s) {
  s.append("table_bindings.glsl", embedded("src/gpu/table_bindings.glsl"));
  s.append("pixel_ray.glsl", embedded("src/gpu/pixel_ray.glsl"));
  s.append("composite.glsl", embedded("src/gpu/composite.glsl"));
}

// The most knots of the atmosphere's piecewise-linear density profiles (at
// least 1): the trip count of profile_density's loop in shaders.
int density_knot_bound(const physics::AtmosphereParams& params) {
  int bound = 1;
  for (int i = 0; i < params.constituent_count; ++i) bound = std::max(bound, params.density[i].knot_count);
  return bound;
}

// The parts of the physics (src/physics/*.glsl) that each program uses, in
// the order of their dependencies (definitions.glsl lists the parts, and each
// names the parts it needs at its top).
// The sky-view table (sky_view.frag.glsl): the light of view rays.
const std::vector<const char*> kSkyViewPhysics = {
    "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "sky_view_table.glsl"};
// The renderer (render.frag.glsl): everything that reaches the camera.
const std::vector<const char*> kRenderPhysics = {
    "stars.glsl", "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "sky_view_table.glsl", "radiance_to_camera.glsl"};
// The engine plugin's pass and its volume (composite.glsl): the same and
// the aerial perspective.
const std::vector<const char*> kCompositePhysics = {
    "stars.glsl", "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "sky_view_table.glsl", "radiance_to_camera.glsl",
    "aerial_perspective.glsl"};
// The instant mode's sky-view table and volume (instant_sky_view.frag.glsl,
// instant_aerial_perspective.comp.glsl): the same and the instant mode's march.
const std::vector<const char*> kInstantSkyViewPhysics = {
    "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "sky_view_table.glsl", "instant_atmosphere.glsl"};
const std::vector<const char*> kInstantCompositePhysics = {
    "stars.glsl", "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "sky_view_table.glsl", "radiance_to_camera.glsl",
    "aerial_perspective.glsl", "instant_atmosphere.glsl"};
// The GLSL library for engines (engine_library.glsl): the sky along a ray,
// the aerial perspective, the irradiance of surfaces, the eclipse factors.
const std::vector<const char*> kEngineLibraryPhysics = {
    "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "aerial_perspective.glsl"};
// The same for a pass of the instant mode, with its march along the rays.
const std::vector<const char*> kInstantEngineLibraryPhysics = {
    "eclipse.glsl", "ray_geometry.glsl", "medium.glsl", "table_coordinates.glsl", "table_lookups.glsl",
    "ray_integration.glsl", "view_ray_scattering.glsl", "sky_view_table.glsl", "aerial_perspective.glsl",
    "instant_atmosphere.glsl"};

// The part every program that reads the tables starts with: the version, the
// subset macros, definitions.glsl, the atmosphere's parameter block
// (parameter_block at `parameters_binding`), then the parts of the physics
// `physics` (names in src/physics/).
AssembledSource physics_shader_source(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                      const std::vector<const char*>& physics,
                                      const std::string& header = "#version 450 core\n",
                                      int parameters_binding = kParametersBinding) {
  AssembledSource s;
  s.append("header", header);
  s.append("macros", kSubsetMacros);
  // Shaders only run the run-time integration (see RAY_MAP_CAPACITY).
  s.append("capacities", "#define RAY_ARRAYS_FOR_RUNTIME\n#define SPECTRAL_SET_CAPACITY " +
                             std::to_string(spectral.count) + "\n#define SPECTRAL_COUNT(s) SPECTRAL_SET_CAPACITY\n" +
                             "#define CONSTITUENT_COUNT(a) " + std::to_string(params.constituent_count) + "\n" +
                             "#define DENSITY_KNOT_BOUND " + std::to_string(density_knot_bound(params)) + "\n");
  s.append("definitions.glsl", embedded("src/physics/definitions.glsl"));
  // The block's text does not depend on the colour matrix's values.
  s.append("parameters", parameter_block(params, spectral, physics::mat3(1.0f), parameters_binding).glsl);
  for (const char* part : physics) s.append(part, embedded((std::string("src/physics/") + part).c_str()));
  return s;
}

}  // namespace

AssembledSource render_fragment_shader_source(const physics::AtmosphereParams& params,
                                              const physics::SpectralSets& spectral, bool sky_view_camera,
                                              bool eclipse) {
  AssembledSource s = physics_shader_source(params, spectral, kRenderPhysics);
  s.append("variant", std::string("#define SKY_VIEW_CAMERA ") + (sky_view_camera ? "true" : "false") +
                          "\n#define RENDER_ECLIPSE " + (eclipse ? "1" : "0") + "\n");
  s.append("table_bindings.glsl", embedded("src/gpu/table_bindings.glsl"));
  s.append("camera.glsl", embedded("src/gpu/camera.glsl"));
  s.append("render.frag.glsl", embedded("src/gpu/render.frag.glsl"));
  return s;
}

AssembledSource sky_view_fragment_shader_source(const physics::AtmosphereParams& params,
                                                const physics::SpectralSets& spectral, bool low_sun,
                                                bool eclipse) {
  AssembledSource s = physics_shader_source(params, spectral, kSkyViewPhysics);
  s.append("variant", std::string("#define SKY_VIEW_LOW_SUN ") + (low_sun ? "true" : "false") +
                          "\n#define SKY_VIEW_ECLIPSE " + (eclipse ? "1" : "0") + "\n");
  s.append("table_bindings.glsl", embedded("src/gpu/table_bindings.glsl"));
  s.append("sky_view.frag.glsl", embedded("src/gpu/sky_view.frag.glsl"));
  return s;
}

AssembledSource atmosphere_pass_fragment_shader_source(const physics::AtmosphereParams& params,
                                                      const physics::SpectralSets& spectral,
                                                      const PassVariant& variant) {
  // The classifying program of all classes at once exports its stencil
  // value (an extension's directive precedes every other token).
  const bool export_stencil = variant.pixels == PassVariant::Pixels::classify_all;
  const bool instant = variant.pixels == PassVariant::Pixels::instant_space;
  AssembledSource s = physics_shader_source(
      params, spectral, instant ? kInstantCompositePhysics : kCompositePhysics,
      export_stencil ? "#version 450 core\n#extension GL_ARB_shader_stencil_export : require\n"
                     : "#version 450 core\n");
  auto flag = [](bool b) { return b ? "true" : "false"; };
  s.append("variant", std::string("#define SKY_VIEW_CAMERA ") + flag(variant.sky_view_camera) +
                          "\n#define VARIANT_LOW_SUN " + flag(variant.low_sun) + "\n#define VARIANT_SHADOWS " +
                          flag(variant.shadows) + "\n#define VARIANT_VOLUME " + flag(variant.volume) +
                          "\n#define VARIANT_BLEND " + flag(variant.blend) +
                          "\n#define VARIANT_SPACE_VOLUME " + flag(variant.space_volume) +
                          "\n#define VARIANT_NIGHT " + flag(variant.night) +
                          "\n#define VARIANT_SURFACE_MODE " + (variant.gbuffer ? "1" : "0") +
                          "\n#define VARIANT_PIXELS " + std::to_string(int(variant.pixels)) +
                          "\n#define VARIANT_STARS " + flag(variant.stars) +
                          "\n#define VARIANT_ECLIPSE " + (variant.eclipse ? "1" : "0") + "\n");
  append_composite(s);
  if (instant) s.append("instant_composite.glsl", embedded("src/gpu/instant_composite.glsl"));
  s.append("atmosphere_pass.frag.glsl", embedded("src/gpu/atmosphere_pass.frag.glsl"));
  return s;
}

AssembledSource atmosphere_pass_vertex_shader_source() {
  AssembledSource s;
  s.append("header", "#version 450 core\n");
  s.append("macros", kSubsetMacros);
  s.append("pixel_ray.glsl", embedded("src/gpu/pixel_ray.glsl"));
  s.append("atmosphere_pass.vert.glsl", embedded("src/gpu/atmosphere_pass.vert.glsl"));
  return s;
}

AssembledSource aerial_perspective_compute_shader_source(const physics::AtmosphereParams& params,
                                                        const physics::SpectralSets& spectral, bool low_sun,
                                                        bool eclipse, bool space, bool split) {
  AssembledSource s = physics_shader_source(params, spectral, kCompositePhysics);
  s.append("variant", std::string("#define VARIANT_LOW_SUN ") + (low_sun ? "true" : "false") +
                          "\n#define VARIANT_ECLIPSE " + (eclipse ? "1" : "0") + "\n#define VARIANT_SPACE " +
                          (space ? "1" : "0") + "\n#define VARIANT_SPLIT " + (split ? "true" : "false") + "\n");
  append_composite(s);
  s.append("aerial_perspective.comp.glsl", embedded("src/gpu/aerial_perspective.comp.glsl"));
  return s;
}

AssembledSource instant_sky_view_fragment_shader_source(const physics::AtmosphereParams& params,
                                                        const physics::SpectralSets& spectral, bool low_sun) {
  AssembledSource s = physics_shader_source(params, spectral, kInstantSkyViewPhysics);
  s.append("variant", std::string("#define INSTANT_LOW_SUN ") + (low_sun ? "true" : "false") + "\n");
  s.append("table_bindings.glsl", embedded("src/gpu/table_bindings.glsl"));
  s.append("instant_sky_view.frag.glsl", embedded("src/gpu/instant_sky_view.frag.glsl"));
  return s;
}

AssembledSource instant_aerial_perspective_compute_shader_source(const physics::AtmosphereParams& params,
                                                                const physics::SpectralSets& spectral,
                                                                bool low_sun) {
  AssembledSource s = physics_shader_source(params, spectral, kInstantCompositePhysics);
  s.append("variant", std::string("#define VARIANT_LOW_SUN ") + (low_sun ? "true" : "false") + "\n");
  append_composite(s);
  s.append("instant_composite.glsl", embedded("src/gpu/instant_composite.glsl"));
  s.append("instant_aerial_perspective.comp.glsl", embedded("src/gpu/instant_aerial_perspective.comp.glsl"));
  return s;
}

std::string engine_library_source(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                  int first_unit, int parameters_binding, bool instant) {
  // The physics without its "#version" line: the engine's shader has its own.
  AssembledSource shared =
      physics_shader_source(params, spectral, instant ? kInstantEngineLibraryPhysics : kEngineLibraryPhysics,
                            "#version 450 core\n", parameters_binding);
  std::string text = shared.text.substr(shared.text.find('\n') + 1);
  text += std::string("#define ATMOS_INSTANT ") + (instant ? "1" : "0") + "\n";
  text += "#define ATMOS_FIRST_UNIT " + std::to_string(first_unit) + "\n";
  for (int unit = 0; unit < 5; ++unit)
    text += "#define ATMOS_UNIT_" + std::to_string(unit) + " " + std::to_string(first_unit + unit) + "\n";
  text += "#define ATMOS_RADIANCE_TO_SRGB atmos_radiance_to_srgb()\n";
  text += embedded("src/gpu/engine_library.glsl");
  return text;
}

}  // namespace atmos::gpu
