// The ray caster shared by the fragment and compute entry points (raycast.frag, raycast.comp).
// Classification: post (TF table per sample), peaks (PEAKS: Knoll's peak finding between
// samples, with PEAK_XOR / PEAKS_ONLY modes) or pre-integrated segments (PREINTEGRATION).
// Samples lie on the ray's lattice (ray/lattice.glsl: uniform or DIFFERENTIAL), indices
// 0..lattice_index(t_exit), computed from the index (no accumulated t += dt drift). Space
// skipping visits only the lattice points inside occupied macrocells, so it changes no sample
// that contributes; ADAPTIVE visits only the multiples of each cell's multiplier.

#include "sampling.glsl"

#ifdef SPACE_SKIPPING
// Per macrocell, the Chebyshev distance in cells to the nearest occupied one (0: occupied).
layout(std430, binding = SSBO_CELL_DISTANCE) readonly buffer CellDistance { uint u_cell_distance[]; };
#endif


#if defined(PEAKS) || defined(PREINTEGRATION) || defined(VIRTUAL_SAMPLES)
#define SEGMENTS  // methods that look at the segment between consecutive samples
#endif
#define EXTENSION 1  // lattice points visited on each side of an occupied cell's run
#define CHUNK 4096   // lattice points per inner loop (see cast_ray)
#if defined(SPACE_SKIPPING) || defined(ADAPTIVE)
#define CELL_TRAVERSAL  // macrocells decide what is visited
#if !defined(ADAPTIVE) && !defined(CELL_DDA)
#define SAMPLE_LEAPS  // driven by the lattice with empty-space leaps; otherwise the 3D-DDA
#endif
#endif

#include "ray_texture.glsl"
// Peak finding and preintegration are declared in every variant (the shared consume names them;
// a variant without them folds the calls away and the compiler drops what they bind).
#include "peak_find.glsl"
#include "preintegration.glsl"
#include "ray/consume.glsl"

#if defined(BRICK) && defined(RAY_TEXTURE)
// The opacity the bricks in front composited, per pixel of the drawn rect (rows of
// P.front_opacity_width pixels; 0: the front brick, none): a ray texture's termination is of the
// opacity over them (render/brick.h Brick::front_opacity).
layout(std430, binding = SSBO_FRONT_OPACITY) readonly buffer FrontOpacity { float u_front_opacity[]; };
#endif

// The field at lattice point i (the target's hook of ray/virtual_samples.glsl vs_finish).
float lattice_field(Ray r, Lattice L, int i, int m) { return sample_field(voxel_coords(r.o + lattice_t(L, float(i)) * r.d)); }
#include "ray/virtual_samples.glsl"
#include "ray/visit.glsl"

