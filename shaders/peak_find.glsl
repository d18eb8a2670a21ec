// Peak finding between samples (Knoll et al. 2009 §4.2, Alg. 1, errata in docs/architecture.md):
// GL's peak table and TF points; the bins, the crossing test, the roots, the exact TF and the
// walk over a segment's table slots are ray/peaks.glsl.
layout(binding = UNIT_PEAK_TABLE) uniform sampler2DArray u_peak_table;  // RGBA32F: 4 peak values per layer, NO_PEAK_TEXEL = none
layout(std430, binding = SSBO_TF_POINTS) readonly buffer TfPoints {
  vec4 tf_points[];  // per TF point: (value in TF coordinates, 0, 0, 0), then (r, g, b, a)
};

vec4 tf_point(int k) { return tf_points[k]; }

// The four values of layer `layer` of the table's cell (i, j), NO_PEAK_TEXEL after the last.
vec4 peak_slots(int i, int j, int layer) { return texelFetch(u_peak_table, ivec3(i, j, layer), 0); }
bool peak_cell_any(int i, int j) { return true; }  // (the CPU keeps a bit per cell; GL reads the texel)

#include "ray/peaks.glsl"
