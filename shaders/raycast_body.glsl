// The ray caster shared by the fragment and compute entry points (raycast.frag, raycast.comp).
// Classification: post (TF table per sample), peaks (PEAKS: Knoll's peak finding between
// samples, with PEAK_XOR / PEAKS_ONLY modes) or pre-integrated segments (PREINTEGRATION).
// Samples lie on the lattice t_i = t_enter + i * step, i = 0..floor((t_exit - t_enter) / step),
// computed from i (no accumulated t += dt drift). Space skipping visits only the lattice points
// inside occupied macrocells, so it changes no sample that contributes.

#ifdef SPACE_SKIPPING
layout(binding = UNIT_OCCUPANCY) uniform usampler3D u_occupancy;  // 1 = some voxel of the cell is visible
#endif

struct RayResult {
  vec4 acc;
  float samples;  // filter evaluations (root-solving steps included); -1: missed the box
};

vec3 voxel_coords(vec3 p) { return (p + u_box_half.xyz) / u_spacing.xyz; }

#if defined(PEAKS) || defined(PREINTEGRATION)
#define SEGMENTS  // methods that look at the segment between consecutive samples
#endif

#ifdef PEAKS
#include "peak_find.glsl"
#endif
#ifdef PREINTEGRATION
#include "preintegration.glsl"
#endif

// The previous sample, for segment methods: a segment exists only between consecutive lattice
// indices.
float g_prev_t, g_prev_f;
int g_prev_i;

// Visits lattice index i: peaks in the segment ending here, then the sample (post-classified,
// or the pre-integrated segment). Returns true when the ray is opaque enough to stop.
bool visit(Ray r, float t_enter, int i, inout RayResult res) {
  float dt = u_box_half.w;
  float t = t_enter + float(i) * dt;
  vec3 x = voxel_coords(r.o + t * r.d);
  float f = sample_field(x);
  res.samples += 1.0;
  bool segment = g_prev_i == i - 1;
  bool peak_hit = false;
#ifdef PEAKS
  if (segment) peak_hit = find_peaks(r, g_prev_t, g_prev_f, t, f, res);
#endif
#if defined(PREINTEGRATION)
  if (segment) {
    vec4 c = preint_lookup(g_prev_f, f);
    if (c.a > 0.0) {
      vec3 rgb = c.rgb / c.a;
#ifdef SHADING
      rgb = shade(rgb, field_gradient(x), r.d);  // at the segment's end, as preintegration does
#endif
      composite(res.acc, rgb, c.a);
    }
  }
#elif !defined(PEAKS_ONLY)
#ifdef PEAK_XOR
  if (!peak_hit)
#endif
  {
    vec4 c = tf_lookup(f);
    if (c.a > 0.0) {
      vec3 rgb = c.rgb;
#ifdef SHADING
      rgb = shade(rgb, field_gradient(x), r.d);
#endif
      composite(res.acc, rgb, correct_opacity(c.a, dt));
    }
  }
#endif
  g_prev_t = t;
  g_prev_f = f;
  g_prev_i = i;
  return res.acc.a >= u_dims.w;
}

RayResult cast_ray(vec2 pixel) {
  RayResult res;
  res.acc = vec4(0.0);
  res.samples = 0.0;
  g_prev_i = -2;
  Ray r = make_ray(pixel);
  vec2 span = intersect_box(r);
  if (!(span.x <= span.y)) {  // missed (also false for NaN)
    res.samples = -1.0;
    return res;
  }
  float dt = u_box_half.w;
  int last = int(min(floor((span.y - span.x) / dt), u_value_map.w - 1.0));
#ifndef SPACE_SKIPPING
  for (int i = 0; i <= last; ++i)
    if (visit(r, span.x, i, res)) break;
#else
  // 3D-DDA over the macrocell grid (Amanatides & Woo) in voxel coordinates. Each occupied cell
  // visits the lattice indices inside it; segment methods also visit one index on each side, so
  // the segments that leave or enter the cell are not lost.
  float edge = u_cells.w;
  vec3 x0 = voxel_coords(r.o + span.x * r.d);
  vec3 dv = r.d / u_spacing.xyz;
  ivec3 grid = ivec3(u_cells.xyz);
  ivec3 cell = clamp(ivec3(floor(x0 / edge)), ivec3(0), grid - 1);
  ivec3 stp = ivec3(sign(dv));
  vec3 t_max, t_delta;
  for (int a = 0; a < 3; ++a) {
    if (abs(dv[a]) < 1e-20) {  // axis-parallel: never crosses a face on this axis
      t_max[a] = 3.0e38;
      t_delta[a] = 3.0e38;
    } else {
      float face = (float(cell[a]) + (dv[a] > 0.0 ? 1.0 : 0.0)) * edge;
      t_max[a] = span.x + (face - x0[a]) / dv[a];
      t_delta[a] = edge / abs(dv[a]);
    }
  }
  float t_in = span.x;
  int next = 0;  // first lattice index not yet visited
  for (int guard = 0; guard < 4 * (grid.x + grid.y + grid.z) + 4; ++guard) {
    float t_out = min(min(t_max.x, t_max.y), t_max.z);
    bool final_cell = t_out >= span.y || any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, grid));
    // Lattice points with t in [t_in, t_out); all remaining ones in the last cell.
    int first = int(ceil((t_in - span.x) / dt));
    int end = final_cell ? last : min(last, int(ceil((t_out - span.x) / dt)) - 1);
    bool occupied = texelFetch(u_occupancy, clamp(cell, ivec3(0), grid - 1), 0).r != 0u;
    if (occupied) {
#ifdef SEGMENTS
      first -= 1;
      end = min(last, end + 1);
#endif
      for (int i = max(next, first); i <= end; ++i)
        if (visit(r, span.x, i, res)) return res;
      next = max(next, end + 1);
    }
    if (final_cell || next > last) break;
    // Step to the neighbour across the nearest face; ties step every tied axis at once.
    bvec3 hit = lessThanEqual(t_max, vec3(t_out));
    for (int a = 0; a < 3; ++a)
      if (hit[a]) {
        cell[a] += stp[a];
        t_max[a] += t_delta[a];
      }
    t_in = t_out;
  }
#endif
  return res;
}

#ifdef BARE_SAMPLING
// Benchmark baseline: the same rays and the same number of samples as a full render (its
// per-pixel sample counts arrive in u_budget), reconstruction only: no TF, no compositing.
layout(binding = UNIT_BUDGET) uniform sampler2D u_budget;

RayResult cast_ray_bare(vec2 pixel, ivec2 texel) {
  RayResult res;
  res.acc = vec4(0.0);
  res.samples = 0.0;
  Ray r = make_ray(pixel);
  vec2 span = intersect_box(r);
  int budget = int(texelFetch(u_budget, texel, 0).r);
  float sum = 0.0;
  for (int i = 0; i < budget; ++i) sum += sample_field(voxel_coords(r.o + (span.x + float(i) * u_box_half.w) * r.d));
  res.acc = vec4(sum * 1e-9);  // keeps the loop from being optimised away
  res.samples = float(budget);
  return res;
}
#define CAST_RAY(pixel, texel) cast_ray_bare(pixel, texel)
#else
#define CAST_RAY(pixel, texel) cast_ray(pixel)
#endif