#if !defined(CELL_TRAVERSAL)
// Every lattice point from `first` on. True when the ray stopped.
bool walk_points(Ray r, Lattice L, inout RayState res, inout RayWalk walk, inout SampleWindow window, int last, int first) {
  // Nested: llvmpipe stops any single loop after 65535 iterations (LP_MAX_TGSI_LOOP_ITERATIONS),
  // far below the per-ray cap; chunks of CHUNK keep every loop under it.
  bool stop = false;
  for (int c = first; c <= last && !stop; c += CHUNK)
    for (int i = c; i <= min(last, c + CHUNK - 1); ++i)
      if (visit(r, L, res, walk, window, i, 1)) {
        stop = true;
        break;
      }
  return stop;
}
#elif defined(SAMPLE_LEAPS)
// Space skipping by leaps from lattice point `first` on. True when the ray stopped.
bool walk_leaps(Ray r, Lattice L, inout RayState res, inout RayWalk walk, inout SampleWindow window, int last, vec2 span, int first) {
  // Space skipping without adaptive multipliers, driven by the lattice: each iteration looks up
  // the macrocell of lattice point i; in an occupied cell (distance 0) it visits i, in an empty
  // one it leaps out of the cube of empty cells the distance promises to the first lattice point
  // beyond. The points visited are the 3D-DDA's (those inside occupied cells), but a frame costs
  // an iteration per sample or leap instead of one per cell crossed plus one per sample: on
  // llvmpipe the cell loop cost more than the samples. Segment methods add the point
  // before a run of occupied cells and the one after it (EXTENSION 1), as the cell loop does.
  float edge = P.cell_edge;
  vec3 xo = cell_coords(r.o);  // the ray in the cells' voxel coordinates: xo + t * dv
  vec3 dv = r.d / P.spacing;
  ivec3 grid = P.cell_grid;
  ivec3 stp = ivec3(sign(dv));
  bvec3 moves = greaterThanEqual(abs(dv), vec3(1e-20));
  vec3 inv_dv = mix(vec3(0.0), 1.0 / mix(vec3(1.0), dv, moves), moves);
  vec3 ahead = vec3(greaterThan(dv, vec3(0.0)));
  int i = first;
  int visited = -2;  // the last lattice index visited
  bool stop = false;
  int rounds = (last + 2 + 8 * (grid.x + grid.y + grid.z)) / CHUNK + 1;
  for (int round = 0; round < rounds && !stop && i <= last; ++round)
    for (int k = 0; k < CHUNK && i <= last; ++k) {
      vec3 x = xo + lattice_t(L, float(i)) * dv;
      // (a point within rounding of a face may get either cell: both ranges hold what it reads)
      ivec3 c = clamp(ivec3(floor(x * (1.0 / edge))), ivec3(0), grid - 1);
      uint empty_distance = cell_byte(u_cell_distance, c);
      if (empty_distance == 0u) {
#ifdef SEGMENTS
        if (i >= 1 && visited != i - 1 && visit(r, L, res, walk, window, i - 1, 1)) {  // the segment into the run
          stop = true;
          break;
        }
#endif
        if (visit(r, L, res, walk, window, i, 1)) {
          stop = true;
          break;
        }
        visited = i;
        ++i;
      } else {
#ifdef SEGMENTS
        if (visited == i - 1) {  // the segment out of the run
          if (visit(r, L, res, walk, window, i, 1)) {
            stop = true;
            break;
          }
          visited = i;
        }
#endif
        int reach = int(empty_distance) - 1;
        vec3 t_face = mix(vec3(3.0e38), ((vec3(c + stp * reach) + ahead) * edge - xo) * inv_dv, moves);
        float t_leave = min(min(t_face.x, t_face.y), t_face.z);
        i = max(i + 1, int(ceil(lattice_index(L, min(t_leave, span.y + P.step)))));
      }
    }
  return stop;
}
#else
// The macrocell 3D-DDA from the ray's start. True when the ray stopped.
bool walk_cells(Ray r, Lattice L, inout RayState res, inout RayWalk walk, inout SampleWindow window, int last, vec2 span) {
  // 3D-DDA over the macrocell grid (Amanatides & Woo) in voxel coordinates. Each occupied cell
  // visits the lattice indices inside it (the multiples of its multiplier M with ADAPTIVE);
  // segment methods also visit EXTENSION more on each side of a run of occupied cells, so the
  // segments that enter or leave the run are not lost.
  float edge = P.cell_edge;
  vec3 x0 = cell_coords(r.o + span.x * r.d);
  vec3 dv = r.d / P.spacing;
  ivec3 grid = P.cell_grid;
  ivec3 cell = clamp(ivec3(floor(x0 / edge)), ivec3(0), grid - 1);
  ivec3 stp = ivec3(sign(dv));
  // Per axis: 1 / dv (0 where the ray is parallel to the axis: it never crosses a face there),
  // and the offset of the face a ray leaving a cell crosses (1 going up, 0 going down).
  bvec3 moves = greaterThanEqual(abs(dv), vec3(1e-20));
  vec3 inv_dv = mix(vec3(0.0), 1.0 / mix(vec3(1.0), dv, moves), moves);
  vec3 ahead = vec3(greaterThan(dv, vec3(0.0)));
  vec3 t_delta = mix(vec3(3.0e38), edge * abs(inv_dv), moves);
  vec3 t_max = mix(vec3(3.0e38), span.x + ((vec3(cell) + ahead) * edge - x0) * inv_dv, moves);
  float t_in = span.x;
  int next = 0;  // first lattice index not yet visited
#ifdef SEGMENTS
  // The EXTENSION points after a run of occupied cells are visited once the run ends: before an
  // empty cell, a leap or the ray's end. An occupied cell next continues the run from its own
  // first point with its own multiplier, as the reference walks it.
  int run_end = -1;  // the last index of the run whose points after it are owed
#endif
  for (int guard = 0; guard < 4 * (grid.x + grid.y + grid.z) + 4; ++guard) {
    ivec3 c = clamp(cell, ivec3(0), grid - 1);
#ifdef SPACE_SKIPPING
    uint empty_distance = cell_byte(u_cell_distance, c);
#ifdef SEGMENTS
    if (run_end >= 0 && empty_distance != 0u) {  // an empty cell or a leap: the run ends here
      for (int j = max(next, run_end + 1); j <= min(last, run_end + EXTENSION); ++j)
        if (visit(r, L, res, walk, window, j, 1)) return true;
      next = max(next, min(last, run_end + EXTENSION) + 1);
      run_end = -1;
    }
#endif
    if (empty_distance > 1u && cell == c) {
      // Every cell within empty_distance - 1 of this one is empty: leap to where the ray leaves
      // that cube (no lattice point inside it is visited) and go on from the cell beyond.
      int reach = int(empty_distance) - 1;
      vec3 t_face = mix(vec3(3.0e38), span.x + ((vec3(cell + stp * reach) + ahead) * edge - x0) * inv_dv, moves);
      float t_leave = min(min(t_face.x, t_face.y), t_face.z);
      if (t_leave >= span.y) break;
      vec3 x = x0 + (t_leave - span.x) * dv;
      ivec3 beyond = clamp(ivec3(floor(x / edge)), cell - reach, cell + reach);
      bvec3 crossed = lessThanEqual(t_face, vec3(t_leave));
      cell = ivec3(mix(vec3(beyond), vec3(cell + stp * (reach + 1)), crossed));
      if (any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, grid))) break;
      t_max = mix(vec3(3.0e38), span.x + ((vec3(cell) + ahead) * edge - x0) * inv_dv, moves);
      t_in = t_leave;
      continue;
    }
    bool occupied = empty_distance == 0u;
