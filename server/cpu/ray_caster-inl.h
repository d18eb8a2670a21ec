// One CPU ray: the ray code shared with the GL shader (shaders/ray/*.glsl), compiled as this
// class's members, its hooks for that code (the field from SIMD sample runs, the tables with one
// bit per cell, the macrocells, the dense_run fast path), and its state (the structs of
// shaders/ray/types.glsl). Defined across ray_kernel.cpp (setup, sample runs, entry points),
// ray_tables-inl.h (table lookups) and dense_run-inl.h (the fast path). Included per SIMD target by cpu/ray_kernel.cpp
// (Highway's -inl.h convention).
#if defined(PEAKCAST_CPU_RAY_CASTER_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef PEAKCAST_CPU_RAY_CASTER_INL_H_
#undef PEAKCAST_CPU_RAY_CASTER_INL_H_
#else
#define PEAKCAST_CPU_RAY_CASTER_INL_H_
#endif

#include <limits>

#include <hwy/highway.h>

#include "cpu/ray_geometry-inl.h"
#include "cpu/sampler-inl.h"
#include "cpu/table_bits.h"
#include "render/shader_interface.h"

#ifndef NO_PEAK_TEXEL
#define NO_PEAK_TEXEL (::peakcast::render::kNoPeakTexel)  // ray/peaks.glsl kNoPeakTexel
#endif

HWY_BEFORE_NAMESPACE();
namespace peakcast::cpu {
namespace HWY_NAMESPACE {
namespace {

// The switches of a frame without a projection: ray::Variant with `projection` hidden by the
// constant 0, so the compiler folds the projection's test out of every consume and visit of the
// DVR paths (read at run time, it cost peaks shaded 1.6% of its instructions).
struct DvrSwitches : ray::Variant {
  static constexpr int projection = 0;
};
template <class Switches>
Switches switches_of(const ray::Variant& v) {
  Switches s{};
  static_cast<ray::Variant&>(s) = v;
  return s;
}

// Switches: DvrSwitches, or ray::Variant for a projection (ray_kernel.cpp picks by the frame).
template <class Switches>
class RayCaster {
 public:
  explicit RayCaster(const CpuFrame& f)
      : P(f.u),
        V(switches_of<Switches>(f.v)),
        f_(f),
        dense_(f.dense_runs && !f.v.brick && !f.key.virtual_samples &&
               (f.v.projection != 0 || (!f.key.peaks && !f.key.shading && !f.key.differential && !f.key.adaptive))) {}

  RayResult cast(float px, float py) { return setup(px, py) ? walk(0) : result(); }
  // The ray through (px, py) up to its traversal; false (and samples -1) when it misses the box.
  bool setup(float px, float py);
  // The traversal from lattice index `first` (walk_leaps only: the points before it lie in empty
  // cells, as leaps_to_first_occupied found), then the ray's end.
  RayResult walk(int first);
  RayResult result() const { return {s_.acc, s_.samples}; }
  LeapInputs leap_inputs() { return {cell_coords(r_.o), r_.d / P.spacing, L_.t0, L_.A, L_.B, span_y_ + P.step, last_}; }

 private:
  // The frame's uniforms and switches, as the shared code (shaders/ray/) reads them.
  const ray::RayUniforms& P;
  const Switches V;
  // The ray code shared with the GL shader, as members (shaders/ray/cxx_prelude.h).
#include "ray/ray_setup.glsl"
#include "ray/lattice.glsl"
#include "ray/compositing.glsl"
#include "ray/shading.glsl"
#include "ray/catmull_rom.glsl"
#include "ray/peaks.glsl"
#include "ray/brick.glsl"
#include "ray/projection.glsl"
#include "ray/consume.glsl"
#include "ray/virtual_samples.glsl"
#include "ray/visit.glsl"
#include "ray/walks.glsl"
#include "ray/ray_start.glsl"

  // The field's hooks (the ray's copies of the uniforms are GL's: P is read here).
  float sample_field(const Ray&, vec3 x) const { return SamplePoint(f_.voxels, x); }
  vec3 field_gradient(const Ray&, vec3 x) const {  // central differences (the six samples at once)
    float s[6];
    SampleCross(f_.voxels, x, s);
    return vec3(s[0] - s[1], s[2] - s[3], s[4] - s[5]) / (2.f * P.spacing);
  }
  // The value at lattice index i: from the current run, or a new run from i (stride m).
  float field_at(int i, int m);
  float lattice_field(const Ray&, const Lattice&, int i, int m) { return field_at(i, m); }  // ray/virtual_samples.glsl
  float new_run(int i, int m);  // field_at's slow path: samples a new run from i

