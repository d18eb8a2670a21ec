// The variant's switches that the shared code tests (server/render/variant.h chooses them per
// scene). GLSL: the constant `V` from the variant's #defines (glsl_prelude.glsl), so a branch
// on it is folded away; C++: a member of the frame's code, set from the VariantKey.
struct Variant {
  bool orthographic;
  bool differential;
  bool shading;
  bool adaptive;        // per-macrocell sample multipliers (walked by the 3D-DDA)
  bool space_skipping;  // empty macrocells are leapt over
  int virtual_samples;  // 0, or the virtual samples between true ones (3 or 7)
  bool peaks;           // peak finding between samples (Knoll §4)
  bool peak_xor;        // ... the DVR term left out where a peak was found
  bool peaks_only;      // ... peaks without the DVR term
  bool preintegration;
  bool segments;        // peaks, preintegration or virtual samples: the segment between samples matters
  bool ray_texture;     // per-ray controls (Raspe 2008): RayState's stop and weights vary per ray
  bool ray_texture_volume;  // ... read where the ray enters the box (else at its pixel)
  bool brick;           // distributed rendering: one brick's part of each ray (RayState.draw)
  int projection;       // kProjectionNone, or the intensity projection (ray/projection.glsl) that replaces compositing
};
