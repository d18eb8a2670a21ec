// The CPU ray caster's macrocell walks: space skipping by lattice-driven leaps (SAMPLE_LEAPS in
// shaders/raycast_body.glsl) and the 3D-DDA over the cells (adaptive multipliers, the tests'
// CELL_DDA). Included per SIMD target by cpu/ray_kernel.cpp (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_RAY_WALKS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_WALKS_INL_H_
#undef PEAKCAST_CPU_RAY_WALKS_INL_H_
#else
#define PEAKCAST_CPU_RAY_WALKS_INL_H_
#endif

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <hwy/highway.h>

#include "cpu/ray_caster-inl.h"

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

uint8_t cell_byte(const uint8_t* table, const CpuFrame& f, ivec3 c) {
  return table[size_t(c.x) + size_t(f.u.cell_grid.x) * (size_t(c.y) + size_t(f.u.cell_grid.y) * size_t(c.z))];
}

// Space skipping without adaptive multipliers, driven by the lattice with empty-space leaps
// (SAMPLE_LEAPS in raycast_body.glsl). True when the ray stopped early.
bool RayCaster::walk_leaps(float span_y, int first) {
  const float edge = P.cell_edge;
  const vec3 xo = cell_coords(r_.o);
  const vec3 dv = r_.d / P.spacing;
  const ivec3 grid = P.cell_grid;
  ivec3 stp;
  vec3 inv_dv, ahead;
  bool moves[3];
  for (int a = 0; a < 3; ++a) {
    stp[a] = dv[a] > 0.f ? 1 : (dv[a] < 0.f ? -1 : 0);
    moves[a] = std::abs(dv[a]) >= 1e-20f;
    inv_dv[a] = moves[a] ? 1.f / dv[a] : 0.f;
    ahead[a] = dv[a] > 0.f ? 1.f : 0.f;
  }
  int i = first, visited = -2;
  const int64_t limit = int64_t(last_) + 2 + 8 * int64_t(grid.x + grid.y + grid.z) + 4096;
  for (int64_t iter = 0; iter < limit && i <= last_; ++iter) {
    const vec3 x = xo + lattice_t(L_, float(i)) * dv;
    ivec3 c;
    for (int a = 0; a < 3; ++a) c[a] = cell_of(x[a] * (1.f / edge), grid[a] - 1);
    const uint8_t empty_distance = cell_byte(f_.cell_distance, f_, c);
    if (empty_distance == 0) {
      if (segments_ && i >= 1 && visited != i - 1 && visit(i - 1, 1)) return true;  // the segment into the run
      if (visit(i, 1)) return true;
      visited = i;
      ++i;
      if (dense_ && dense_run<true>(i, visited, xo, dv, grid)) return true;
    } else {
      if (segments_ && visited == i - 1) {  // the segment out of the run
        if (visit(i, 1)) return true;
        visited = i;
      }
      const int reach = int(empty_distance) - 1;
      float t_leave = kHuge;
      for (int a = 0; a < 3; ++a)
        if (moves[a]) t_leave = std::min(t_leave, (float(c[a] + stp[a] * reach + ahead[a]) * edge - xo[a]) * inv_dv[a]);
      const float next = std::ceil(lattice_index(L_, std::min(t_leave, span_y + P.step)));
      i = std::max(i + 1, index_floor_cap(next, last_ + 1));
    }
  }
  return false;
}

template <bool kCells>
bool RayCaster::dense_run(int& i, int& visited, vec3 xo, vec3 dv, ivec3 grid) {
  const bool preint = f_.key.preintegration;
  vec4 acc = s_.acc;
  float samples = s_.samples, prev_f = s_.prev_f;
  const int first = i;
  bool stopped = false;
  const float dt = lattice_step(L_, 0.f, 1.f);  // uniform steps (the ray texture's multiplier in it)
  const bool whole = dt == P.step;             // the table's own step: no correction
  while (i <= last_) {
    if constexpr (kCells) {  // walk_leaps's cell test, as it would make it
      const vec3 x = xo + lattice_t(L_, float(i)) * dv;
      ivec3 c;
      for (int a = 0; a < 3; ++a) c[a] = cell_of(x[a] * (1.f / P.cell_edge), grid[a] - 1);
      if (cell_byte(f_.cell_distance, f_, c) != 0) break;
    }
    const float fv = field_at(i, 1);
    samples += 1.f;
    vec4 s;
    if (preint) {  // the segment from the previous point (visited without a gap)
      if (preint_lookup(prev_f, fv, s)) composite_premultiplied(acc, s, s_.dvr_weight);
    } else if (tf_lookup(fv, s) && s.a < 1.f) {
      // (The first point is never in a run; the last one's chord is cut at the exit.) One cold
      // call: more of them made the compiler keep the ray's opacity in memory.
      const float a = HWY_LIKELY(whole && i != last_) ? 1.f - s.a : dense_opacity_slow(s.a, i, dt);
      composite(acc, vec3(s), a * s_.dvr_weight);
    }
    prev_f = fv;
    visited = i++;
    if (acc.a >= s_.stop) {
      stopped = true;
      break;
    }
  }
  s_.acc = acc;
  s_.samples = samples;
  if (i > first) {  // as the last consume leaves them
    s_.prev_t = lattice_t(L_, float(visited));
    s_.prev_f = prev_f;
    k_.expect = visited + 1;
  }
  return stopped;
}

