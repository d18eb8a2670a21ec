// The C++ side of the language shaders/ray/*.glsl is written in: a subset of GLSL 4.50 that is
// also C++17 with glm. The GLSL side is glsl_prelude.glsl. A file of shaders/ray/ is included
// into a C++ struct's body (its functions become members, so they read the frame's uniforms `P`
// and switches `V` as a shader reads its globals), after this header at namespace scope. The
// subset, checked by both compilers on every build:
// - float literals carry `f` (1.0f); a double would not mix with glm's float vectors;
// - no swizzles but .x .y .z .w (vec3(v) takes a vec4's first three), no implicit int->float;
// - `inout`/`out` parameters are INOUT(T)/OUT(T) (references here, copy-in/out in GLSL); a
//   function writes each OUT parameter on every path (GLSL leaves an unwritten one undefined);
//   a struct read only is IN(T) (a const reference here: a call the compiler does not inline
//   copies nothing);
// - constants at file scope are SHARED_CONST; `precise` is PRECISE (the CPU backend builds with
//   -ffp-contract=off, so every product is rounded by itself already);
// - RAY_COLD marks a function the CPU keeps out of line, RAY_INLINE one it always inlines (the
//   GLSL compiler inlines everything);
// - the uniform block is RAY_UNIFORMS_BEGIN ... RAY_UNIFORMS_END (ray/uniforms.glsl).
#pragma once

#include <cmath>

#include <glm/common.hpp>
#include <glm/exponential.hpp>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <glm/vec4.hpp>
#include <glm/vector_relational.hpp>

#define IN(T) const T&
#define INOUT(T) T&
#define OUT(T) T&
#define PRECISE
#define SHARED_CONST static constexpr
#ifndef RAY_COLD
#define RAY_COLD __attribute__((noinline))
#endif
#ifndef RAY_INLINE
#define RAY_INLINE __attribute__((always_inline))
#endif
#define RAY_LOOP_CHUNK (1 << 20)  // GLSL's is 4096 (llvmpipe's loop limit); here the outer loops run once
#define RAY_UNIFORMS_BEGIN struct RayUniforms {
#define RAY_UNIFORMS_END \
  }                      \
  ;

namespace peakcast::ray {

using glm::bvec3;
using glm::ivec2;
using glm::ivec3;
using glm::ivec4;
using glm::uint;
using glm::uvec4;
using glm::vec2;
using glm::vec3;
using glm::vec4;

using glm::abs;
using glm::acos;
using glm::any;
using glm::atan;
using glm::ceil;
using glm::clamp;
using glm::dot;
using glm::floor;
using glm::greaterThan;
using glm::greaterThanEqual;
using glm::length;
using glm::lessThan;
using glm::lessThanEqual;
using glm::max;
using glm::min;
using glm::mix;
using glm::sign;
using std::pow;
using std::sqrt;
inline bool isnan(float x) { return std::isnan(x); }

// The relational functions, any() and mix by a bvec3 on the types the shared code uses, written
// out: glm's are templates the compiler left out of line in the walks (one call per cell; 6% of
// a differential + adaptive frame's instructions).
#define PEAKCAST_RAY_RELATION(name, op, T) \
  RAY_INLINE inline bvec3 name(const T& a, const T& b) { return bvec3(a.x op b.x, a.y op b.y, a.z op b.z); }
PEAKCAST_RAY_RELATION(lessThan, <, vec3)
PEAKCAST_RAY_RELATION(lessThan, <, ivec3)
PEAKCAST_RAY_RELATION(lessThanEqual, <=, vec3)
PEAKCAST_RAY_RELATION(lessThanEqual, <=, ivec3)
PEAKCAST_RAY_RELATION(greaterThan, >, vec3)
PEAKCAST_RAY_RELATION(greaterThan, >, ivec3)
PEAKCAST_RAY_RELATION(greaterThanEqual, >=, vec3)
PEAKCAST_RAY_RELATION(greaterThanEqual, >=, ivec3)
#undef PEAKCAST_RAY_RELATION
RAY_INLINE inline bool any(const bvec3& b) { return b.x || b.y || b.z; }
RAY_INLINE inline vec3 mix(const vec3& a, const vec3& b, const bvec3& m) {
  return vec3(m.x ? b.x : a.x, m.y ? b.y : a.y, m.z ? b.z : a.z);
}

}  // namespace peakcast::ray