  // The TF table at s (colour, and the step's transparency in .a); false, leaving `out` alone,
  // where its opacity is exactly zero.
  bool tf_lookup(float s, vec4& out) const;
  static bool tf_lookup_in(const float* tf, const uint64_t* bits, float s, vec4& out);  // of the given table
  vec4 tf_point(int k) const { return f_.tf_points[k]; }
  // The peak table's cell (i, j), layer `layer`; peak_cell_any: layer 0 holds a peak there (one
  // bit per cell, so that a segment finding none does not read the table, which misses the cache).
  vec4 peak_slots(int i, int j, int layer) const {
    const float* p =
        f_.peak_texels + ((size_t(layer) * size_t(P.peak_bins) + size_t(j)) * size_t(P.peak_bins) + size_t(i)) * 4;
    return vec4(p[0], p[1], p[2], p[3]);
  }
  bool peak_cell_any(int i, int j) const { return test_bit(f_.peak_any, size_t(j) * size_t(P.peak_bins) + size_t(i)); }
  // The table at (s_front, s_back); false, leaving `out` alone, where it is exactly zero.
  bool preint_lookup(const Ray&, float s_front, float s_back, vec4& out) const;
  // The shared walk of kind kKind (walk_kind()) over this ray's state.
  template <int kKind>
  HWY_NOINLINE void walk_as(int first) {
    walk_ray(r_, L_, s_, k_, w_, last_, vec2(span_x_, span_y_), first, kKind);
  }
  // The ray start's hooks (ray/ray_start.glsl): the ray texture's controls at uv (bilinear
  // between texel centres, as GL's sampler) and the opacity of the bricks in front.
  vec3 ray_texture_at(vec2 uv) const {
    const auto c = sample_ray_texture(*f_.ray_texture, glm::dvec2(uv));
    return vec3(float(c[0]), float(c[1]), float(c[2]));
  }
  float front_opacity(vec2 pixel) const {
    if (!f_.front_opacity) return -1.f;
    return f_.front_opacity[size_t(int(pixel.y) - P.tile_y) * size_t(P.front_opacity_width) +
                            size_t(int(pixel.x) - P.tile_x)];
  }
  // The walks' hooks (ray/walks.glsl): the macrocell tables, one byte per cell in grid order.
  size_t cell_offset(ivec3 c) const {
    return size_t(c.x) + size_t(P.cell_grid.x) * (size_t(c.y) + size_t(P.cell_grid.y) * size_t(c.z));
  }
  uint cell_distance(ivec3 c) const { return f_.cell_distance[cell_offset(c)]; }
  vec2 cell_range(ivec3 c) const { return f_.cell_range[cell_offset(c)]; }
  int cell_multiplier(ivec3 c) const { return std::clamp(int(f_.cell_stride[cell_offset(c)]), 1, 8); }
  ivec3 cell_containing(vec3 x) const {
    return ivec3(cell_of(x.x, P.cell_grid.x - 1), cell_of(x.y, P.cell_grid.y - 1), cell_of(x.z, P.cell_grid.z - 1));
  }
  // From index i on, while the points lie in occupied cells (cells: tested as walk_leaps would;
  // else every point): sample, classify and composite as sample_visit and consume would, bit for
  // bit, with the ray's colour in locals (the loop-carried chain through s in memory cost a store
  // and a reload per sample). Only for plain DVR (postclassified or preintegrated, unshaded,
  // uniform steps, one process); advances i and visited; true when the ray stopped.
  // Held to the walks without it by Leaps.CpuDenseRunsEqualTheSharedWalks
  // (tests/gpu/empty_space_test.cpp).
  // Projections: the points up to `last` (walk_points: the ray's; visit_cell: the cell's), folded
  // into the ray's value by the shared project_sample with the ray's state in a local, so the
  // same operations in the same order: bit for bit the shared walk's (tests/gpu/projection_test.cpp).
  bool dense_run(const Ray&, const Lattice& L, RayState& s, RayWalk& k, int& i, int& visited, int last, bool cells,
                 vec3 xo, vec3 dv) {
    if (!dense_) return false;
    if (V.projection != kProjectionNone) return project_loop(L, s, k, i, visited, last);
    return cells ? dense_loop<true>(L, s, k, i, visited, last, xo, dv)
                 : dense_loop<false>(L, s, k, i, visited, last, xo, dv);
  }
  bool project_loop(const Lattice& L, RayState& s, RayWalk& k, int& i, int& visited, int last);
  template <bool kCells>
  bool dense_loop(const Lattice& L, RayState& s, RayWalk& k, int& i, int& visited, int last, vec3 xo, vec3 dv);
  // dense_loop's opacity for a step other than the table's (a ray texture's multiplier) or the
  // last point's chord.
  HWY_NOINLINE float dense_opacity_slow(const RayWalk& k, float T, int i, float dt) {
    return step_opacity(T, i == k.ray_last ? chord_at_ends(dt, i, 1, k.head, k.tail, k.ray_last) : dt, P.step);
  }

  const CpuFrame& f_;
  // Plain DVR (postclassified or preintegrated, unshaded, uniform steps, one process): runs of
  // occupied points go through dense_loop, which holds the colour in registers. Projections
  // without virtual samples (one process): project_loop.
  const bool dense_;
  float span_x_ = 0, span_y_ = 0;
  Ray r_;
  Lattice L_;
  // What the ray has composited, its termination and weights, and its previous sample (shared
  // with the shader: shaders/ray/types.glsl).
  RayState s_{vec4(0.f), 0.f, 1.f, 1.f, 1.f, true, 0.f, 0.f, false, false, 0.f, 0.f};
  int last_ = 0;  // the walk's last lattice index (a brick's may end before the ray's)
  RayWalk k_{0, 0, std::numeric_limits<int>::max(), 0, 0.f, 0.f, ivec4(-1, -1, 1, 1)};  // the walk's bookkeeping
  SampleWindow w_{vec4(0.f), vec4(0.f), vec4(0.f), vec3(0.f), vec3(0.f),
                  vec3(0.f), vec3(0.f), 0,         0u};  // virtual samples
  // The current run of samples (sample_run): indices run_first_ + k * run_stride_, k < run_count_.
  float run_[kMaxRun];
  int run_first_ = 0, run_stride_ = 1, run_count_ = 0, run_batch_ = 0;
};

}  // namespace
}  // namespace HWY_NAMESPACE
}  // namespace peakcast::cpu
HWY_AFTER_NAMESPACE();

#endif  // PEAKCAST_CPU_RAY_CASTER_INL_H_
