// The C++ meaning of the qualifiers of the GLSL/C++ subset in which the
// shared shader code of the physics and of the post-processing is written
// (physics/definitions.glsl, post/tone_mapping.glsl; the planet layer, which
// sees only the public headers, defines the same in noise_cpp.hpp and
// ocean_waves_cpp.hpp): parameters
// IN(T) -> const T&, OUT(T) and INOUT(T) -> T&, and functions
// INLINE -> inline. In GLSL they are in T, out T, inout T and nothing
// (gpu/shader_source.cpp, post/post_process.cpp).
#pragma once

#ifndef IN
#define IN(T) const T&
#endif
#ifndef OUT
#define OUT(T) T&
#endif
#ifndef INOUT
#define INOUT(T) T&
#endif
#ifndef INLINE
#define INLINE inline
#endif
