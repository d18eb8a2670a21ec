#include "cpu/cpu_renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/camera.h"
#include "core/parallel.h"
#include "core/sampling.h"
#include "cpu/table_bits.h"
#include "render/small_cache.h"

namespace peakcast::cpu {

using render::cache_find;
using render::cache_insert;
using render::Clock;
using render::ms_since;
using render::PixelRect;
using render::RenderResult;
using render::RenderStats;

namespace {

constexpr int kTile = kRayPacket;  // pixels per tile side: neighbouring rays share cache lines of the volume

const CpuVolume& cpu_volume(const render::ResidentVolume& v) {
  const auto* cv = dynamic_cast<const CpuVolume*>(&v);
  if (!cv)
    throw std::invalid_argument("the CPU renderer draws CPU volumes only (this one was made by another backend)");
  return *cv;
}

// The colour over the background and the opacity (output.glsl's finish_pixel).
glm::vec3 finish_pixel(const glm::vec4& acc, const glm::vec3& background) {
  return glm::vec3(acc) + (1.f - acc.a) * background;
}

// encode::to_rgb8 for one channel: non-finite -> 0, clamp, times 255 in float, round half up.
// Without lround's library call (three a pixel): y - int(y) is exact for y in [0, 255], so
// adding one where it is >= 0.5 rounds half up exactly as lround does for y >= 0.
inline uint8_t quantise(float v) {
  const float y = std::clamp(std::isfinite(v) ? v : 0.f, 0.f, 1.f) * 255.f;
  const int i = int(y);
  return uint8_t(i + (y - float(i) >= 0.5f ? 1 : 0));
}

}  // namespace

CpuRenderer::CpuRenderer(int threads) : threads_(threads > 0 ? threads : hardware_threads()) {}

std::string CpuRenderer::description() const {
  return std::string("CPU: ") + simd_target() + ", " + std::to_string(threads_) + " threads";
}

std::unique_ptr<render::ResidentVolume> CpuRenderer::make_resident(std::shared_ptr<const Volume> volume,
                                                                   VolumeMacrocells cells) {
  return std::make_unique<CpuVolume>(std::move(volume), std::move(cells));
}

int CpuRenderer::sample_cap(const render::VariantKey&) const { return kMaxSamplesPerRay; }

// The TF baked for the scene's step, with one bit per cell (cached by its key).
const CpuRenderer::TfTable& CpuRenderer::tf_table(const ResolvedScene& s, const std::string& tf_sig, double lo,
                                                  double hi) {
  const std::string tf_key = render::step_tf_key(s, tf_sig);
  TfTable* tf = cache_find(tf_tables_, tf_key);
  if (!tf) {
    std::vector<float> rgba = render::step_tf_table(s, lo, hi);
    std::vector<uint64_t> bits = tf_cell_bits(rgba, TransferFunction::kTableSize);
    tf = &cache_insert(tf_tables_, TfTable{tf_key, std::move(rgba), std::move(bits)}, kCacheEntries);
    ++table_builds_;
  }
  return *tf;
}

// The peak table and TF points, or the preintegration table (cached by what they depend on).
const CpuRenderer::Tables& CpuRenderer::tables(const ResolvedScene& s, const std::vector<Peak>& peaks, double lo,
                                               double hi) {
  const std::string key = render::tables_key(s, lo, hi, peaks.size());
  Tables* t = cache_find(tables_, key);
  if (t) return *t;
  Tables n;
  n.key = key;
  if (s.scene.render.classification == Classification::Peaks) {
    const PeakTable table = build_peak_table(peaks, lo, hi, s.scene.render.peak_table_bins);
    n.peak_texels = render::peak_texels(table, lo, hi);
    n.peak_bins = table.bins;
    n.peak_layers = table.layers;
    n.peak_any = peak_texel_bits(n.peak_texels, n.peak_bins);
  }
  if (s.scene.render.classification == Classification::Peaks || is_projection(s.scene.render.classification))
    n.tf_points = render::tf_point_pairs(s.tf, lo, hi);  // tf_exact's points
  if (s.scene.render.classification == Classification::Preint) {
    PreintegrationTable table = render::scene_preintegration(s, lo, hi);
    n.preint = std::move(table.rgba);
    n.preint_size = table.size;
    n.preint_any = preint_cell_bits(n.preint, n.preint_size);
  }
  ++table_builds_;
  return cache_insert(tables_, std::move(n), kCacheEntries);
}

// The per-macrocell bytes the walks read: empty-space distances (space skipping), multipliers
// (adaptive sampling; data only, built once per grid).
void CpuRenderer::cell_tables(CpuFrame& f, const CpuVolume& cv, const MacrocellGrid& cells,
                              const render::FrameSetup& fs) {
  if (f.key.space_skipping) {
    CellBytes* d = cache_find(distances_, fs.occupancy_key);
    if (!d) {
      std::vector<uint8_t> distance = render::traversal_distances(*fs.occupancy, setup_options_.leaps);
      const bool any = std::find(distance.begin(), distance.end(), uint8_t(0)) != distance.end();
      distance.resize(distance.size() + 4, 0);  // the packet leaps read 4 bytes at a cell's index
      d = &cache_insert(distances_, CellBytes{fs.occupancy_key, std::move(distance), any}, kCacheEntries);
    }
    f.cell_distance = d->bytes.data();
    f.nothing_visible = !d->any_occupied;
  }
  if (f.key.adaptive) {  // data only (no TF): built once per grid
    const std::string mkey = std::to_string(cv.serial()) + " " + cells.to_string();
    CellBytes* m = cache_find(multipliers_, mkey);
    if (!m) {
      m = &cache_insert(multipliers_, CellBytes{mkey, adaptive_multipliers(cells, volume_stddev(cv.volume()))},
                        kCacheEntries);
      ++table_builds_;
    }
    f.cell_stride = m->bytes.data();
  }
  if (f.key.projection_skips()) {  // data only: once per grid
    const std::string rkey = std::to_string(cv.serial()) + " " + cells.to_string();
    CellRanges* r = cache_find(ranges_, rkey);
    if (!r) {
      r = &cache_insert(ranges_, CellRanges{rkey, render::cell_ranges(cells, cv.tf_lo(), cv.tf_hi())}, kCacheEntries);
      ++table_builds_;
    }
    f.cell_range = r->ranges.data();
  }
}

CpuFrame CpuRenderer::prepare(const CpuVolume& cv, const ResolvedScene& s, render::RenderPath path,
                              const PixelRect& rect, const render::Brick* brick, RenderStats* stats) {
  const MacrocellGrid& cells = cv.macrocells(s.scene.render.filter);
  const render::FrameSetup fs = render::setup_frame(cv, s, path, setup_options_, occupancy_, table_builds_);
  const auto t_tables = Clock::now();
  const double lo = cv.tf_lo(), hi = cv.tf_hi();

  CpuFrame f;
  f.key = fs.key;
  f.key.cpu = true;
  f.voxels = cv.grid(s.scene.render.filter);
  f.run_lanes = sample_run_lanes();
  f.dense_runs = dense_runs_;

  const TfTable& tf = tf_table(s, fs.tf_sig, lo, hi);
  f.tf = tf.rgba.data();
  f.tf_alpha_any = tf.alpha_any.data();
  const std::vector<Peak> no_peaks;
  const Tables* t = &tables(s, f.key.peaks ? fs.peaks : no_peaks, lo, hi);
  f.peak_texels = t->peak_texels.data();
  f.tf_points = t->tf_points.data();
  f.preint = t->preint.data();
  const render::TableShape shape{t->peak_bins, t->peak_layers, t->preint_size, int(t->tf_points.size() / 2)};
  f.u = render::make_ray_uniforms(s, cv.volume(), render::ValueMap{}, cells, shape, rect, sample_cap(f.key), brick);
  f.v = render::shared_variant(f.key);
  f.v.brick = brick != nullptr;  // (the CPU's key keeps its name: "+brick" is added to the stats)
  f.peak_any = t->peak_any.data();
  f.preint_any = t->preint_any.data();

  cell_tables(f, cv, cells, fs);
  if (f.key.ray_texture) {
    const auto u = ray_textures_.get(*s.ray_texture, s.scene.render.early_termination);
    f.ray_texture = &u.entry->texels;
    if (stats) {
      stats->ray_texture_ms = u.ms;
      stats->ray_texture_strokes = int64_t(u.applied);
      stats->ray_texture_texels = u.dirty.empty() ? 0 : int64_t(u.dirty.x1 - u.dirty.x0) * (u.dirty.y1 - u.dirty.y0);
    }
  }
  if (stats) {
    stats->empty_cells = fs.occupancy->empty_cells;
    stats->peaks = fs.peaks.size();
    stats->table_ms = fs.table_ms + ms_since(t_tables);
  }
  return f;
}

template <class PerRow>
void CpuRenderer::for_each_row(const PixelRect& rect, const PerRow& fn) const {
  const int tiles_x = (rect.w + kTile - 1) / kTile, tiles_y = (rect.h + kTile - 1) / kTile;
  parallel_for(
      size_t(tiles_x) * size_t(tiles_y),
      [&](size_t tile) {
        const int x0 = int(tile % size_t(tiles_x)) * kTile, y0 = int(tile / size_t(tiles_x)) * kTile;
        for (int y = y0; y < std::min(rect.h, y0 + kTile); ++y) fn(x0, std::min(rect.w, x0 + kTile), y);
      },
      threads_);
}

void CpuRenderer::for_rows(const PixelRect& rect, const std::function<void(int, int, int)>& fn) const {
  for_each_row(rect, fn);
}

void CpuRenderer::cast_rows(const CpuFrame& f, const PixelRect& rect, bool rgb8, bool read_samples,
                            const glm::vec3& background, RenderResult& res, std::vector<float>& samples) const {
  for_each_row(rect, [&](int x0, int x1, int y) {
    float px[kTile], py[kTile];
    RayResult rays[kTile];
    for (int x = x0; x < x1; ++x) {
      px[x - x0] = float(rect.x + x) + 0.5f;
      py[x - x0] = float(rect.y + y) + 0.5f;
    }
    if (packets_) {
      cast_rays(f, px, py, x1 - x0, rays);
    } else {
      for (int q = 0; q < x1 - x0; ++q) rays[q] = cast_ray(f, px[q], py[q]);
    }
    for (int x = x0; x < x1; ++x) {
      const RayResult& r = rays[x - x0];
      const size_t p = size_t(y) * size_t(rect.w) + size_t(x);
      const glm::vec3 c = finish_pixel(r.acc, background);
      if (rgb8) {
        for (int k = 0; k < 3; ++k) res.rgb8.rgb[p * 3 + k] = quantise(c[k]);
      } else {
        float* out = &res.image.rgba[p * 4];
        out[0] = c.r;
        out[1] = c.g;
        out[2] = c.b;
        out[3] = r.acc.a;
      }
      if (read_samples) samples[p] = r.samples;
    }
  });
}

RenderResult CpuRenderer::render(const render::ResidentVolume& v, const ResolvedScene& s,
                                 const render::RenderRequest& req, RenderStats* stats) {
  const CpuVolume& cv = cpu_volume(v);
  const PixelRect rect = req.tile.value_or(PixelRect{0, 0, s.scene.width, s.scene.height});
  render::check_rect(rect, s.scene.width, s.scene.height);
  if (stats) *stats = RenderStats::for_scene(s);
  CpuFrame f = prepare(cv, s, req.path, rect, nullptr, stats);
  const bool rgb8 = req.output == render::RenderOutput::Rgb8;
  f.key.rgb8 = rgb8;
  const bool read_samples = !rgb8 || req.sample_stats;
  const glm::vec3 background(s.scene.background);

  RenderResult res;
  res.rect = rect;
  std::vector<float> samples(read_samples ? size_t(rect.w) * size_t(rect.h) : 0);
  if (rgb8)
    res.rgb8 = render::Rgb8Image(rect.w, rect.h);
  else
    res.image = Image(rect.w, rect.h);
  const auto t0 = Clock::now();
  const bool empty_frame = f.nothing_visible && rgb8 && !read_samples;
  if (empty_frame) {  // a frame with nothing to draw costs nothing
    uint8_t bg[3];
    for (int k = 0; k < 3; ++k) bg[k] = quantise(background[k]);
    for (size_t p = 0; p < size_t(rect.w) * size_t(rect.h); ++p) std::copy(bg, bg + 3, &res.rgb8.rgb[p * 3]);
  } else {
    cast_rows(f, rect, rgb8, read_samples, background, res, samples);
  }
  const double render_ms = ms_since(t0);
  if (!rgb8) res.image.samples = samples;
  if (stats) {
    stats->render_ms = render_ms;
    stats->variant = f.key.name() + (empty_frame ? "+nothing-visible" : "");
    stats->has_samples = read_samples;
    stats->sample_cap = f.u.sample_cap;
    if (read_samples) {
      for (float n : samples) {
        if (n < 0) continue;  // missed the box
        stats->samples_total += n;
        stats->samples_max = std::max<double>(stats->samples_max, n);
        stats->rays_hit++;
        if (n >= float(f.u.sample_cap)) stats->rays_at_cap++;
      }
      stats->samples_mean = stats->rays_hit ? stats->samples_total / double(stats->rays_hit) : 0.0;
    }
  }
  return res;
}

Image CpuRenderer::render_brick(const render::ResidentVolume& v, const ResolvedScene& s, const Brick& brick,
                                RenderStats* stats, std::optional<PixelRect> tile) {
  const CpuVolume& cv = cpu_volume(v);
  const glm::dvec3 spacing = cv.volume().spacing;
  const PixelRect rect = render::check_brick_frame(s, brick, spacing, tile);
  const int w = rect.w, h = rect.h;
  if (stats) *stats = RenderStats::for_scene(s);
  CpuFrame f = prepare(cv, s, render::RenderPath::Fragment, rect, &brick, stats);  // stop 1: until opaque
  if (brick.front_opacity && f.ray_texture) f.front_opacity = brick.front_opacity->data();
  Image img(w, h);
  const auto t0 = Clock::now();
  for_each_row(rect, [&](int x0, int x1, int y) {
    float px[kTile] = {}, py[kTile] = {};
    RayResult rays[kTile];
    for (int x = x0; x < x1; ++x) {
      px[x - x0] = float(rect.x + x) + 0.5f;
      py[x - x0] = float(rect.y + y) + 0.5f;
    }
    cast_rays(f, px, py, x1 - x0, rays);
    for (int x = x0; x < x1; ++x) {
      const RayResult& ray = rays[x - x0];
      const size_t p = size_t(y) * size_t(w) + size_t(x);
      for (int k = 0; k < 4; ++k) img.rgba[p * 4 + k] = ray.acc[k];
      img.samples[p] = ray.samples;
    }
  });
  if (stats) {
    stats->render_ms = ms_since(t0);
    stats->variant = f.key.name() + "+brick";
    stats->has_samples = true;
    stats->sample_cap = f.u.sample_cap;
    for (float n : img.samples) {
      if (n < 0) continue;  // owns no point of this ray
      stats->samples_total += n;
      stats->samples_max = std::max<double>(stats->samples_max, n);
      stats->rays_hit++;
    }
    stats->samples_mean = stats->rays_hit ? stats->samples_total / double(stats->rays_hit) : 0.0;
  }
  return img;
}

}  // namespace peakcast::cpu
