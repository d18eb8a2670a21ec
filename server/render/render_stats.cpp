#include "render/render_stats.h"

#include <algorithm>
#include <sstream>

#include "core/scene.h"

namespace peakcast::render {

RenderStats RenderStats::for_scene(const ResolvedScene& s) {
  RenderStats st;
  st.tf_source = s.tf_derived ? "auto" : "scene";
  st.warnings = s.warnings;
  return st;
}

nlohmann::json RenderStats::to_json() const {
  nlohmann::json j = {
      {"render_ms", render_ms}, {"readback_ms", readback_ms},      {"table_ms", table_ms}, {"variant", variant},
      {"peaks", peaks},         {"empty_macrocells", empty_cells}, {"tiles", tiles},       {"tf_source", tf_source},
      {"warnings", warnings},   {"compile_ms", compile_ms}};
  if (gpu_ms >= 0) j["gpu_ms"] = gpu_ms;
  if (variant.find("+raytex") != std::string::npos) {
    j["ray_texture_ms"] = ray_texture_ms;
    j["ray_texture_strokes"] = ray_texture_strokes;
    j["ray_texture_texels"] = ray_texture_texels;
  }
  if (has_samples) {
    j["samples_per_ray"] = samples_mean;
    j["samples_per_ray_max"] = samples_max;
    j["rays_hit"] = rays_hit;
    j["rays_at_sample_cap"] = rays_at_cap;
    j["sample_cap"] = sample_cap;
  }
  return j;
}

std::string RenderStats::to_string() const {
  const nlohmann::json j = to_json();
  std::ostringstream s;
  s << "RenderStats{";
  bool first = true;
  for (const char* key :
       {"variant", "render_ms", "readback_ms", "table_ms", "samples_per_ray", "samples_per_ray_max", "rays_hit",
        "rays_at_sample_cap", "sample_cap", "peaks", "empty_macrocells", "tiles", "ray_texture_ms",
        "ray_texture_strokes", "ray_texture_texels", "tf_source", "warnings", "compile_ms", "gpu_ms"}) {
    if (!j.contains(key)) continue;
    s << (first ? "" : " ") << key << "="
      << (j[key].is_string() ? j[key].get<std::string>()
                             : j[key].dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    first = false;
  }
  s << "}";
  return s.str();
}

void RenderStats::merge(const RenderStats& t) {
  render_ms += t.render_ms;
  readback_ms += t.readback_ms;
  gpu_ms = gpu_ms >= 0 && t.gpu_ms >= 0 ? gpu_ms + t.gpu_ms : -1.0;
  compile_ms += t.compile_ms;
  table_ms += t.table_ms;
  has_samples = has_samples && t.has_samples;
  samples_total += t.samples_total;
  samples_max = std::max(samples_max, t.samples_max);
  rays_hit += t.rays_hit;
  rays_at_cap += t.rays_at_cap;
  sample_cap = std::max(sample_cap, t.sample_cap);
  samples_mean = rays_hit ? samples_total / double(rays_hit) : 0.0;
  tiles += t.tiles;
  ray_texture_ms += t.ray_texture_ms;
  ray_texture_strokes += t.ray_texture_strokes;
  ray_texture_texels += t.ray_texture_texels;
  if (!has_samples) samples_total = samples_mean = samples_max = 0.0, rays_hit = rays_at_cap = 0;
}

}  // namespace peakcast::render