#else
    bool occupied = true;
#endif
    float t_out = min(min(t_max.x, t_max.y), t_max.z);
    bool final_cell = t_out >= span.y || any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, grid));
    // Lattice points with t in [t_in, t_out); all remaining ones in the last cell.
    int first = int(ceil(lattice_index(L, t_in)));
    int end = final_cell ? last : min(last, int(ceil(lattice_index(L, t_out))) - 1);
#ifdef ADAPTIVE
    // 1..8. The clamp also matters to llvmpipe: with the raw byte as the loop increment it
    // rendered adaptive frames wrong (a constant volume at 31.9 dB; the bytes were right).
    int m = clamp(int(cell_byte(u_cell_stride, c)), 1, 8);
#else
    const int m = 1;
#endif
    if (occupied) {
      // Every m-th lattice index from the first one not yet visited; each sample stands for the
      // steps up to the next one, the cell's last for those up to the cell's end, so the cells'
      // samples cover the ray without gaps or overlaps. Segment methods add the single indices
      // just before the run and, once it ends, just after it (one step each).
      int i = max(next, first);
#ifdef SEGMENTS
      for (int e = EXTENSION; e >= 1; --e)
        if (first - e >= next && visit(r, L, res, walk, window, first - e, 1)) return true;
#endif
      while (i <= end) {  // in chunks, as above
        int chunk_end = min(end, i + (CHUNK - 1) * m);
        for (; i <= chunk_end; i += m)
          if (visit(r, L, res, walk, window, i, min(m, end + 1 - i))) return true;
      }
      next = max(next, end + 1);
#ifdef SEGMENTS
      run_end = end;
#endif
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
#ifdef SEGMENTS
  // A run that reaches the last cell visited (or the guard): its points after it, never one
  // visited already.
  if (run_end >= 0)
    for (int j = max(next, run_end + 1); j <= min(last, run_end + EXTENSION); ++j)
      if (visit(r, L, res, walk, window, j, 1)) return true;
#endif
  return false;
}
#endif

