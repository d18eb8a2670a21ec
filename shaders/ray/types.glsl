// The ray and its sample lattice (docs/scenes.md). The ray is o + t d with o near the box (not
// at the eye), so t stays small even for a camera 1e6 away; t_eye is the eye's own parameter
// (rays start there). Lattice: sample j lies at t0 + j (B + A j / 2) (lattice.glsl).
struct Ray {
  vec3 o;
  vec3 d;
  float t_eye;
  // The frame's values the per-sample code reads, copied from the uniforms once per ray
  // (ray_from): on llvmpipe a uniform-block member read inside the sample loop is a gather on
  // every sample, which cost GL a third of its frame (docs/performance.md).
  vec3 voxel_half;    // voxel_at: the point at t lies at (o + t d + voxel_half) * inv_spacing (P.sample_half)
  vec3 inv_spacing;
  vec3 spacing;       // the field's gradient per world unit (field_gradient)
  vec3 inv_dims;      // 1 / the resident texture's voxels (GL's sample_field)
  float value_scale;  // texel value -> TF coordinate (GL's sample_field)
  float value_bias;
  float step;         // the scene's uniform step, the TF table's (step_opacity, segment_for_length)
  float min_spacing;  // shade
  int peak_bins;      // peak_bin
  int preint_size;    // the preintegration table's entries per side (GL's preint_lookup)
};

struct Lattice {
  float t0;
  float A;
  float B;
};

// One ray's compositing state while it is walked: what it has composited, its early termination
// and ray-texture weights, whether the sample being consumed is this ray's to draw, and the
// previous sample a segment starts from.
struct RayState {
  vec4 acc;           // premultiplied colour and opacity so far
  float samples;      // filter evaluations (root-solving steps included); -1: missed the box
  float stop;         // early-termination opacity (a ray texture's; on a brick, of the opacity over those in front)
  float dvr_weight;   // ray textures' blend: the factor of the DVR samples' opacity
  float peak_weight;  // ... and of the peaks'
  // Who draws what on a brick: a consume (a sample with the segment into it: its peaks, its
  // preintegrated colour, its DVR term, and the early-termination test after them) is the rank's
  // that owns the sample; a true sample is owned with its lattice point, a virtual one with the
  // true sample starting its segment. A sample not drawn (a look-behind, the Catmull-Rom
  // look-ahead) is still a segment's start and never stops the ray. Always true in one process.
  bool draw;
  float prev_t;       // the previous sample (segment methods)
  float prev_f;
  bool have_prev;
  bool gap;           // lattice points were skipped since it (an empty macrocell's): no segment across
  // Projections (ray/projection.glsl): the value projected so far (TF coordinates; a mean's sum
  // of value x chord), and a mean's chords summed (its weight).
  float proj;
  float proj_len;
};

// Virtual samples' window (Lee et al. 2010): the last four true samples, newest in .w (no dynamic
// indexing: on llvmpipe an indexed array lives in memory, which cost more than the tricubic
// fetches it saves).
struct SampleWindow {
  vec4 t;
  vec4 f;
  vec4 dt;
  vec3 g0;
  vec3 g1;
  vec3 g2;
  vec3 g3;
  int n;     // true samples waiting (0..4), the newest n of the window
  uint own;  // the window's samples owned (bricks): bit 0 the newest (.w) to bit 3 (.x)
};

// Where a ray's walk stands: the visits' bookkeeping that the walks (walks.glsl) and the visit
// (visit.glsl) share.
struct RayWalk {
  int expect;     // the lattice index that continues the last visit without a gap
  int own_first;  // the lattice points the ray composites (a brick's own; else all of them)
  int own_last;
  int ray_last;   // the whole ray's last lattice index (a brick's walk may end before it)
  float head;     // what the first and last samples' chords differ from a whole step by
  float tail;
  // Bricks: the last visits before the owned points, held back unsampled (index -1: none), newest
  // in .x: sampled only when they lead to the first owned visit without a gap (the segment into
  // it needs the one before, and virtual samples the window of the segment before that), so a
  // walk from the ray's start samples nothing in front. .xy: indices, .zw: their strides.
  ivec4 behind;
};
