// The walks over a ray's lattice: which lattice points are visited, in which order, each visit
// handed to visit.glsl. The variant picks one (walk_ray):
// - walk_points: every point (no macrocells);
// - walk_leaps: space skipping driven by the lattice, with empty-space leaps: each step looks up
//   the macrocell of lattice point i; in an occupied cell it visits i, in an empty one it leaps
//   out of the cube of empty cells its distance promises to the first lattice point beyond.
//   The points visited are the 3D-DDA's (those inside occupied cells), but a ray costs a step per
//   sample or leap instead of one per cell crossed plus one per sample;
// - walk_cells: the macrocell 3D-DDA (Amanatides & Woo), for adaptive multipliers (each cell
//   visits the multiples of its multiplier m), leaping over empty cells likewise.
// Segment methods (peaks, preintegration, virtual samples) also visit kExtension points on each
// side of a run of occupied cells, so the segments that enter or leave the run are not lost
// (walk_leaps visits the one point on each side itself: it assumes kExtension == 1).
//
// A maximum or minimum projection walks the 3D-DDA too, skipping the cells that cannot change
// the ray's value so far (ray/projection.glsl).
//
// What a target supplies (its hooks): cell_distance(c), space skipping's byte per macrocell
// (Chebyshev distance in cells to the nearest occupied one, 0: occupied); cell_range(c), the
// cell's value range in TF coordinates (min, max) for projections; cell_multiplier(c),
// the adaptive multiplier 1..8; cell_containing(x), the cell of a point in cell units, clamped
// to the grid; dense_run(...), a target's fast path over the points that follow a visit while
// they lie in occupied cells, or over an occupied cell's points (the CPU's, held by tests to
// these walks; GL has none).

SHARED_CONST int kExtension = 1;  // lattice points visited on each side of an occupied run
// Lattice points per inner loop: llvmpipe stops any single loop after 65535 iterations
// (LP_MAX_TGSI_LOOP_ITERATIONS), far below the per-ray cap, so the walks nest their loops; the
// CPU's chunk is long enough that its outer loops run once (the preludes' RAY_LOOP_CHUNK).
SHARED_CONST int kChunk = RAY_LOOP_CHUNK;

// The ray in the macrocells' voxel coordinates, x0 + (t - t_start) dv, and per axis: the step
// across a face, whether it moves at all (it never crosses a face where it does not), 1 / dv
// (0 there), and the offset of the face it leaves a cell by (1 going up, 0 going down).
struct CellRay {
  float edge;  // the macrocells' edge in voxels, and their grid (copies of P's: read once per ray)
  ivec3 grid;
  vec3 x0;
  float t_start;
  vec3 dv;
  ivec3 stp;
  bvec3 moves;
  vec3 inv_dv;
  vec3 ahead;
};

RAY_INLINE CellRay cell_ray(IN(Ray) r, float t_start) {
  CellRay g;
  g.edge = P.cell_edge;
  g.grid = P.cell_grid;
  g.t_start = t_start;
  g.x0 = cell_coords(r.o + t_start * r.d);
  g.dv = r.d / P.spacing;
  g.stp = ivec3(sign(g.dv));
  g.moves = greaterThanEqual(abs(g.dv), vec3(1e-20f));
  g.inv_dv = mix(vec3(0.0f), 1.0f / mix(vec3(1.0f), g.dv, g.moves), g.moves);
  g.ahead = vec3(greaterThan(g.dv, vec3(0.0f)));
  return g;
}

// Per axis, where the ray leaves the cube of cells within `reach` of `cell` (kHuge on an axis it
// does not move along); reach 0: the cell itself.
vec3 faces_beyond(IN(CellRay) g, ivec3 cell, int reach) {
  return mix(vec3(kHuge), g.t_start + ((vec3(cell + g.stp * reach) + g.ahead) * g.edge - g.x0) * g.inv_dv, g.moves);
}

// A float index to int, at most `cap`: a leap far beyond the ray's end stops there.
int index_at_most(float x, int cap) { return x >= float(cap) ? cap : int(x); }

// Every lattice point from `first` on. True when the ray stopped.
RAY_INLINE bool walk_points(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int last, int first) {
  int i = first;
  int visited = -1;
  int rounds = (last - first + 1) / kChunk + 1;
  for (int round = 0; round < rounds && i <= last; ++round)
    for (int n = 0; n < kChunk && i <= last; ++n) {
      if (visit(r, L, s, k, w, i, 1)) return true;
      visited = i;
      i += 1;
      if (dense_run(r, L, s, k, i, visited, last, false, vec3(0.0f), vec3(0.0f))) return true;
    }
  return false;
}