RayState cast_ray(vec2 pixel) {
  RayState res = RayState(vec4(0.0), 0.0, P.stop, 1.0, 1.0, true, 0.0, 0.0, false, false);
  SampleWindow window;  // virtual samples (n counts the samples it holds; the rest is never read)
  window.n = 0;
  window.own = 0u;
  Ray r = make_ray(pixel);
  vec2 span = intersect_box(r);
  if (!(span.x <= span.y)) {  // missed (also false for NaN)
    res.samples = -1.0;
    return res;
  }
  float t_box = span.x;  // the box entry: where a volume-mapped ray texture is read
  span = clip_span(r, span);
  if (!(span.x <= span.y)) {  // the clip keeps none of the ray
    res.samples = 0.0;
    return res;
  }
  Lattice L = ray_lattice(r, span.x);
#ifdef RAY_TEXTURE
  float step_mult = read_ray_texture(r, pixel, t_box, res);
  L.A *= step_mult;
  L.B *= step_mult;
#endif
  int last = int(min(floor(lattice_index(L, span.y)), float(P.sample_cap - 1)));
  RayWalk walk = start_walk(L, span.y, last);
#ifdef BRICK
  if (!clip_to_brick(r, L, span, last, walk.own_first, walk.own_last)) {  // none of its points in this brick: nothing to draw here
    res.samples = -1.0;
    return res;
  }
#ifdef RAY_TEXTURE
  if (P.front_opacity_width > 0) {
    ivec2 p = ivec2(pixel) - ivec2(P.tile_x, P.tile_y);
    float a = u_front_opacity[p.y * P.front_opacity_width + p.x];
    if (a >= 0.0 && a >= res.stop) {  // reached in front (after a consume there): one process stopped
      res.samples = -1.0;
      return res;
    }
    if (a > 0.0) res.stop = (res.stop - a) / (1.0 - a);  // a + (1 - a) * acc >= stop; a < 0: none in front
  }
#endif
#endif
  // A brick starts where the points it samples before its own (walk.behind: one, or two with
  // virtual samples) are visited as in one process: at them (a walk over every point), one
  // before them (leaps: whether a point is visited depends on its neighbours only), at the
  // ray's start (the 3D-DDA: a cell's first point depends on the cells before it).
#if defined(VIRTUAL_SAMPLES)
  const int behind = 2;
#elif defined(SEGMENTS)
  const int behind = 1;
#else
  const int behind = 0;
#endif
  bool stopped;
#if !defined(CELL_TRAVERSAL)
  stopped = walk_points(r, L, res, walk, window, last, max(walk.own_first - behind, 0));
#elif defined(SAMPLE_LEAPS)
  stopped = walk_leaps(r, L, res, walk, window, last, span, max(walk.own_first - behind - 1, 0));
#else
  stopped = walk_cells(r, L, res, walk, window, last, span);
#endif
  if (stopped) return res;
#ifdef VIRTUAL_SAMPLES
  vs_finish(r, res, window, L, last, walk.own_last, span.y);
#elif defined(PREINTEGRATION)
  close_segment(r, res, span.y, walk.expect == walk.ray_last + 1);
#endif
  return res;
}

#ifdef BARE_SAMPLING
// Benchmark baseline: the same rays and the same number of samples as a full render (its
// per-pixel sample counts arrive in u_budget), reconstruction only: no TF, no compositing.
layout(binding = UNIT_BUDGET) uniform sampler2D u_budget;

RayState cast_ray_bare(vec2 pixel, ivec2 texel) {
  RayState res = RayState(vec4(0.0), 0.0, P.stop, 1.0, 1.0, true, 0.0, 0.0, false, false);
  Ray r = make_ray(pixel);
  vec2 span = intersect_box(r);
  int budget = int(texelFetch(u_budget, texel, 0).r);
  float sum = 0.0;
  Lattice L = ray_lattice(r, span.x);
  for (int i = 0; i < budget; ++i) sum += sample_field(voxel_coords(r.o + lattice_t(L, float(i)) * r.d));
  res.acc = vec4(sum * 1e-9);  // keeps the loop from being optimised away
  res.samples = float(budget);
  return res;
}
#define CAST_RAY(pixel, texel) cast_ray_bare(pixel, texel)
#else
#define CAST_RAY(pixel, texel) cast_ray(pixel)
#endif
