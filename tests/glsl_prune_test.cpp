// The pruning of a program's GLSL to the functions it uses
// (data/glsl_prune.hpp): what it removes, what it must keep, and that the
// lines keep their numbers.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "atmos/planet_file.hpp"
#include "data/glsl_prune.hpp"
#include "gpu/shader_source.hpp"
#include "physics/parameters.hpp"

namespace {

using atmos::data::prune_unreferenced_functions;

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }
long lines(const std::string& text) { return long(std::count(text.begin(), text.end(), '\n')); }

TEST(GlslPrune, RemovesWhatNothingReachesAndKeepsTheLines) {
  const std::string source =
      "#version 450 core\n"
      "// helpers\n"
      "float used(float x) { return x * 2.0; }\n"
      "float unused(float x) {\n"
      "  return x + 1.0;  /* { not a brace */\n"
      "}\n"
      "out vec4 colour;\n"
      "void main() { colour = vec4(used(1.0)); }\n";
  const std::string pruned = prune_unreferenced_functions(source);
  EXPECT_FALSE(has(pruned, "unused"));
  EXPECT_TRUE(has(pruned, "float used(float x) { return x * 2.0; }\n"));
  EXPECT_TRUE(has(pruned, "void main() { colour = vec4(used(1.0)); }"));
  EXPECT_EQ(lines(pruned), lines(source));
  // The line after the removed definition is where it was: line 7.
  EXPECT_EQ(lines(pruned.substr(0, pruned.find("out vec4"))), 6);
}

TEST(GlslPrune, FollowsCallChains) {
  const std::string source =
      "float c(float x) { return x; }\n"
      "float b(float x) { return c(x); }\n"
      "float a(float x) { return b(x); }\n"
      "float d(float x) { return c(x); }\n"  // unreached, though it calls a reached function
      "float e(float x) { return d(x); }\n"  // reaches d only from an unreached function
      "void main() { gl_FragDepth = a(0.5); }\n";
  const std::string pruned = prune_unreferenced_functions(source);
  EXPECT_TRUE(has(pruned, "float a(") && has(pruned, "float b(") && has(pruned, "float c("));
  EXPECT_FALSE(has(pruned, "float d(") || has(pruned, "float e("));
  EXPECT_EQ(lines(pruned), lines(source));
}

TEST(GlslPrune, KeepsEveryOverloadOfAReachedName) {
  const std::string source =
      "float f(float x) { return x; }\n"
      "vec3 f(vec3 x) { return x; }\n"
      "vec2 g(vec2 x) { return x; }\n"
      "float g(float x) { return x; }\n"
      "void main() { gl_FragDepth = f(0.5); }\n";
  const std::string pruned = prune_unreferenced_functions(source);
  EXPECT_TRUE(has(pruned, "float f(float x)") && has(pruned, "vec3 f(vec3 x)"));
  EXPECT_FALSE(has(pruned, "vec2 g(") || has(pruned, "float g("));
}

TEST(GlslPrune, KeepsFunctionsNamedInDirectivesAndGlobals) {
  const std::string source =
      "#define IN(T) in T\n"
      "#define LIGHT(x) sun_light(x)\n"
      "float sun_light(IN(float) x) { return x; }\n"
      "float initial(float x) { return x; }\n"
      "const float START = initial(1.0);\n"
      "#if 0\n"
      "float disabled = branch_only(1.0);\n"
      "#else\n"
      "float enabled = 1.0;\n"
      "#endif\n"
      "float branch_only(float x) { return x; }\n"
      "float unused(IN(float) x) { return x; }\n"
      "void main() { gl_FragDepth = START; }\n";
  const std::string pruned = prune_unreferenced_functions(source);
  // Named by a macro's body (never expanded here), by a constant's
  // initialiser and in a branch that the preprocessor drops: all kept.
  EXPECT_TRUE(has(pruned, "float sun_light("));
  EXPECT_TRUE(has(pruned, "float initial("));
  EXPECT_TRUE(has(pruned, "float branch_only("));
  EXPECT_FALSE(has(pruned, "float unused("));
  EXPECT_EQ(lines(pruned), lines(source));
}

TEST(GlslPrune, KeepsDefinitionsInsideOrHoldingConditionals) {
  const std::string source =
      "#ifdef EXTRA\n"
      "float in_region(float x) { return x; }\n"
      "#endif\n"
      "float holds_a_branch(float x) {\n"
      "#if FAST\n"
      "  return x;\n"
      "#else\n"
      "  return 2.0 * x;\n"
      "#endif\n"
      "}\n"
      "float holds_a_define(float x) {\n"
      "#define SCALE 3.0\n"
      "  return x;\n"
      "}\n"
      "float after(float x) { return SCALE * x; }\n"
      "void main() { gl_FragDepth = 0.5; }\n";
  const std::string pruned = prune_unreferenced_functions(source);
  EXPECT_TRUE(has(pruned, "float in_region("));
  EXPECT_TRUE(has(pruned, "float holds_a_branch("));
  EXPECT_TRUE(has(pruned, "#define SCALE 3.0"));
  // Outside any region and without directives: removed.
  EXPECT_FALSE(has(pruned, "float after("));
  EXPECT_EQ(lines(pruned), lines(source));
}

