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
// same-typed fields is caught by the GPU-vs-CPU test.
static_assert(sizeof(physics::DensityProfile) == 4 * (2 + 2 * MAX_DENSITY_KNOTS),
              "DensityProfile changed: update atmosphere_params_glsl()");
static_assert(sizeof(physics::AtmosphereParams) ==
                  4 * (3 + 1 + 3 * 3 + 2 * 3 + 2 + 8 + 6 + SCATTERING_R_AXIS_KNOTS + 2) +
                      MAX_CONSTITUENTS * (sizeof(physics::DensityProfile) + 4 * (3 + 3 + 1)),
              "AtmosphereParams changed: update atmosphere_params_glsl()");

std::string glsl_int(int value) { return std::to_string(value); }

std::string glsl_vec3(const physics::vec3& v) {
  return "vec3(" + glsl_float(v.x) + ", " + glsl_float(v.y) + ", " + glsl_float(v.z) + ")";
}

// "T[n](a, b, ...)" from n already formatted elements.
template <typename Format>
std::string glsl_array(const char* type, int n, Format element) {
  std::string s = std::string(type) + "[" + std::to_string(n) + "](";
  for (int i = 0; i < n; ++i) s += (i > 0 ? ", " : "") + element(i);
  return s + ")";
}

std::string glsl_density_profile(const physics::DensityProfile& d) {
  return "DensityProfile(" + glsl_float(d.scale_height) + ", " + glsl_int(d.knot_count) + ", " +
         glsl_array("float", MAX_DENSITY_KNOTS, [&](int i) { return glsl_float(d.knot_altitude[i]); }) + ", " +
         glsl_array("float", MAX_DENSITY_KNOTS, [&](int i) { return glsl_float(d.knot_density[i]); }) + ")";
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

// "AtmosphereParams(...)", every field in declaration order.
std::string atmosphere_params_expression(const physics::AtmosphereParams& p) {
  const int n = MAX_CONSTITUENTS;
  std::string s = "AtmosphereParams(\n";
  s += "    " + glsl_float(p.bottom_radius) + ", " + glsl_float(p.top_radius) + ", " + glsl_int(p.constituent_count) +
       ",\n";
  s += "    " + glsl_array("DensityProfile", n, [&](int i) { return glsl_density_profile(p.density[i]); }) + ",\n";
  s += "    " + glsl_array("vec3", n, [&](int i) { return glsl_vec3(p.scattering[i]); }) + ",\n";
  s += "    " + glsl_array("vec3", n, [&](int i) { return glsl_vec3(p.absorption[i]); }) + ",\n";
  s += "    " + glsl_array("int", n, [&](int i) { return glsl_int(p.is_aerosol[i]); }) + ",\n";
  s += "    " + glsl_int(p.aerosol_phase_kind) + ", " + glsl_vec3(p.aerosol_g) + ", " + glsl_vec3(p.aerosol_g_back) +
       ", " + glsl_vec3(p.aerosol_forward_weight) + ",\n";
  s += "    " + glsl_vec3(p.ground_albedo) + ", " + glsl_vec3(p.solar_irradiance) + ",\n";
  s += "    " + glsl_float(p.sun_angular_radius) + ", " + glsl_float(p.mu_s_min) + ",\n";
  s += "    " + glsl_int(p.transmittance_mu_size) + ", " + glsl_int(p.transmittance_r_size) + ", " +
       glsl_int(p.irradiance_mu_s_size) + ", " + glsl_int(p.irradiance_r_size) + ", " +
       glsl_int(p.scattering_nu_size) + ", " + glsl_int(p.scattering_mu_s_size) + ", " +
       glsl_int(p.scattering_mu_size) + ", " + glsl_int(p.scattering_r_size) + ",\n";
  s += "    " + glsl_int(p.transmittance_tile) + ", " + glsl_int(p.transmittance_tiles) + ", " +
       glsl_int(p.single_scattering_tile) + ", " + glsl_int(p.scattering_nu_in_angle) + ", " +
       glsl_float(p.scattering_mu_log_weight) + ",\n";
  s += "    " + glsl_float(p.scattering_r_optical_depth_weight) + ", " +
       glsl_array("float", SCATTERING_R_AXIS_KNOTS, [&](int i) { return glsl_float(p.scattering_r_axis[i]); }) +
       ",\n";
  s += "    " + glsl_float(p.source_flat_optical_depth) + ", " + glsl_float(p.scattering_row_1_height) + ")";
  return s;
}

std::string glsl_mat3(const physics::mat3& m) {
  std::string s = "mat3(";
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) s += glsl_float(m[c][r]) + (c == 2 && r == 2 ? ")" : ", ");
  return s;
}

}  // namespace

