// The ray caster's tables: TF-dependent ones (peak table, preintegration table) and the ones
// that follow the data or the scene (adaptive multipliers, ray texture), each cached on what
// it depends on. See gl_renderer.cpp for the frame itself.
#include <sstream>

#include "core/preintegration.h"
#include "gpu/gl_renderer.h"
#include "render/shader_interface.h"
#include "gpu/table_cache.h"

namespace peakcast::gpu {

using namespace render;  // the renderer interface and frame setup this implements

gpu::Buffer make_cell_buffer(const MacrocellGrid& cells, const std::vector<uint8_t>& bytes) {
  if (bytes.size() != cells.size()) throw std::invalid_argument("make_cell_buffer: one byte per cell");
  std::vector<uint32_t> words((bytes.size() + 3) / 4, 0u);
  for (size_t i = 0; i < bytes.size(); ++i) words[i / 4] |= uint32_t(bytes[i]) << (8 * (i % 4));
  gpu::Buffer buf = gpu::make_buffer();
  glNamedBufferStorage(buf.id(), GLsizeiptr(std::max<size_t>(1, words.size()) * sizeof(uint32_t)), words.data(), 0);
  return buf;
}

// The ray texture as an RGB32F texture read with linear filtering between texel centres,
// clamped at the edges (what sample_ray_texture does on the CPU): made when the host cache
// builds a lineage, refreshed by the rectangle new strokes touched.
void GlRenderer::bind_ray_texture(const ResolvedScene& s, RenderStats* stats) {
  const auto t0 = Clock::now();
  auto u = ray_textures_.get(*s.ray_texture, s.scene.render.early_termination);
  RayTextureEntry& e = *u.entry;
  if (u.created) {
    e.extra = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(e.extra.id(), 1, GL_RGB32F, e.texels.width(), e.texels.height());
    glTextureParameteri(e.extra.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(e.extra.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(e.extra.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(e.extra.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  }
  const TexelRect& dirty = u.dirty;
  if (!dirty.empty()) {  // only the touched rectangle of rows goes up
    const int w = e.texels.width();
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, w);
    const float* first = e.texels.texels().data() + (size_t(dirty.y0) * size_t(w) + size_t(dirty.x0)) * 3;
    glTextureSubImage2D(e.extra.id(), 0, dirty.x0, dirty.y0, dirty.x1 - dirty.x0, dirty.y1 - dirty.y0, GL_RGB, GL_FLOAT,
                        first);
    glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  }
  glBindTextureUnit(kUnitRayTexture, e.extra.id());
  if (stats) {
    stats->ray_texture_ms = ms_since(t0);
    stats->ray_texture_strokes = int64_t(u.applied);
    stats->ray_texture_texels = dirty.empty() ? 0 : int64_t(dirty.x1 - dirty.x0) * (dirty.y1 - dirty.y0);
  }
}

// The adaptive multipliers of a volume's grid: data only (no TF), so built once per grid.
void GlRenderer::bind_multipliers(const GlVolume& gv, const MacrocellGrid& cells) {
  const std::string key = std::to_string(gv.serial()) + " " + cells.to_string();
  StrideEntry* e = cache_find(stride_cache_, key);
  if (!e) {
    StrideEntry n{key, make_cell_buffer(cells, adaptive_multipliers(cells, volume_stddev(gv.volume())))};
    e = &cache_insert(stride_cache_, std::move(n), kCacheEntries);
    ++table_builds_;
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboCellStride, e->buffer.id());
}

void GlRenderer::bind_cell_ranges(const GlVolume& gv, const MacrocellGrid& cells) {
  const std::string key = std::to_string(gv.serial()) + " " + cells.to_string();
  StrideEntry* e = cache_find(range_cache_, key);
  if (!e) {
    const std::vector<glm::vec2> ranges = cell_ranges(cells, gv.tf_lo(), gv.tf_hi());
    StrideEntry n{key, gpu::make_buffer()};
    glNamedBufferStorage(n.buffer.id(), GLsizeiptr(std::max<size_t>(1, ranges.size()) * sizeof(glm::vec2)),
                         ranges.data(), 0);
    e = &cache_insert(range_cache_, std::move(n), kCacheEntries);
    ++table_builds_;
  }
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboCellRange, e->buffer.id());
}

void GlRenderer::upload_tables(const GlVolume& gv, const ResolvedScene& s, const std::vector<Peak>& peaks) {
  const RenderSettings& r = s.scene.render;
  const double lo = gv.tf_lo(), hi = gv.tf_hi();
  // The tables depend on the TF, the value range, the method's sizes and (preintegration) the
  // step: a frame that changes none of them (a camera move) reuses what is bound.
  const std::string key = tables_key(s, lo, hi, peaks.size());
  if (const Tables* t = cache_find(tables_cache_, key)) {
    if (t->peak_table) glBindTextureUnit(kUnitPeakTable, t->peak_table.id());
    if (t->tf_points) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboTfPoints, t->tf_points.id());
    if (t->preint_table) glBindTextureUnit(kUnitPreint, t->preint_table.id());
    tables_ = t->sizes;
    return;
  }
  Tables t;
  t.key = key;
  if (r.classification == Classification::Peaks) {
    const PeakTable table = build_peak_table(peaks, lo, hi, r.peak_table_bins);
    const std::vector<float> texels = peak_texels(table, lo, hi);
    t.peak_table = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
    glTextureStorage3D(t.peak_table.id(), 1, GL_RGBA32F, table.bins, table.bins, table.layers);
    glTextureSubImage3D(t.peak_table.id(), 0, 0, 0, 0, table.bins, table.bins, table.layers, GL_RGBA, GL_FLOAT,
                        texels.data());
    glTextureParameteri(t.peak_table.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t.peak_table.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTextureUnit(kUnitPeakTable, t.peak_table.id());
    t.sizes.peak_bins = table.bins;
    t.sizes.peak_layers = table.layers;
    t.sizes.max_peaks = r.max_peaks;
    t.sizes.secant_iterations = r.secant_iterations;
    t.sizes.peak_count = peaks.size();
  }
  if (r.classification == Classification::Peaks || is_projection(r.classification)) {  // tf_exact's points
    const std::vector<glm::vec4> points = tf_point_pairs(s.tf, lo, hi);
    t.tf_points = gpu::make_buffer();
    glNamedBufferStorage(t.tf_points.id(), GLsizeiptr(points.size() * sizeof(glm::vec4)), points.data(), 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboTfPoints, t.tf_points.id());
    t.sizes.tf_points = int(s.tf.points.size());
  }
  if (r.classification == Classification::Preint) {
    const PreintegrationTable table = scene_preintegration(s, lo, hi);
    t.preint_table = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(t.preint_table.id(), 1, GL_RGBA32F, table.size, table.size);
    glTextureSubImage2D(t.preint_table.id(), 0, 0, 0, table.size, table.size, GL_RGBA, GL_FLOAT, table.rgba.data());
    glTextureParameteri(t.preint_table.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(t.preint_table.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(t.preint_table.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(t.preint_table.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glBindTextureUnit(kUnitPreint, t.preint_table.id());
    t.sizes.preint_size = table.size;
  }
  tables_ = t.sizes;
  cache_insert(tables_cache_, std::move(t), kCacheEntries);
  ++table_builds_;
}

}  // namespace peakcast::gpu
