// The GLSL side of the language shaders/ray/*.glsl is written in (the C++ side, with the rules
// of the subset, is cxx_prelude.h): the qualifiers both compilers read, and the variant's
// switches as the constant `V` that the shared code tests (`if (V.peaks)`), folded by the
// compiler so a variant holds only what its scene uses.
#define IN(T) T
#define INOUT(T) inout T
#define OUT(T) out T
#define PRECISE precise
#define SHARED_CONST const
#define RAY_COLD
#define RAY_INLINE
#define RAY_LOOP_CHUNK 4096  // llvmpipe stops any single loop after 65535 iterations (ray/walks.glsl)
#define RAY_UNIFORMS_BEGIN layout(std140, binding = UBO_RAY) uniform RayUniforms {
#define RAY_UNIFORMS_END } P;

#include "ray/variant.glsl"

#ifdef ORTHOGRAPHIC
#define V_ORTHOGRAPHIC true
#else
#define V_ORTHOGRAPHIC false
#endif
#ifdef DIFFERENTIAL
#define V_DIFFERENTIAL true
#else
#define V_DIFFERENTIAL false
#endif
#ifdef SHADING
#define V_SHADING true
#else
#define V_SHADING false
#endif
#ifdef ADAPTIVE
#define V_ADAPTIVE true
#else
#define V_ADAPTIVE false
#endif
#ifdef SPACE_SKIPPING
#define V_SPACE_SKIPPING true
#else
#define V_SPACE_SKIPPING false
#endif
#ifdef VIRTUAL_SAMPLES
#define V_VIRTUAL_SAMPLES VIRTUAL_SAMPLES
#else
#define V_VIRTUAL_SAMPLES 0
#endif
#ifdef PEAKS
#define V_PEAKS true
#else
#define V_PEAKS false
#endif
#ifdef PEAK_XOR
#define V_PEAK_XOR true
#else
#define V_PEAK_XOR false
#endif
#ifdef PEAKS_ONLY
#define V_PEAKS_ONLY true
#else
#define V_PEAKS_ONLY false
#endif
#ifdef PREINTEGRATION
#define V_PREINTEGRATION true
#else
#define V_PREINTEGRATION false
#endif
#if defined(PEAKS) || defined(PREINTEGRATION) || defined(VIRTUAL_SAMPLES)
#define V_SEGMENTS true
#else
#define V_SEGMENTS false
#endif
#ifdef RAY_TEXTURE
#define V_RAY_TEXTURE true
#else
#define V_RAY_TEXTURE false
#endif
#ifdef RAY_TEXTURE_VOLUME
#define V_RAY_TEXTURE_VOLUME true
#else
#define V_RAY_TEXTURE_VOLUME false
#endif
#ifdef BRICK
#define V_BRICK true
#else
#define V_BRICK false
#endif
#ifdef PROJECTION
#define V_PROJECTION PROJECTION
#else
#define V_PROJECTION 0
#endif
const Variant V = Variant(V_ORTHOGRAPHIC, V_DIFFERENTIAL, V_SHADING, V_ADAPTIVE, V_SPACE_SKIPPING,
                          V_VIRTUAL_SAMPLES, V_PEAKS, V_PEAK_XOR, V_PEAKS_ONLY, V_PREINTEGRATION,
                          V_SEGMENTS, V_RAY_TEXTURE, V_RAY_TEXTURE_VOLUME, V_BRICK, V_PROJECTION);
