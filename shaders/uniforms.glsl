// The ray-cast uniform block. Mirrored by server/render/gpu_layout.h (std140; a test compares
// the offsets GL reports with the C++ struct). Positions are relative to the box centre so
// that a camera far away keeps float precision (see ray_setup.glsl).
layout(std140, binding = UBO_RAY) uniform RayUniforms {
  vec4 u_p0;         // xyz: point of the view axis nearest the box centre; w: unused
  vec4 u_right;      // xyz: camera right; w: half width of the image plane per unit depth (or world units, ortho)
  vec4 u_up;         // xyz: camera up; w: half height likewise
  vec4 u_forward;    // xyz: view direction; w: distance eye -> p0 along it
  vec4 u_box_half;   // xyz: half the box extent (world); w: uniform step (world units)
  vec4 u_spacing;    // xyz: voxel spacing; w: opacity unit (world units)
  vec4 u_dims;       // xyz: voxels per axis; w: early-termination opacity
  vec4 u_value_map;  // x, y: texel value -> TF coordinate (a*v + b); z: TF size; w: max samples
  vec4 u_background; // rgb background
  vec4 u_cells;      // xyz: macrocell grid; w: cell edge in voxels
  ivec4 u_image;     // x, y: full image size in pixels; z, w: first pixel of this draw (tile)
  vec4 u_peaks;      // x: peak-table bins; y: layers; z: max peaks per segment; w: secant iterations
  vec4 u_tables;     // x: preintegration table size; y: TF point count (exact TF at peaks); z: differential k; w: minimum step
  vec4 u_brick_half; // BRICK: xyz: what voxel_coords adds (half the box less the brick's first voxel, world); w: front opacity's row width (0: none)
  vec4 u_own_lo;     // BRICK: xyz: the owned box's low corner (whole-volume voxels); w: axes without that bound (bits)
  vec4 u_own_hi;     // BRICK: xyz: its high corner; w: likewise
  vec4 u_clip_lo;    // render.clip (box-centred): xyz: the crop box's low corner; w: 1 with a crop box
  vec4 u_clip_hi;    // xyz: its high corner; w: 1 with a clip plane
  vec4 u_clip_plane; // xyz: the plane's unit normal; w: its offset (kept: dot(p, normal) >= offset)
};