// The 3D-DDA over the macrocells (Amanatides & Woo): adaptive multipliers, or the tests' CELL_DDA.
bool RayCaster::walk_cells(float span_x, float span_y) {
  const float edge = P.cell_edge;
  const vec3 x0 = cell_coords(r_.o + span_x * r_.d);
  const vec3 dv = r_.d / P.spacing;
  const ivec3 grid = P.cell_grid;
  ivec3 cell, stp;
  vec3 inv_dv, ahead, t_delta, t_max;
  bool moves[3];
  for (int a = 0; a < 3; ++a) {
    cell[a] = std::clamp(int(std::floor(x0[a] / edge)), 0, grid[a] - 1);
    stp[a] = dv[a] > 0.f ? 1 : (dv[a] < 0.f ? -1 : 0);
    moves[a] = std::abs(dv[a]) >= 1e-20f;
    inv_dv[a] = moves[a] ? 1.f / dv[a] : 0.f;
    ahead[a] = dv[a] > 0.f ? 1.f : 0.f;
    t_delta[a] = moves[a] ? edge * std::abs(inv_dv[a]) : kHuge;
    t_max[a] = moves[a] ? span_x + ((float(cell[a]) + ahead[a]) * edge - x0[a]) * inv_dv[a] : kHuge;
  }
  auto outside = [&](ivec3 c) {
    return c.x < 0 || c.y < 0 || c.z < 0 || c.x >= grid.x || c.y >= grid.y || c.z >= grid.z;
  };
  float t_in = span_x;
  int next = 0;  // first lattice index not yet visited
  const int last = last_;
  // Segment methods visit EXTENSION points after a run of occupied cells, so that the segment
  // leaving it is not lost: once the run ends, before an empty cell, a leap or the ray's end. An
  // occupied cell next continues the run from its own first point with its own multiplier, as the
  // reference walks it (visited right away, the point would shift the next cell's samples).
  int run_end = -1;  // the last index of the run whose points after it are owed
  auto end_run = [&]() {
    if (!segments_ || run_end < 0) return false;
    const int end = std::min(last, run_end + kExtension);
    for (int j = std::max(next, run_end + 1); j <= end; ++j)
      if (visit(j, 1)) return true;
    next = std::max(next, end + 1);
    run_end = -1;
    return false;
  };
  for (int guard = 0; guard < 4 * (grid.x + grid.y + grid.z) + 4; ++guard) {
    const ivec3 c = glm::clamp(cell, ivec3(0), grid - 1);
    bool occupied = true;
    if (f_.key.space_skipping) {
      const uint8_t empty_distance = cell_byte(f_.cell_distance, f_, c);
      if (empty_distance > 1 && cell == c) {
        if (end_run()) return true;
        // Every cell within empty_distance - 1 of this one is empty: leap out of that cube.
        const int reach = int(empty_distance) - 1;
        vec3 t_face;
        for (int a = 0; a < 3; ++a)
          t_face[a] = moves[a] ? span_x + ((float(cell[a] + stp[a] * reach) + ahead[a]) * edge - x0[a]) * inv_dv[a]
                               : kHuge;
        const float t_leave = std::min(std::min(t_face.x, t_face.y), t_face.z);
        if (t_leave >= span_y) break;
        const vec3 x = x0 + (t_leave - span_x) * dv;
        for (int a = 0; a < 3; ++a) {
          const int beyond = std::clamp(int(std::floor(x[a] / edge)), cell[a] - reach, cell[a] + reach);
          cell[a] = t_face[a] <= t_leave ? cell[a] + stp[a] * (reach + 1) : beyond;
        }
        if (outside(cell)) break;
        for (int a = 0; a < 3; ++a)
          t_max[a] = moves[a] ? span_x + ((float(cell[a]) + ahead[a]) * edge - x0[a]) * inv_dv[a] : kHuge;
        t_in = t_leave;
        continue;
      }
      occupied = empty_distance == 0;
    }
    const float t_out = std::min(std::min(t_max.x, t_max.y), t_max.z);
    const bool final_cell = t_out >= span_y || outside(cell);
    // Lattice points with t in [t_in, t_out); all remaining ones in the last cell.
    const int first = index_floor_cap(std::ceil(lattice_index(L_, t_in)), last + 1);
    int end = final_cell ? last : std::min(last, index_floor_cap(std::ceil(lattice_index(L_, t_out)), last + 1) - 1);
    const int m = f_.key.adaptive ? std::clamp(int(cell_byte(f_.cell_stride, f_, c)), 1, 8) : 1;
    if (occupied) {
      int i = std::max(next, first);
      if (segments_)
        for (int e = kExtension; e >= 1; --e)
          if (first - e >= next && visit(first - e, 1)) return true;
      for (; i <= end; i += m)
        if (visit(i, std::min(m, end + 1 - i))) return true;
      next = std::max(next, end + 1);
      run_end = end;
    } else if (end_run()) {
      return true;
    }
    if (final_cell || next > last) break;
    // Step to the neighbour across the nearest face; ties step every tied axis at once.
    for (int a = 0; a < 3; ++a)
      if (t_max[a] <= t_out) {
        cell[a] += stp[a];
        t_max[a] += t_delta[a];
      }
    t_in = t_out;
  }
  return end_run();
}

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_WALKS_INL_H_