TEST(GlslPrune, ReadsFunctionsCalledFromKeptConditionalCode) {
  const std::string source =
      "float only_if_fast(float x) { return x; }\n"
      "float only_if_slow(float x) { return x; }\n"
      "void main() {\n"
      "#if FAST\n"
      "  gl_FragDepth = only_if_fast(0.5);\n"
      "#else\n"
      "  gl_FragDepth = only_if_slow(0.5);\n"
      "#endif\n"
      "}\n";
  const std::string pruned = prune_unreferenced_functions(source);
  EXPECT_TRUE(has(pruned, "float only_if_fast(") && has(pruned, "float only_if_slow("));
}

TEST(GlslPrune, KeepsStructsBlocksAndDeclarations) {
  const std::string source =
      "struct Ray { vec3 origin; vec3 direction; };\n"
      "layout(std430, binding = 0) buffer Columns { vec4 column[]; };\n"
      "layout(binding = 1) uniform sampler2D table;\n"
      "const float WEIGHTS[2] = float[2](0.25, 0.75);\n"
      "float prototype(float x);\n"
      "Ray unused_ray(vec3 o) { Ray r; r.origin = o; r.direction = o; return r; }\n"
      "void main() { gl_FragDepth = WEIGHTS[0]; }\n";
  const std::string pruned = prune_unreferenced_functions(source);
  EXPECT_TRUE(has(pruned, "struct Ray { vec3 origin; vec3 direction; };"));
  EXPECT_TRUE(has(pruned, "buffer Columns { vec4 column[]; };"));
  EXPECT_TRUE(has(pruned, "uniform sampler2D table;"));
  EXPECT_TRUE(has(pruned, "const float WEIGHTS[2]"));
  EXPECT_TRUE(has(pruned, "float prototype(float x);"));
  EXPECT_FALSE(has(pruned, "unused_ray"));
}

TEST(GlslPrune, ReturnsTextItCannotParseUnchanged) {
  const std::string tail = "float unused(float x) { return x; }\nvoid main() { gl_FragDepth = 0.5; }\n";
  // A branch that opens a brace the other does not: the definitions'
  // extents are unknown.
  const std::string unbalanced = "#if A\nvoid main() {\n#else\nvoid main() { if (true) {\n#endif\n}\n" + tail;
  EXPECT_EQ(prune_unreferenced_functions(unbalanced), unbalanced);
  // Token pasting could spell any name.
  const std::string pasting = "#define CALL(n) f_##n(1.0)\n" + tail;
  EXPECT_EQ(prune_unreferenced_functions(pasting), pasting);
  // A macro with a brace could open or close a body.
  const std::string braced = "#define BEGIN {\n" + tail;
  EXPECT_EQ(prune_unreferenced_functions(braced), braced);
  const std::string continued = "float x = 1.0 + \\\n 2.0;\n" + tail;
  EXPECT_EQ(prune_unreferenced_functions(continued), continued);
  const std::string open_comment = tail + "/* unterminated";
  EXPECT_EQ(prune_unreferenced_functions(open_comment), open_comment);
  // The same tail alone does lose `unused`.
  EXPECT_FALSE(has(prune_unreferenced_functions(tail), "unused"));
}

TEST(GlslPrune, KeepsADefinitionAMacroSpells) {
  // "DEFINE_LOOKUP(table) { ... }" looks like a definition of DEFINE_LOOKUP;
  // it is whatever the macro makes of it.
  const std::string source =
      "#define DEFINE_LOOKUP(name) float name##_lookup(float x)\n"
      "void main() { gl_FragDepth = 0.5; }\n";
  EXPECT_EQ(prune_unreferenced_functions(source), source);  // "##": unchanged
  const std::string spelled =
      "#define HEADER(name) float name(float x)\n"
      "HEADER(lookup) { return x; }\n"
      "void main() { gl_FragDepth = lookup(0.5); }\n";
  EXPECT_EQ(prune_unreferenced_functions(spelled), spelled);
  // Nor is a definition after such a block in the same statement removed
  // (the block's extent would run into it).
  const std::string followed =
      "#define HEADER(name) float name(float x)\n"
      "HEADER(lookup) { return x; }\n"
      "float unused(float x) { return x; }\n"
      "void main() { gl_FragDepth = lookup(0.5); }\n";
  EXPECT_EQ(prune_unreferenced_functions(followed), followed);
}

// The library as the programs assemble it parses (no fallback to the whole
// text), loses functions, and keeps its line numbers.
TEST(GlslPrune, PrunesTheAssembledPrograms) {
  const atmos::Atmosphere earth = atmos::load_atmosphere("earth");
  const atmos::TableSizes sizes;
  const atmos::physics::AtmosphereParams params = atmos::physics::make_render_params(earth, sizes);
  const auto spectral = atmos::physics::make_spectral_sets(earth, sizes);
  atmos::gpu::PassVariant sky;
  const std::string pass = atmos::gpu::atmosphere_pass_fragment_shader_source(params, *spectral, sky).text;
  for (const std::string& source :
       {pass, atmos::gpu::sky_view_fragment_shader_source(params, *spectral, false, false).text,
        atmos::gpu::aerial_perspective_compute_shader_source(params, *spectral, false, false, false, false).text}) {
    const std::string pruned = prune_unreferenced_functions(source);
    EXPECT_LT(double(pruned.size()), 0.95 * double(source.size()));
    EXPECT_EQ(lines(pruned), lines(source));
    EXPECT_TRUE(has(pruned, "void main()"));
  }
  // The CPU twin's entry point of the pass, which no program calls.
  EXPECT_TRUE(has(pass, "vec3 composite_pixel("));
  EXPECT_FALSE(has(prune_unreferenced_functions(pass), "vec3 composite_pixel("));
}

}  // namespace
