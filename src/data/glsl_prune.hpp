// The GLSL of one program pruned to the functions it uses, before it goes
// to the driver: every program is assembled from the whole shared library
// (src/physics/*.glsl, src/gpu/*.glsl), of which a variant calls a part, and
// a driver's front end parses and optimises every function it is given.
#pragma once

#include <string>
#include <string_view>

namespace atmos::data {

// `source` (a whole shader, preprocessor directives included) without the
// top-level function definitions that nothing kept refers to. Kept is
// main(), all text outside function definitions (declarations, structs,
// constants, every directive: #define bodies and #if conditions), and,
// transitively, every definition whose name appears as an identifier in
// kept text, in any branch of any #if; all overloads of a name go together.
// A definition is only removed if it lies outside every #if region and
// holds no directive, so the result is the same program for every outcome
// of the preprocessor. A removed definition leaves its newlines behind:
// line N of the result is line N of `source`, and the driver's messages keep
// their line numbers. Text the pruning cannot parse with certainty (a
// line continuation outside a directive, "#" or "##" in a macro body, a
// macro body with braces or a semicolon, braces or parentheses not balanced
// within each #if branch, an unterminated comment) is returned unchanged.
std::string prune_unreferenced_functions(std::string_view source);

}  // namespace atmos::data
