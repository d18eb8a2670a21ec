#include "gpu/gl_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "core/occupancy.h"
#include "core/preintegration.h"
#include "render/ray_uniforms.h"
#include "render/shader_interface.h"
#include "gpu/table_cache.h"

namespace peakcast::gpu {

using namespace render;  // the renderer interface and frame setup this implements

GlRenderer::GlRenderer(gpu::ShaderCache& shaders) : shaders_(shaders) {
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  llvmpipe_ = renderer && std::string(renderer).find("llvmpipe") != std::string::npos;
  ubo_ = gpu::make_buffer();
  front_opacity_ = gpu::make_buffer();
  timer_ = gpu::GpuTimer::make();
  glNamedBufferStorage(ubo_.id(), sizeof(ray::RayUniforms), nullptr, GL_DYNAMIC_STORAGE_BIT);
  vao_ = gpu::make_vertex_array();
}

std::string GlRenderer::description() const {
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  return std::string("OpenGL: ") + (renderer ? renderer : "unknown");
}

std::unique_ptr<ResidentVolume> GlRenderer::make_resident(std::shared_ptr<const Volume> volume,
                                                          VolumeMacrocells cells) {
  return std::make_unique<GlVolume>(std::move(volume), std::move(cells));
}

namespace {
const GlVolume& gpu_volume(const ResidentVolume& v) {
  const auto* gv = dynamic_cast<const GlVolume*>(&v);
  if (!gv) throw std::invalid_argument("the GL renderer draws GPU volumes only (this one was made by another backend)");
  return *gv;
}
}  // namespace

int GlRenderer::sample_cap(const VariantKey& key) const {
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

const gpu::Program& GlRenderer::program(const VariantKey& key) {
  if (key.path == RenderPath::Compute) return shaders_.get(key.name(), {"raycast.comp"}, key.defines());
  return shaders_.get(key.name(), {"fullscreen.vert", "raycast.frag"}, key.defines());
}

void GlRenderer::prefetch_variants() {
  // Around the last frame's variant: the other classifications, shading toggled, and the float
  // output of stills; built on the shader cache's thread, most likely first.
  std::vector<VariantKey> next;
  VariantKey k = last_key_;
  auto with = [&](auto change) {
    VariantKey v = k;
    change(v);
    next.push_back(v);
  };
  if (!k.projection) with([](VariantKey& v) { v.shading = !v.shading; });  // (a projection is never shaded)
  with([](VariantKey& v) { v.peaks = false, v.preintegration = false, v.projection = 0; });
  with([](VariantKey& v) { v.peaks = false, v.preintegration = true, v.projection = 0; });
  with([](VariantKey& v) { v.peaks = true, v.preintegration = false, v.projection = 0; });
  with([](VariantKey& v) { v.rgb8 = !v.rgb8; });
  for (const VariantKey& v : next) {
    if (v.path == RenderPath::Compute)
      shaders_.prefetch(v.name(), {"raycast.comp"}, v.defines());
    else
      shaders_.prefetch(v.name(), {"fullscreen.vert", "raycast.frag"}, v.defines());
  }
}

GlRenderer::Targets& GlRenderer::targets(int w, int h, RenderOutput output) {
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

RenderResult GlRenderer::render(const ResidentVolume& v, const ResolvedScene& s, const RenderRequest& req,
                                RenderStats* stats) {
  const GlVolume& gv = gpu_volume(v);
  const PixelRect rect = req.tile.value_or(PixelRect{0, 0, s.scene.width, s.scene.height});
  check_rect(rect, s.scene.width, s.scene.height);
  if (stats) *stats = RenderStats::for_scene(s);
  VariantKey key = prepare(gv, s, req.path, stats);
  key.rgb8 = req.output == RenderOutput::Rgb8;
  return draw(gv, s, key, rect, req.output == RenderOutput::Float || req.sample_stats, stats);
}

Image GlRenderer::render_brick(const ResidentVolume& v, const ResolvedScene& s, const Brick& brick, RenderStats* stats,
                               std::optional<PixelRect> tile) {
  const GlVolume& gv = gpu_volume(v);
  const PixelRect rect = check_brick_frame(s, brick, gv.volume().spacing, tile);
  if (stats) *stats = RenderStats::for_scene(s);
  VariantKey key = prepare(gv, s, RenderPath::Fragment, stats);
  key.brick = true;
  key.rgb8 = false;
  return std::move(draw(gv, s, key, rect, true, stats, &brick).image);
}

// The TF table for the scene's step (render/frame_setup.h), linearly filtered like a texture.
void GlRenderer::bind_tf_table(const GlVolume& gv, const ResolvedScene& s, const std::string& tf_sig) {
  const std::string sig = step_tf_key(s, tf_sig);
  TfTable* tf_table = cache_find(tf_tables_, sig);
  if (!tf_table) {
    TfTable e{sig, gpu::make_texture(GL_TEXTURE_1D)};
    glTextureStorage1D(e.texture.id(), 1, GL_RGBA32F, TransferFunction::kTableSize);
    glTextureParameteri(e.texture.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTextureParameteri(e.texture.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTextureParameteri(e.texture.id(), GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    const std::vector<float> table = step_tf_table(s, gv.tf_lo(), gv.tf_hi());
    glTextureSubImage1D(e.texture.id(), 0, 0, TransferFunction::kTableSize, GL_RGBA, GL_FLOAT, table.data());
    tf_table = &cache_insert(tf_tables_, std::move(e), kCacheEntries);
    ++table_builds_;
  }
  glBindTextureUnit(kUnitTf, tf_table->texture.id());
}

VariantKey GlRenderer::prepare(const GlVolume& gv, const ResolvedScene& s, RenderPath path, RenderStats* stats) {
  const MacrocellGrid& cells = gv.macrocells(s.scene.render.filter);
  const FrameSetup f = setup_frame(gv, s, path, setup_options_, occupancy_cache_, table_builds_);
  const auto t_tables = Clock::now();
  bind_tf_table(gv, s, f.tf_sig);
  upload_tables(gv, s, f.key.peaks ? f.peaks : std::vector<Peak>{});
  const double table_ms = f.table_ms + ms_since(t_tables);
  if (f.key.space_skipping) {
    DistanceEntry* e = cache_find(distance_cache_, f.occupancy_key);
    if (!e) {
      e = &cache_insert(distance_cache_,
                        DistanceEntry{f.occupancy_key,
                                      make_cell_buffer(cells, traversal_distances(*f.occupancy, setup_options_.leaps))},
                        kCacheEntries);
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboCellDistance, e->buffer.id());
  }
  if (f.key.adaptive) bind_multipliers(gv, cells);
  if (f.key.projection_skips()) bind_cell_ranges(gv, cells);
  if (f.key.ray_texture) bind_ray_texture(s, stats);
  if (stats) {
    stats->empty_cells = f.occupancy->empty_cells;
    stats->peaks = f.peaks.size();
    stats->table_ms = table_ms;
  }
  return f.key;
}

GlRenderer::Targets& GlRenderer::setup_draw(const GlVolume& gv, const ResolvedScene& s, const VariantKey& key,
                                            const PixelRect& rect, const Brick* brick, RenderStats* stats) {
  const MacrocellGrid& cells = gv.macrocells(s.scene.render.filter);
  const auto t_program = Clock::now();
  const bool was_ready = shaders_.ready(key.name());
  const gpu::Program& prog = program(key);
  if (stats && !was_ready) stats->compile_ms = ms_since(t_program);  // built, loaded or waited for
  last_key_ = key;
  const TableShape shape{tables_.peak_bins, tables_.peak_layers, tables_.preint_size, tables_.tf_points};
  const ray::RayUniforms u = make_ray_uniforms(s, gv.volume(), ValueMap{gv.value_scale(), gv.value_bias()}, cells,
                                               shape, rect, sample_cap(key), brick);
  glNamedBufferSubData(ubo_.id(), 0, sizeof u, &u);
  glBindBufferBase(GL_UNIFORM_BUFFER, kUboRay, ubo_.id());
  gv.bind(kUnitVolume);  // the TF table and the other per-TF tables were bound by prepare()
  if (brick && brick->front_opacity) {
    const std::vector<float>& front = *brick->front_opacity;
    glNamedBufferData(front_opacity_.id(), GLsizeiptr(front.size() * sizeof(float)), front.data(), GL_STREAM_DRAW);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, kSsboFrontOpacity, front_opacity_.id());
  }
  Targets& t = targets(rect.w, rect.h, key.rgb8 ? RenderOutput::Rgb8 : RenderOutput::Float);
  glUseProgram(prog.id());
  return t;
}

void GlRenderer::dispatch(const VariantKey& key, Targets& t, bool read_samples, const gpu::GpuTimer& timer) {
  timer.start();
  if (key.path == RenderPath::Compute) {
    glBindImageTexture(kImageColor, t.color.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, key.rgb8 ? GL_RGBA8UI : GL_RGBA32F);
    glBindImageTexture(kImageSamples, t.samples.id(), 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glDispatchCompute(GLuint((t.w + 7) / 8), GLuint((t.h + 7) / 8), 1);
    glMemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT | GL_PIXEL_BUFFER_BARRIER_BIT);
  } else {
    // Sample counts nobody reads are not written (draw buffer NONE drops them).
    const GLenum bufs[] = {GL_COLOR_ATTACHMENT0, read_samples ? GLenum(GL_COLOR_ATTACHMENT1) : GLenum(GL_NONE)};
    glNamedFramebufferDrawBuffers(t.fbo.id(), 2, bufs);
    glBindFramebuffer(GL_FRAMEBUFFER, t.fbo.id());
    glViewport(0, 0, t.w, t.h);
    glDisable(GL_BLEND);
    glDisable(GL_DEPTH_TEST);
    glBindVertexArray(vao_.id());
    glDrawArrays(GL_TRIANGLES, 0, 3);
  }
  timer.stop();
}

RenderResult GlRenderer::draw(const GlVolume& gv, const ResolvedScene& s, const VariantKey& key, const PixelRect& rect,
                              bool read_samples, RenderStats* stats, const Brick* brick) {
  const int w = rect.w, h = rect.h;
  const RenderOutput output = key.rgb8 ? RenderOutput::Rgb8 : RenderOutput::Float;
  const int cap = sample_cap(key);
  Targets& t = setup_draw(gv, s, key, rect, brick, stats);
  glFinish();  // render_ms is the draw's alone, not the uploads queued before it
  const auto t0 = Clock::now();
  dispatch(key, t, read_samples, timer_);
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
    stats->gpu_ms = timer_.elapsed_ms();
    stats->readback_ms = ms_since(t1);
    stats->variant = key.name();
    if (read_samples) count_samples(output == RenderOutput::Float ? res.image.samples : samples, cap, *stats);
    stats->sample_cap = cap;
  }
  return res;
}

void count_samples(const std::vector<float>& samples, int cap, RenderStats& stats) {
  stats.has_samples = true;
  for (float n : samples) {
    if (n < 0) continue;  // missed the box
    stats.samples_total += n;
    stats.samples_max = std::max<double>(stats.samples_max, n);
    stats.rays_hit++;
    if (n >= float(cap)) stats.rays_at_cap++;
  }
  stats.samples_mean = stats.rays_hit ? stats.samples_total / double(stats.rays_hit) : 0.0;
}

}  // namespace peakcast::gpu
