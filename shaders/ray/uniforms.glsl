// The ray caster's uniforms, one definition for both targets (std140 in GLSL: the block `P`;
// the struct RayUniforms in C++, filled by render/ray_uniforms.cpp for the GL and CPU backends).
// Every value has its own name. The layout keeps std140 and C++ in step: each vec3 starts a
// 16-byte row and is followed by one 4-byte scalar, other scalars come four to a row (a test
// compares the offsets GL reports with the C++ struct's). Positions are relative to the box
// centre, so a camera far away keeps float precision (ray_setup.glsl).
RAY_UNIFORMS_BEGIN
  vec3 p0;            float eye_distance;  // the view axis' point nearest the box centre; eye -> p0
  vec3 right;         float half_width;    // camera right; half the image plane's width per unit depth (orthographic: world units)
  vec3 up;            float half_height;   // camera up; likewise
  vec3 forward;       float step;          // view direction; the uniform step (world units)
  vec3 box_half;      float stop;          // half the box (world); early-termination opacity
  vec3 sample_half;   int sample_cap;      // voxel coordinates of the resident voxels are (p + sample_half) * inv_spacing (a brick's are moved by its first voxel); most lattice points a ray visits
  vec3 spacing;       float min_spacing;   // voxel spacing (world units per voxel); its smallest
  vec3 inv_spacing;   float value_scale;   // 1 / spacing; texel value -> TF coordinate: value_scale * v + value_bias
  vec3 inv_dims;      float value_bias;    // 1 / the resident texture's voxels per axis
  vec3 background;    int unused3;         // background colour
  ivec3 cell_grid;    float cell_edge;     // macrocells per axis; a cell's edge in voxels
  vec3 own_lo;        int open_lo;         // a brick's own box (whole-volume voxels) and the axes (bits) where that bound is the volume's own face, so none
  vec3 own_hi;        int open_hi;
  vec3 clip_lo;       int clip_box;        // render.clip, box-centred (core/clip.h): the crop box (clip_box 1 with one)
  vec3 clip_hi;       int clip_plane;      // ... clip_plane 1 with a plane
  vec3 clip_normal;   float clip_offset;   // the plane: kept where dot(p, clip_normal) >= clip_offset
  int image_width;    int image_height;    int tile_x;             int tile_y;             // the full image; the first pixel of this draw
  int peak_bins;      int peak_layers;     int max_peaks;          int secant_iterations;  // peak finding (Knoll §4)
  int preint_size;    int tf_point_count;  float differential_k;   float min_step;         // tables; differential sampling (Knoll §5)
  int front_opacity_width; int unused0;    int unused1;            int unused2;            // ray textures on a brick: the rows of the opacity in front (0: none)
RAY_UNIFORMS_END