// Space skipping by leaps from lattice point `first` on (the points before it lie in empty
// cells). True when the ray stopped.
RAY_INLINE bool walk_leaps(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int last, vec2 span, int first) {
  CellRay g = cell_ray(r, 0.0f);
  int i = first;
  int visited = -2;  // the last lattice index visited
  int rounds = (last + 2 + 8 * (g.grid.x + g.grid.y + g.grid.z)) / kChunk + 1;
  for (int round = 0; round < rounds && i <= last; ++round)
    for (int n = 0; n < kChunk && i <= last; ++n) {
      // (a point within rounding of a face may get either cell: both ranges hold what it reads)
      ivec3 c = cell_containing((g.x0 + lattice_t(L, float(i)) * g.dv) * (1.0f / g.edge));
      uint empty_distance = cell_distance(c);
      if (empty_distance == 0u) {
        if (V.segments && i >= 1 && visited != i - 1 && visit(r, L, s, k, w, i - 1, 1)) return true;  // the segment into the run
        if (visit(r, L, s, k, w, i, 1)) return true;
        visited = i;
        i += 1;
        if (dense_run(r, L, s, k, i, visited, last, true, g.x0, g.dv)) return true;
      } else {
        if (V.segments && visited == i - 1) {  // the segment out of the run
          if (visit(r, L, s, k, w, i, 1)) return true;
          visited = i;
        }
        vec3 t_face = faces_beyond(g, c, int(empty_distance) - 1);
        float t_leave = min(min(t_face.x, t_face.y), t_face.z);
        i = max(i + 1, index_at_most(ceil(lattice_index(L, min(t_leave, span.y + r.step))), last + 1));
      }
    }
  return false;
}

// walk_cells: the points owed after a run of occupied cells (run_end: its last index; -1: none
// owed), visited once the run ends (before an empty cell, a leap or the ray's end), never one
// visited already. True when the ray stopped.
bool end_run(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int last, INOUT(int) next, INOUT(int) run_end) {
  if (!V.segments || run_end < 0) return false;
  int end = min(last, run_end + kExtension);
  for (int j = max(next, run_end + 1); j <= end; ++j)
    if (visit(r, L, s, k, w, j, 1)) return true;
  next = max(next, end + 1);
  run_end = -1;
  return false;
}

// walk_cells: an occupied cell's lattice points first..end, every m-th from the first not yet
// visited; each stands for the steps up to the next one, the cell's last for those up to the
// cell's end, so the cells' samples cover the ray without gaps or overlaps. Segment methods first
// visit the points just before the run (an occupied cell next continues the run from its own
// first point with its own multiplier, as the reference walks it). True when the ray stopped.
RAY_INLINE bool visit_cell(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int first, int end, int m, INOUT(int) next) {
  if (V.segments)
    for (int e = kExtension; e >= 1; --e)
      if (first - e >= next && visit(r, L, s, k, w, first - e, 1)) return true;
  int i = max(next, first);
  int visited = i - 1;
  // A target's fast path over the cell's points, for projections (the CPU's; GL's folds away).
  if (V.projection != kProjectionNone && m == 1 && dense_run(r, L, s, k, i, visited, end, false, vec3(0.0f), vec3(0.0f)))
    return true;
  while (i <= end) {  // in chunks (kChunk; a target without the loop limit takes one)
    int chunk_end = kChunk > 65535 ? end : min(end, i + (kChunk - 1) * m);
    for (; i <= chunk_end; i += m)
      if (visit(r, L, s, k, w, i, min(m, end + 1 - i))) return true;
  }
  next = max(next, end + 1);
  return false;
}

// walk_cells: every cell within reach of `cell` is empty; leap to where the ray leaves that cube
// and on to the cell beyond. False when the ray leaves the volume (or its span) first.
bool leap_cells(IN(CellRay) g, float t_exit, int reach, INOUT(ivec3) cell, INOUT(vec3) t_max, INOUT(float) t_in) {
  vec3 t_face = faces_beyond(g, cell, reach);
  float t_leave = min(min(t_face.x, t_face.y), t_face.z);
  if (t_leave >= t_exit) return false;
  vec3 x = g.x0 + (t_leave - g.t_start) * g.dv;
  ivec3 beyond = clamp(ivec3(floor(x / g.edge)), cell - reach, cell + reach);
  cell = ivec3(mix(vec3(beyond), vec3(cell + g.stp * (reach + 1)), lessThanEqual(t_face, vec3(t_leave))));
  if (any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, g.grid))) return false;
  t_max = faces_beyond(g, cell, 0);
  t_in = t_leave;
  return true;
}