std::string atmosphere_params_glsl(const physics::AtmosphereParams& p) {
  return "const AtmosphereParams ATMOSPHERE = " + atmosphere_params_expression(p) + ";\n";
}

std::string spectral_sets_glsl(const physics::SpectralSets& sets) {
  // The shaders' SPECTRAL_SET_CAPACITY is the actual count (see
  // physics_shader_source).
  const int n = sets.count;
  return "const SpectralSets SPECTRAL = SpectralSets(" + glsl_int(n) + ",\n" +
         glsl_array("AtmosphereParams", n, [&](int i) { return atmosphere_params_expression(sets.set[i]); }) +
         ",\n" + glsl_array("mat3", n, [&](int i) { return glsl_mat3(sets.to_channels[i]); }) + ");\n";
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
// subset macros, definitions.glsl with the atmosphere's constants, then the
// parts of the physics `physics` (names in src/physics/).
AssembledSource physics_shader_source(const physics::AtmosphereParams& params, const physics::SpectralSets& spectral,
                                      const std::vector<const char*>& physics,
                                      const std::string& header = "#version 450 core\n") {
  AssembledSource s;
  s.append("header", header);
  s.append("macros", kSubsetMacros);
  // Shaders only run the run-time integration (see RAY_MAP_CAPACITY).
  s.append("capacities", "#define RAY_ARRAYS_FOR_RUNTIME\n#define SPECTRAL_SET_CAPACITY " +
                             std::to_string(spectral.count) + "\n#define SPECTRAL_COUNT(s) SPECTRAL_SET_CAPACITY\n" +
                             "#define CONSTITUENT_COUNT(a) " + std::to_string(params.constituent_count) + "\n" +
                             "#define DENSITY_KNOT_BOUND " + std::to_string(density_knot_bound(params)) + "\n");
  s.append("definitions.glsl", embedded("src/physics/definitions.glsl"));
  s.append("ATMOSPHERE", atmosphere_params_glsl(params));
  s.append("SPECTRAL", spectral_sets_glsl(spectral));
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
                                  const physics::mat3& radiance_to_srgb, int first_unit, bool instant) {
  // The physics without its "#version" line: the engine's shader has its own.
  AssembledSource shared =
      physics_shader_source(params, spectral, instant ? kInstantEngineLibraryPhysics : kEngineLibraryPhysics);
  std::string text = shared.text.substr(shared.text.find('\n') + 1);
  text += std::string("#define ATMOS_INSTANT ") + (instant ? "1" : "0") + "\n";
  text += "#define ATMOS_FIRST_UNIT " + std::to_string(first_unit) + "\n";
  for (int unit = 0; unit < 5; ++unit)
    text += "#define ATMOS_UNIT_" + std::to_string(unit) + " " + std::to_string(first_unit + unit) + "\n";
  text += "const mat3 ATMOS_RADIANCE_TO_SRGB = mat3(";
  for (int c = 0; c < 3; ++c)
    for (int r = 0; r < 3; ++r) text += glsl_float(radiance_to_srgb[c][r]) + (c == 2 && r == 2 ? ");\n" : ", ");
  text += embedded("src/gpu/engine_library.glsl");
  return text;
}

}  // namespace atmos::gpu
