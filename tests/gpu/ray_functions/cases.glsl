// One row of the function table: the shared ray code's functions called with the row's inputs
// (kind in k.x; a, b, c), their answers in r0 and r1. Compiled as GLSL (probe.comp, a compute
// shader over the rows) and as C++ (ray_functions_test.cpp), so both targets make the same calls.
SHARED_CONST int kMakeRay = 0;     // make_ray
SHARED_CONST int kSpans = 1;       // intersect_box, clip_span
SHARED_CONST int kLattice = 2;     // ray_lattice, lattice_t, lattice_step, lattice_index
SHARED_CONST int kChord = 3;       // chord_head, chord_tail, chord_at_ends
SHARED_CONST int kOpacity = 4;     // step_opacity, segment_for_length
SHARED_CONST int kComposite = 5;   // composite over a sequence across opacity edges, premultiplied, finish_pixel
SHARED_CONST int kShade = 6;       // shade
SHARED_CONST int kCatmullRom = 7;  // catmull_rom, catmull_rom3 (virtual-sample windows)
SHARED_CONST int kPeakRoot = 8;    // solve_root, root_evaluations, crosses, tf_exact, peak_bin
SHARED_CONST int kBrick = 9;       // clip_to_brick, owns, index_near (brick faces)
SHARED_CONST int kFindPeaks = 10;  // find_peaks (the slot walk, roots, compositing)
SHARED_CONST int kConsume = 11;    // consume over a sequence of samples across opacity edges, close_segment
SHARED_CONST int kWindow = 12;     // the virtual-sample window: vs_push over a run with a gap, vs_finish
SHARED_CONST int kProject = 13;    // project_sample over six samples, finish_projection (projection variants)
SHARED_CONST int kKinds = 14;

// The field at lattice point i, for vs_finish (the targets read it from their sample runs).
float lattice_field(Ray r, Lattice L, int i, int m) { return sample_field(r, voxel_at(r, lattice_t(L, float(i)))); }
#include "ray/virtual_samples.glsl"

