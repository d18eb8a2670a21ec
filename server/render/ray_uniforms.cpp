#include "render/ray_uniforms.h"

#include <cstddef>

#include "core/camera.h"
#include "core/clip.h"
#include "core/sampling.h"
#include "core/transfer_function.h"

namespace peakcast::render {

ray::RayUniforms make_ray_uniforms(const ResolvedScene& s, const Volume& resident, ValueMap map,
                                   const MacrocellGrid& cells, const TableShape& tables, const PixelRect& rect,
                                   int sample_cap, const Brick* brick) {
  const SamplingPlan plan = plan_sampling(s);
  const glm::dvec3 center = (s.box_min + s.box_max) * 0.5;
  const ViewSetup view = setup_view(s.camera, center, s.scene.width, s.scene.height);
  ray::RayUniforms u{};
  u.p0 = glm::vec3(view.p0);
  u.eye_distance = float(view.dist);
  u.right = glm::vec3(view.right);
  u.half_width = float(view.half_w);
  u.up = glm::vec3(view.up);
  u.half_height = float(view.half_h);
  u.forward = glm::vec3(view.forward);
  u.step = float(plan.step);
  u.box_half = glm::vec3((s.box_max - s.box_min) * 0.5);
  u.stop = float(s.scene.render.early_termination);
  u.sample_half = u.box_half;
  u.sample_cap = sample_cap;
  u.spacing = glm::vec3(resident.spacing);
  u.min_spacing = std::min(u.spacing.x, std::min(u.spacing.y, u.spacing.z));
  u.inv_spacing = 1.f / u.spacing;
  u.value_scale = map.scale;
  u.value_bias = map.bias;
  const auto dims = resident.dims();
  u.inv_dims = 1.f / glm::vec3(float(dims[0]), float(dims[1]), float(dims[2]));
  u.background = glm::vec3(s.scene.background);
  u.cell_grid = glm::ivec3(int(cells.grid[0]), int(cells.grid[1]), int(cells.grid[2]));
  u.cell_edge = float(cells.cell);
  const auto clip = center_clip<glm::vec3, float>(s.scene.render.clip, center);
  u.clip_lo = clip.lo;
  u.clip_box = clip.box ? 1 : 0;
  u.clip_hi = clip.hi;
  u.clip_plane = clip.plane ? 1 : 0;
  u.clip_normal = clip.normal;
  u.clip_offset = clip.offset;
  u.image_width = s.scene.width;
  u.image_height = s.scene.height;
  u.tile_x = rect.x;
  u.tile_y = rect.y;
  u.peak_bins = tables.peak_bins;
  u.peak_layers = tables.peak_layers;
  u.max_peaks = s.scene.render.max_peaks;
  u.secant_iterations = s.scene.render.secant_iterations;
  u.preint_size = tables.preint_size;
  u.tf_point_count = tables.tf_point_count;
  u.differential_k = float(plan.k);
  u.min_step = float(plan.min_step);
  if (brick) {
    u.sample_half = u.box_half - glm::vec3(brick->read_lo * resident.spacing);
    u.own_lo = glm::vec3(brick->own_lo);
    u.own_hi = glm::vec3(brick->own_hi);
    for (int a = 0; a < 3; ++a) {
      u.open_lo |= brick->at_start[a] ? 1 << a : 0;
      u.open_hi |= brick->at_end[a] ? 1 << a : 0;
    }
    u.stop = 1.f;  // until opaque: no rank sees the opacity in front of its brick
    if (brick->front_opacity) u.front_opacity_width = rect.w;  // ray textures (the backend reads it only then)
  }
  return u;
}

ray::Variant shared_variant(const VariantKey& key) {
  ray::Variant v{};
  v.orthographic = key.orthographic;
  v.differential = key.differential;
  v.shading = key.shading;
  v.adaptive = key.adaptive;
  v.space_skipping = key.space_skipping;
  v.virtual_samples = key.virtual_samples;
  v.peaks = key.peaks;
  v.peak_xor = key.peaks && key.peak_mode == PeakMode::Xor;
  v.peaks_only = key.peaks && key.peak_mode == PeakMode::PeaksOnly;
  v.preintegration = key.preintegration;
  v.segments = key.peaks || key.preintegration || key.virtual_samples != 0;
  v.ray_texture = key.ray_texture;
  v.ray_texture_volume = key.ray_texture && key.ray_texture_volume;
  v.brick = key.brick;
  v.projection = key.projection;
  return v;
}

std::map<std::string, size_t> host_uniform_offsets() {
  using ray::RayUniforms;
#define PEAKCAST_OFFSET(name) \
  { "RayUniforms." #name, offsetof(RayUniforms, name) }
  return {PEAKCAST_OFFSET(p0),
          PEAKCAST_OFFSET(eye_distance),
          PEAKCAST_OFFSET(right),
          PEAKCAST_OFFSET(half_width),
          PEAKCAST_OFFSET(up),
          PEAKCAST_OFFSET(half_height),
          PEAKCAST_OFFSET(forward),
          PEAKCAST_OFFSET(step),
          PEAKCAST_OFFSET(box_half),
          PEAKCAST_OFFSET(stop),
          PEAKCAST_OFFSET(sample_half),
          PEAKCAST_OFFSET(sample_cap),
          PEAKCAST_OFFSET(spacing),
          PEAKCAST_OFFSET(min_spacing),
          PEAKCAST_OFFSET(inv_spacing),
          PEAKCAST_OFFSET(value_scale),
          PEAKCAST_OFFSET(inv_dims),
          PEAKCAST_OFFSET(value_bias),
          PEAKCAST_OFFSET(background),
          PEAKCAST_OFFSET(unused3),
          PEAKCAST_OFFSET(cell_grid),
          PEAKCAST_OFFSET(cell_edge),
          PEAKCAST_OFFSET(own_lo),
          PEAKCAST_OFFSET(open_lo),
          PEAKCAST_OFFSET(own_hi),
          PEAKCAST_OFFSET(open_hi),
          PEAKCAST_OFFSET(clip_lo),
          PEAKCAST_OFFSET(clip_box),
          PEAKCAST_OFFSET(clip_hi),
          PEAKCAST_OFFSET(clip_plane),
          PEAKCAST_OFFSET(clip_normal),
          PEAKCAST_OFFSET(clip_offset),
          PEAKCAST_OFFSET(image_width),
          PEAKCAST_OFFSET(image_height),
          PEAKCAST_OFFSET(tile_x),
          PEAKCAST_OFFSET(tile_y),
          PEAKCAST_OFFSET(peak_bins),
          PEAKCAST_OFFSET(peak_layers),
          PEAKCAST_OFFSET(max_peaks),
          PEAKCAST_OFFSET(secant_iterations),
          PEAKCAST_OFFSET(preint_size),
          PEAKCAST_OFFSET(tf_point_count),
          PEAKCAST_OFFSET(differential_k),
          PEAKCAST_OFFSET(min_step),
          PEAKCAST_OFFSET(front_opacity_width),
          PEAKCAST_OFFSET(unused0),
          PEAKCAST_OFFSET(unused1),
          PEAKCAST_OFFSET(unused2)};
#undef PEAKCAST_OFFSET
}

}  // namespace peakcast::render