// The macrocell 3D-DDA from the ray's start. True when the ray stopped.
RAY_INLINE bool walk_cells(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int last, vec2 span) {
  CellRay g = cell_ray(r, span.x);
  ivec3 cell = cell_containing(g.x0 / g.edge);
  vec3 t_delta = mix(vec3(kHuge), g.edge * abs(g.inv_dv), g.moves);
  vec3 t_max = faces_beyond(g, cell, 0);
  float t_in = span.x;
  int next = 0;      // the first lattice index not yet visited
  int run_end = -1;  // the last index of the run whose points after it are owed (end_run)
  // The next cell's first lattice index where the occupied cell before it gave it (its end + 1:
  // the same ceil(lattice_index(t)) at the face they share, without its square root); -1: unknown.
  int next_first = -1;
  for (int guard = 0; guard < 4 * (g.grid.x + g.grid.y + g.grid.z) + 4; ++guard) {
    ivec3 c = clamp(cell, ivec3(0), g.grid - 1);
    bool occupied = true;
    if (V.space_skipping) {
      uint empty_distance = cell_distance(c);
      occupied = empty_distance == 0u;
      if (!occupied) next_first = -1;
      if (!occupied && end_run(r, L, s, k, w, last, next, run_end)) return true;  // an empty cell or a leap: the run ends
      if (empty_distance > 1u && cell == c) {
        if (!leap_cells(g, span.y, int(empty_distance) - 1, cell, t_max, t_in)) break;
        continue;
      }
    } else if (projection_skips()) {  // a cell that cannot change the ray's maximum (minimum)
      occupied = projection_may_change(s, cell_range(c));
      if (!occupied) next_first = -1;
    }
    float t_out = min(min(t_max.x, t_max.y), t_max.z);
    bool final_cell = t_out >= span.y || any(lessThan(cell, ivec3(0))) || any(greaterThanEqual(cell, g.grid));
    if (occupied) {  // lattice points with t in [t_in, t_out); all remaining ones in the last cell
      int first = next_first >= 0 ? next_first : index_at_most(ceil(lattice_index(L, t_in)), last + 1);
      int end = final_cell ? last : min(last, index_at_most(ceil(lattice_index(L, t_out)), last + 1) - 1);
      if (visit_cell(r, L, s, k, w, first, end, V.adaptive ? cell_multiplier(c) : 1, next)) return true;
      run_end = end;
      next_first = end + 1;
    }
    if (final_cell || next > last) break;
    // Step to the neighbour across the nearest face; ties step every tied axis at once.
    for (int a = 0; a < 3; ++a)
      if (t_max[a] <= t_out) {
        cell[a] += g.stp[a];
        t_max[a] += t_delta[a];
      }
    t_in = t_out;
  }
  return end_run(r, L, s, k, w, last, next, run_end);  // a run that reaches the last cell (or the guard)
}

// Which walk the variant takes (walk_ray's `kind`).
SHARED_CONST int kWalkPoints = 0;
SHARED_CONST int kWalkLeaps = 1;
SHARED_CONST int kWalkCells = 2;
int walk_kind() {
  if (projection_skips()) return kWalkCells;  // (space skipping is off for projections)
  if (!V.space_skipping && !V.adaptive) return kWalkPoints;
  return V.adaptive ? kWalkCells : kWalkLeaps;
}

// The ray's walk of the given kind (walk_kind(); a constant, so the others fold away) from
// lattice point `first` (leaps only: the points before it lie in empty cells), then its last
// segment. A brick starts where the points it samples before its own (k.behind: one, or two with
// virtual samples) are visited as in one process: at them (every point), one before them (leaps:
// whether a point is visited depends on its neighbours only), at the ray's start (the 3D-DDA: a
// cell's first point depends on the cells before it).
RAY_INLINE void walk_ray(IN(Ray) r, IN(Lattice) L, INOUT(RayState) s, INOUT(RayWalk) k, INOUT(SampleWindow) w, int last, vec2 span, int first, int kind) {
  int behind = V.virtual_samples != 0 ? 2 : (V.segments ? 1 : 0);
  bool stopped;
  if (kind == kWalkPoints)
    stopped = walk_points(r, L, s, k, w, last, max(k.own_first - behind, 0));
  else if (kind == kWalkLeaps)
    stopped = walk_leaps(r, L, s, k, w, last, span, max(first, k.own_first - behind - 1));
  else
    stopped = walk_cells(r, L, s, k, w, last, span);
  if (!stopped) {
    if (V.virtual_samples != 0)
      vs_finish(r, s, w, L, last, k.own_last, span.y);
    else if (V.preintegration)
      close_segment(r, s, span.y, k.expect == k.ray_last + 1);
  }
  if (V.projection != kProjectionNone) finish_projection(s);
}