// Each function gets its inputs from the row (a ray as o = a.xyz, d = b.xyz; a lattice as c.xyz),
// not from another function's answer, so a difference names the function it is in.
void run_case(vec4 k, vec4 a, vec4 b, vec4 c, OUT(vec4) r0, OUT(vec4) r1) {
  int kind = int(k.x);
  r0 = vec4(0.0f);
  r1 = vec4(0.0f);
  Ray r = ray_from(vec3(a), vec3(b), a.w);
  Lattice L;
  L.t0 = c.x;
  L.A = c.y;
  L.B = c.z;
  if (kind == kMakeRay) {
    Ray m = make_ray(vec2(a.x, a.y));
    r0 = vec4(m.o, m.t_eye);
    r1 = vec4(m.d, 0.0f);
  } else if (kind == kSpans) {
    vec2 box = intersect_box(r);
    vec2 clipped = clip_span(r, vec2(k.y, k.z));
    r0 = vec4(box.x, box.y, clipped.x, clipped.y);
  } else if (kind == kLattice) {
    float j = k.y, m = k.z;
    Lattice R = ray_lattice(r, k.w);
    r0 = vec4(lattice_t(L, j), lattice_step(L, j, m), lattice_index(L, c.w), 0.0f);
    r1 = vec4(R.t0, R.A, R.B, 0.0f);
  } else if (kind == kChord) {
    int last = int(k.y), i = int(k.z), m = int(k.w);
    float head = chord_head(L), tail = chord_tail(L, c.w, last);
    r0 = vec4(head, tail, chord_at_ends(lattice_step(L, 0.0f, 1.0f), 0, 1, head, tail, last), 0.0f);
    r1 = vec4(chord_at_ends(lattice_step(L, float(last), 1.0f), last, 1, head, tail, last),
              chord_at_ends(lattice_step(L, float(i), float(m)), i, m, head, tail, last), 0.0f, 0.0f);
  } else if (kind == kOpacity) {
    r0 = vec4(step_opacity(a.x, a.y, r.step), step_opacity(a.x, r.step, r.step), step_opacity(a.z, a.w, r.step), 0.0f);
    r1 = segment_for_length(c, a.y, r.step);
  } else if (kind == kComposite) {
    vec4 acc = vec4(0.0f);
    for (int q = 0; q < 8; ++q) {
      float alpha = q < 4 ? a[q] : c[q - 4];
      composite(acc, vec3(0.2f, 0.5f, 0.9f) * (1.0f + 0.1f * float(q)), alpha);
    }
    vec4 pre = vec4(0.0f);
    composite_premultiplied(pre, vec4(0.1f, 0.2f, 0.3f, a.x), c.x);
    composite_premultiplied(pre, vec4(0.3f, 0.2f, 0.1f, a.y), c.y);
    r0 = acc;
    r1 = vec4(finish_pixel(acc), pre.w);
  } else if (kind == kShade) {
    r0 = vec4(shade(r, vec3(c), vec3(a)), 0.0f);
  } else if (kind == kCatmullRom) {
    r0 = vec4(catmull_rom(c.x, c.y, c.z, c.w, k.y), catmull_rom3(vec3(a), vec3(c), vec3(c.w, a.w, a.x), vec3(c.z, a.y, k.z), k.y));
  } else if (kind == kPeakRoot) {
    float t0 = k.y, t1 = k.z;
    float f0 = sample_field(r, voxel_at(r, t0)), f1 = sample_field(r, voxel_at(r, t1));
    float v = mix(min(f0, f1), max(f0, f1), c.x) + c.y;  // c.y moves v off the segment's range, or onto a tangency
    float evaluations = 0.0f;
    float t = solve_root(r, t0, f0, t1, f1, v, evaluations);
    r0 = vec4(t, evaluations, root_evaluations(f0, f1, v), crosses(f0, f1, v) ? 1.0f : 0.0f);
    vec4 exact = tf_exact(c.z);
    r1 = vec4(exact.x, exact.w, float(peak_bin(c.z, r.peak_bins)), float(peak_bin(c.w, r.peak_bins)));
  } else if (kind == kBrick) {
    vec2 span = vec2(k.y, k.z);
    int last = int(k.w);
    int walk_last = last, own_first = -1, own_last = -1;
    bool owned = clip_to_brick(r, L, span, walk_last, own_first, own_last);
    r0 = vec4(owned ? 1.0f : 0.0f, float(own_first), float(own_last), float(walk_last));
    r1 = vec4(owns(r, L, int(c.w)) ? 1.0f : 0.0f, float(index_near(L, mix(span.x, span.y, a.w), span, last)), 0.0f, 0.0f);
  } else if (kind == kFindPeaks) {
    RayState s = {vec4(0.0f), 0.0f, 0.95f, 1.0f, 0.7f, true, 0.0f, 0.0f, false, false, 0.0f, 0.0f};
    bool hit = find_peaks(r, s, k.y, c.x, k.z, c.y);
    r0 = s.acc;
    r1 = vec4(s.samples, hit ? 1.0f : 0.0f, 0.0f, 0.0f);
  } else if (kind == kConsume) {
    // Six samples at t = k.y + q * k.z with values from c and a.w, the fourth after a gap.
    RayState s = {vec4(0.0f), 0.0f, 0.99f, 0.8f, 1.0f, true, 0.0f, 0.0f, false, false, projection_start(), 0.0f};
    bool stopped = false;
    for (int q = 0; q < 6 && !stopped; ++q) {
      float f = q < 4 ? c[q] : (q == 4 ? a.w : c.x);
      if (q == 3) s.gap = true;
      stopped = consume(r, s, k.y + float(q) * k.z, f, vec3(c.y - 0.5f, c.z - 0.5f, 0.25f), k.z * (1.0f + 0.1f * float(q)));
    }
    if (!stopped) close_segment(r, s, k.y + 6.5f * k.z, true);
    r0 = s.acc;
    bool proj = V.projection != kProjectionNone;  // (a projection's consume keeps its value, not a segment's start)
    r1 = vec4(s.samples, proj ? s.proj : s.prev_t, proj ? s.proj_len : s.prev_f, stopped ? 1.0f : 0.0f);
  } else if (kind == kProject) {
    // Six samples as kConsume's through consume (a projection's), then the pixel's colour; in the
    // other variants the same samples composited.
    RayState s = {vec4(0.0f), 0.0f, 0.99f, 0.8f, 1.0f, true, 0.0f, 0.0f, false, false, projection_start(), 0.0f};
    bool stopped = false;
    int taken = 0;
    for (int q = 0; q < 6 && !stopped; ++q) {
      float f = q < 4 ? c[q] : (q == 4 ? a.w : c.x);
      stopped = consume(r, s, k.y + float(q) * k.z, f, vec3(0.0f), k.z * (0.5f + 0.1f * float(q)));
      taken = q + 1;
    }
    float projected = V.projection == kProjectionNone ? 0.0f : s.proj;
    if (V.projection != kProjectionNone) finish_projection(s);
    r0 = s.acc;
    r1 = vec4(projected, s.proj_len, float(taken), stopped ? 1.0f : 0.0f);
  } else if (kind == kWindow) {
    // True samples at lattice points 0..last of the ray's lattice, with a gap before point k.z,
    // each pushed into the window as sample_visit does, then the ray's end.
    RayState s = {vec4(0.0f), 0.0f, 0.995f, 1.0f, 1.0f, true, 0.0f, 0.0f, false, false, 0.0f, 0.0f};
    SampleWindow w = {vec4(0.0f), vec4(0.0f), vec4(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f), vec3(0.0f), 0, 0u};
    int last = min(int(k.y), 40), gap_at = int(k.z);
    bool stopped = false;
    for (int i = 0; i <= last && !stopped; ++i) {
      if (i == gap_at) continue;
      float t = lattice_t(L, float(i));
      if (i == gap_at + 1 && w.n > 0) {
        stopped = vs_flush(r, s, w, L.t0);
        s.gap = true;
      }
      if (!stopped)
        stopped = vs_push(r, s, w, L.t0, t, lattice_field(r, L, i, 1), field_gradient(r, voxel_at(r, t)),
                          lattice_step(L, float(i), 1.0f), true);
    }
    if (!stopped) vs_finish(r, s, w, L, last, last, c.w);
    r0 = s.acc;
    r1 = vec4(s.samples, s.prev_t, float(w.n), stopped ? 1.0f : 0.0f);
  }
}
