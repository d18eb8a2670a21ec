#include "render/raycaster.h"

#include <algorithm>
#include <chrono>
#include <sstream>

#include "core/occupancy.h"
#include "core/preintegration.h"
#include "render/gpu_layout.h"
#include "render/shader_interface.h"

namespace peakcast::render {
namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

// Everything a per-TF table depends on: the points, the opacity unit and the value range.
std::string tf_signature(const TransferFunction& tf, double lo, double hi) {
  std::ostringstream s;
  s.precision(17);
  s << lo << ' ' << hi << ' ' << tf.opacity_unit;
  for (const auto& p : tf.points) s << ' ' << p.value << ' ' << p.r << ' ' << p.g << ' ' << p.b << ' ' << p.a;
  return s.str();
}

RayUniforms make_uniforms(const GpuVolume& gv, const ResolvedScene& s, const MacrocellGrid& cells,
                          const RayTables& t, const PixelRect& rect, int sample_cap) {
  const SamplingPlan plan = plan_sampling(s);
  const Volume& v = gv.volume();
  const glm::dvec3 center = (s.box_min + s.box_max) * 0.5;
  const ViewSetup view = setup_view(s.camera, center, s.scene.width, s.scene.height);
  RayUniforms u{};
  u.p0 = glm::vec4(glm::vec3(view.p0), 0.f);
  u.right = glm::vec4(glm::vec3(view.right), float(view.half_w));
  u.up = glm::vec4(glm::vec3(view.up), float(view.half_h));
  u.forward = glm::vec4(glm::vec3(view.forward), float(view.dist));
  u.box_half = glm::vec4(glm::vec3((s.box_max - s.box_min) * 0.5), float(plan.step));
  u.spacing = glm::vec4(glm::vec3(v.spacing), float(s.tf.opacity_unit));
  u.dims = glm::vec4(float(v.dims()[0]), float(v.dims()[1]), float(v.dims()[2]), float(s.scene.render.early_termination));
  u.value_map = glm::vec4(gv.value_scale(), gv.value_bias(), float(TransferFunction::kTableSize), float(sample_cap));
  u.background = glm::vec4(glm::vec3(s.scene.background), 1.f);
  u.cells = glm::vec4(float(cells.grid[0]), float(cells.grid[1]), float(cells.grid[2]), float(cells.cell));
  u.image = glm::ivec4(s.scene.width, s.scene.height, rect.x, rect.y);
  u.peaks = glm::vec4(float(t.peak_bins), float(t.peak_layers), float(t.max_peaks), float(t.secant_iterations));
  u.tables = glm::vec4(float(t.preint_size), float(t.tf_points), float(plan.k), float(plan.min_step));
  return u;
}

// One byte per macrocell (occupancy, adaptive multiplier) as an R8UI 3D texture in grid order.
gpu::Texture make_cell_texture(const MacrocellGrid& cells, const std::vector<uint8_t>& bytes) {
  gpu::Texture tex = gpu::make_texture(GL_TEXTURE_3D);
  glTextureStorage3D(tex.id(), 1, GL_R8UI, GLsizei(cells.grid[0]), GLsizei(cells.grid[1]), GLsizei(cells.grid[2]));
  // Integer textures are complete only with NEAREST filtering.
  glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glTextureSubImage3D(tex.id(), 0, 0, 0, 0, GLsizei(cells.grid[0]), GLsizei(cells.grid[1]), GLsizei(cells.grid[2]),
                      GL_RED_INTEGER, GL_UNSIGNED_BYTE, bytes.data());
  return tex;
}

// Moves the entry named `key` to the front of a most-recent-first cache; nullptr when absent.
template <class T>
T* cache_find(std::vector<T>& cache, const std::string& key) {
  auto it = std::find_if(cache.begin(), cache.end(), [&](const T& e) { return e.key == key; });
  if (it == cache.end()) return nullptr;
  std::rotate(cache.begin(), it, it + 1);
  return &cache.front();
}

// Puts `e` at the front, dropping the least recently used entry beyond `cap`.
template <class T>
T& cache_insert(std::vector<T>& cache, T e, size_t cap) {
  if (cache.size() >= cap) cache.pop_back();
  cache.insert(cache.begin(), std::move(e));
  return cache.front();
}

}  // namespace

Raycaster::Raycaster(gpu::ShaderCache& shaders) : shaders_(shaders) {
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  llvmpipe_ = renderer && std::string(renderer).find("llvmpipe") != std::string::npos;
  ubo_ = gpu::make_buffer();
  glNamedBufferStorage(ubo_.id(), sizeof(RayUniforms), nullptr, GL_DYNAMIC_STORAGE_BIT);
  vao_ = gpu::make_vertex_array();
}

int Raycaster::sample_cap(const VariantKey& key) const {
  if (!llvmpipe_) return kMaxSamplesPerRay;
  // llvmpipe ends a shader invocation's loops after 65535 iterations in all, shared by every
  // loop (gallivm's LP_MAX_TGSI_LOOP_ITERATIONS): leave room for the macrocell walk and the
  // chunking loops, and count each sample's inner loops. Measured per true sample (1199-voxel
  // ray, 1e-3 step): 1 plain, preintegrated, tricubic or shaded; 6 with 3 virtual samples, 10
  // with 7; 9 with peak finding per composited sample; 94 with both (peaks, 7): budgeted
  // here as vs + 3 and 12 per composited sample.
  const int vs = key.virtual_samples;
  const int per_sample = (vs ? vs + 3 : 1) + (key.peaks ? 12 * (1 + vs) : 0);
  return kLlvmpipeLoopBudget / per_sample;
}

const gpu::Program& Raycaster::program(const VariantKey& key) {
  if (key.path == GpuPath::Compute) return shaders_.get(key.name(), {"raycast.comp"}, key.defines());
  return shaders_.get(key.name(), {"fullscreen.vert", "raycast.frag"}, key.defines());
}

Raycaster::Targets& Raycaster::targets(int w, int h, RenderOutput output) {
  auto it = std::find_if(targets_.begin(), targets_.end(),
                         [&](const Targets& t) { return t.w == w && t.h == h && t.output == output; });
  if (it == targets_.end()) {
    Targets t;
    t.w = w;
    t.h = h;
    t.output = output;
    t.color = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(t.color.id(), 1, output == RenderOutput::Rgb8 ? GL_RGBA8UI : GL_RGBA32F, w, h);
    t.samples = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(t.samples.id(), 1, GL_R32F, w, h);
    t.fbo = gpu::make_framebuffer();
    glNamedFramebufferTexture(t.fbo.id(), GL_COLOR_ATTACHMENT0, t.color.id(), 0);
    glNamedFramebufferTexture(t.fbo.id(), GL_COLOR_ATTACHMENT1, t.samples.id(), 0);
    if (glCheckNamedFramebufferStatus(t.fbo.id(), GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      throw std::runtime_error("render target incomplete");
    gpu::check_gl("render targets");
    if (targets_.size() >= 3) targets_.pop_back();  // a stream size, a tile size, one spare
    targets_.insert(targets_.begin(), std::move(t));
    return targets_.front();
  }
  std::rotate(targets_.begin(), it, it + 1);
  return targets_.front();
}

Image Raycaster::render(const GpuVolume& gv, const ResolvedScene& s, GpuPath path, RenderStats* stats) {
  RenderRequest req;
  req.path = path;
  return std::move(render(gv, s, req, stats).image);
}

RenderResult Raycaster::render(const GpuVolume& gv, const ResolvedScene& s, const RenderRequest& req,
                               RenderStats* stats) {
  const PixelRect rect = req.tile.value_or(PixelRect{0, 0, s.scene.width, s.scene.height});
  check_rect(rect, s.scene.width, s.scene.height);
  if (stats) *stats = RenderStats{};
  VariantKey key = prepare(gv, s, req.path, stats);
  key.rgb8 = req.output == RenderOutput::Rgb8;
  return draw(gv, s, key, rect, req.output == RenderOutput::Float || req.sample_stats, stats);
}

VariantKey Raycaster::prepare(const GpuVolume& gv, const ResolvedScene& s, GpuPath path, RenderStats* stats) {
  const MacrocellGrid& cells = gv.macrocells(s.scene.render.filter);

  // Per-frame state that depends on the TF: table and macrocell occupancy.
  const std::string tf_sig = tf_signature(s.tf, gv.tf_lo(), gv.tf_hi());
  TfTable* tf_table = cache_find(tf_tables_, tf_sig);
  if (!tf_table) {
    TfTable e{tf_sig, gpu::make_texture(GL_TEXTURE_1D)};
    glTextureStorage1D(e.texture.id(), 1, GL_RGBA32F, TransferFunction::kTableSize);
    glTextureParameteri(e.texture.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(e.texture.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(e.texture.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    const std::vector<float> table = s.tf.bake(TransferFunction::kTableSize, gv.tf_lo(), gv.tf_hi());
    glTextureSubImage1D(e.texture.id(), 0, 0, TransferFunction::kTableSize, GL_RGBA, GL_FLOAT, table.data());
    tf_table = &cache_insert(tf_tables_, std::move(e), kCacheEntries);
    ++table_builds_;
  }
  glBindTextureUnit(kUnitTf, tf_table->texture.id());
  const auto t_tables = Clock::now();
  const std::vector<Peak> peaks =
      s.scene.render.classification == Classification::Peaks ? find_peaks(s.tf) : std::vector<Peak>{};
  std::vector<double> peak_values;
  for (const auto& p : peaks) peak_values.push_back(p.value);
  // Occupancy depends on the grid, the TF over the value range and the peaks: a camera move
  // reuses it (and its texture).
  Occupancy no_skipping;
  const Occupancy* occ = &no_skipping;
  OccupancyEntry* occ_entry = nullptr;
  // A virtual sample reads a Catmull-Rom window two steps either side: its cell's range is the
  // union over the cells that window can reach (ring), widened by Lee's (M - m)/8 (eq. 8), the
  // most the spline overshoots its samples. Windows reaching too far sample without skipping.
  const bool vs = s.scene.render.virtual_samples != 0;
  const int ring = vs ? virtual_sample_ring(plan_sampling(s), s, cells.cell) : 0;
  if (s.scene.render.space_skipping && ring >= 0) {
    const double overshoot = vs ? vs_widening_ : 0.0;
    const int reach = vs && vs_widening_ > 0.0 ? ring : 0;  // widening 0 (a test's): neither
    const std::string occ_key = tf_sig + " cells " + std::to_string(gv.serial()) + " " + cells.to_string() +
                                " peaks " + std::to_string(peaks.size()) + " overshoot " + std::to_string(overshoot) +
                                " ring " + std::to_string(reach);
    occ_entry = cache_find(occupancy_cache_, occ_key);
    if (!occ_entry) {
      occ_entry = &cache_insert(
          occupancy_cache_,
          OccupancyEntry{occ_key,
                         classify_cells(reach ? dilate_ranges(cells, reach) : cells, s.tf, gv.tf_lo(), gv.tf_hi(),
                                        peak_values, TransferFunction::kTableSize, overshoot),
                         {}},
          kCacheEntries);
      ++table_builds_;
    }
    occ = &occ_entry->occupancy;
  }
  const VariantKey key = choose_variant(s, occ->empty_cells, path, peaks.size());
  upload_tables(gv, s, key.peaks ? peaks : std::vector<Peak>{});
  const double table_ms = ms_since(t_tables);
  if (key.space_skipping) {
    gpu::Texture& tex = occ_entry->texture;
    if (!tex) tex = make_cell_texture(cells, occ->occupied);
    glBindTextureUnit(kUnitOccupancy, tex.id());
  }
  if (key.adaptive) bind_multipliers(gv, cells);
  if (key.ray_texture) bind_ray_texture(s);
  if (stats) {
    stats->empty_cells = occ->empty_cells;
    stats->peaks = peaks.size();
    stats->table_ms = table_ms;
  }
  return key;
}

// The ray texture as an RGB32F texture read with linear filtering between texel centres,
// clamped at the edges (what sample_ray_texture does on the CPU); uploaded once per content.
void Raycaster::bind_ray_texture(const ResolvedScene& s) {
  const std::string key = s.scene.render.ray_texture.dump() + " termination " +
                          std::to_string(s.scene.render.early_termination);
  RayTextureEntry* e = cache_find(ray_texture_cache_, key);
  if (!e) {
    const RayTexture& rt = *s.ray_texture;
    gpu::Texture tex = gpu::make_texture(GL_TEXTURE_2D);
    glTextureStorage2D(tex.id(), 1, GL_RGB32F, rt.width(), rt.height());
    glTextureParameteri(tex.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(tex.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(tex.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTextureParameteri(tex.id(), GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
    glTextureSubImage2D(tex.id(), 0, 0, 0, rt.width(), rt.height(), GL_RGB, GL_FLOAT, rt.texels().data());
    e = &cache_insert(ray_texture_cache_, RayTextureEntry{key, std::move(tex)}, kCacheEntries);
  }
  glBindTextureUnit(kUnitRayTexture, e->texture.id());
}

// The adaptive multipliers of a volume's grid: data only (no TF), so built once per grid.
void Raycaster::bind_multipliers(const GpuVolume& gv, const MacrocellGrid& cells) {
  const std::string key = std::to_string(gv.serial()) + " " + cells.to_string();
  StrideEntry* e = cache_find(stride_cache_, key);
  if (!e) {
    StrideEntry n{key, make_cell_texture(cells, adaptive_multipliers(cells, volume_stddev(gv.volume())))};
    e = &cache_insert(stride_cache_, std::move(n), kCacheEntries);
    ++table_builds_;
  }
  glBindTextureUnit(kUnitStride, e->texture.id());
}

void Raycaster::upload_tables(const GpuVolume& gv, const ResolvedScene& s, const std::vector<Peak>& peaks) {
  const RenderSettings& r = s.scene.render;
  const double lo = gv.tf_lo(), hi = gv.tf_hi();
  const double preint_step = plan_sampling(s).step;  // segments the table is built for
  // The tables depend on the TF, the value range, the method's sizes and (preintegration) the
  // step: a frame that changes none of them (a camera move) reuses what is bound.
  std::ostringstream key;
  key.precision(17);
  key << tf_signature(s.tf, lo, hi) << ' ' << to_string(r.classification) << ' ' << r.peak_table_bins << ' '
      << r.max_peaks << ' ' << r.secant_iterations << ' ' << r.preint_table_size << ' ' << r.preint_method << ' '
      << peaks.size() << ' '
      << (r.classification == Classification::Preint ? preint_step : 0.0);
  if (const Tables* t = cache_find(tables_cache_, key.str())) {
    if (t->peak_table) glBindTextureUnit(kUnitPeakTable, t->peak_table.id());
    if (t->tf_points) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboTfPoints, t->tf_points.id());
    if (t->preint_table) glBindTextureUnit(kUnitPreint, t->preint_table.id());
    tables_ = t->sizes;
    return;
  }
  Tables t;
  t.key = key.str();
  if (r.classification == Classification::Peaks) {
    const PeakTable table = build_peak_table(peaks, lo, hi, r.peak_table_bins);
    std::vector<float> texels(table.texels.size());
    for (size_t k = 0; k < texels.size(); ++k)  // to TF coordinates
      texels[k] = table.texels[k] == PeakTable::kNoPeak ? kNoPeakTexel : float((table.texels[k] - lo) / (hi - lo));
    t.peak_table = gpu::make_texture(GL_TEXTURE_2D_ARRAY);
    glTextureStorage3D(t.peak_table.id(), 1, GL_RGBA32F, table.bins, table.bins, table.layers);
    glTextureSubImage3D(t.peak_table.id(), 0, 0, 0, 0, table.bins, table.bins, table.layers, GL_RGBA, GL_FLOAT,
                        texels.data());
    glTextureParameteri(t.peak_table.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTextureParameteri(t.peak_table.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glBindTextureUnit(kUnitPeakTable, t.peak_table.id());
    std::vector<glm::vec4> points;
    for (const auto& p : s.tf.points) {
      points.emplace_back(float((p.value - lo) / (hi - lo)), 0.f, 0.f, 0.f);
      points.emplace_back(float(p.r), float(p.g), float(p.b), float(p.a));
    }
    t.tf_points = gpu::make_buffer();
    glNamedBufferStorage(t.tf_points.id(), GLsizeiptr(points.size() * sizeof(glm::vec4)), points.data(), 0);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboTfPoints, t.tf_points.id());
    t.sizes.peak_bins = table.bins;
    t.sizes.peak_layers = table.layers;
    t.sizes.max_peaks = r.max_peaks;
    t.sizes.secant_iterations = r.secant_iterations;
    t.sizes.tf_points = int(s.tf.points.size());
    t.sizes.peak_count = peaks.size();
  }
  if (r.classification == Classification::Preint) {
    const PreintegrationTable table = build_preintegration(s.tf, lo, hi, preint_step, r.preint_table_size,
                                                           preint_method(r));
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

Image Raycaster::render_bare(const GpuVolume& gv, const ResolvedScene& s, GpuPath path, const Image& full,
                             RenderStats* stats) {
  const int w = s.scene.width, h = s.scene.height;
  if (full.width != w || full.height != h) throw std::invalid_argument("render_bare: image size differs");
  std::vector<float> budget(full.samples.size());  // rows top-down, like the render targets
  for (size_t p = 0; p < budget.size(); ++p) budget[p] = std::max(0.f, full.samples[p]);
  budget_texture_ = gpu::make_texture(GL_TEXTURE_2D);
  glTextureStorage2D(budget_texture_.id(), 1, GL_R32F, w, h);
  glTextureSubImage2D(budget_texture_.id(), 0, 0, 0, w, h, GL_RED, GL_FLOAT, budget.data());
  glTextureParameteri(budget_texture_.id(), GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTextureParameteri(budget_texture_.id(), GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glBindTextureUnit(kUnitBudget, budget_texture_.id());
  VariantKey key = choose_variant(s, 0, path);
  key.shading = false;
  key.bare_sampling = true;
  if (stats) *stats = RenderStats{};
  return std::move(draw(gv, s, key, PixelRect{0, 0, w, h}, true, stats).image);
}

RenderResult Raycaster::draw(const GpuVolume& gv, const ResolvedScene& s, const VariantKey& key,
                           const PixelRect& rect, bool read_samples, RenderStats* stats) {
  const int w = rect.w, h = rect.h;
  const MacrocellGrid& cells = gv.macrocells(s.scene.render.filter);
  const GpuPath path = key.path;
  const RenderOutput output = key.rgb8 ? RenderOutput::Rgb8 : RenderOutput::Float;
  const gpu::Program& prog = program(key);
  const int cap = sample_cap(key);
  const RayUniforms u = make_uniforms(gv, s, cells, tables_, rect, cap);
  glNamedBufferSubData(ubo_.id(), 0, sizeof u, &u);
  glBindBufferBase(GL_UNIFORM_BUFFER, kUboRay, ubo_.id());
  gv.bind(kUnitVolume);  // the TF table and the other per-TF tables were bound by prepare()
  Targets& t = targets(w, h, output);
  glUseProgram(prog.id());

  glFinish();
  const auto t0 = Clock::now();
  if (path == GpuPath::Compute) {
    glBindImageTexture(kImageColor, t.color.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, key.rgb8 ? GL_RGBA8UI : GL_RGBA32F);
    glBindImageTexture(kImageSamples, t.samples.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glDispatchCompute(GLuint((w + 7) / 8), GLuint((h + 7) / 8), 1);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT);
  } else {
    // Sample counts nobody reads are not written (draw buffer NONE drops them).
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, read_samples ? GLenum(GL_COLOR_ATTACHMENT1) : GLenum(GL_NONE)};
    glNamedFramebufferDrawBuffers(t.fbo.id(), 2, bufs);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.id());
    glViewport(0, 0, w, h);
    glDisable(GL_BLEND);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(vao_.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  glFinish();
  const double render_ms = ms_since(t0);
  gpu::check_gl("ray cast");

  // The targets hold rows top-down: read straight into the result, no flip.
  const auto t1 = Clock::now();
  RenderResult res;
  res.rect = rect;
  std::vector<float> samples;
  if (output == RenderOutput::Float) {
    res.image = Image(w, h);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(t.color.id(), 0, GL_RGBA, GL_FLOAT, GLsizei(res.image.rgba.size() * 4), res.image.rgba.data());
    glGetTextureImage(t.samples.id(), 0, GL_RED, GL_FLOAT, GLsizei(res.image.samples.size() * 4),
                      res.image.samples.data());
  } else {
    res.rgb8 = Rgb8Image(w, h);
    glPixelStorei(GL_PACK_ALIGNMENT, 1);  // rows of 3 * w bytes, unpadded
    glGetTextureImage(t.color.id(), 0, GL_RGB_INTEGER, GL_UNSIGNED_BYTE, GLsizei(res.rgb8.rgb.size()),
                      res.rgb8.rgb.data());
    if (read_samples) {
      samples.resize(size_t(w) * h);
      glPixelStorei(GL_PACK_ALIGNMENT, 4);
      glGetTextureImage(t.samples.id(), 0, GL_RED, GL_FLOAT, GLsizei(samples.size() * 4), samples.data());
    }
  }
  gpu::check_gl("read-back");
  if (stats) {
    stats->render_ms = render_ms;
    stats->readback_ms = ms_since(t1);
    stats->variant = key.name();
    stats->has_samples = read_samples;
    stats->sample_cap = cap;
    if (read_samples) {
      for (float n : output == RenderOutput::Float ? res.image.samples : samples) {
        if (n < 0) continue;  // missed the box
        stats->samples_total += n;
        stats->samples_max = std::max<double>(stats->samples_max, n);
        stats->rays_hit++;
        if (n >= float(cap)) stats->rays_at_cap++;
      }
      stats->samples_mean = stats->rays_hit ? stats->samples_total / double(stats->rays_hit) : 0.0;
    }
  }
  return res;
}

}  // namespace peakcast::render
