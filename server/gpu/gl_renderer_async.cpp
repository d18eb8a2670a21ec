// The stream's frames on GL without stalls: each frame is drawn, then read back into a
// pixel-buffer object of a small ring with a fence after it, and the render thread goes on to
// draw the next frame; collect() waits on the oldest fence and copies the mapped buffer out.
// On a GPU the read-back of frame N (and its encode, on the encode pool) overlaps the draw of
// frame N + 1; on llvmpipe, which draws on the CPU, little overlaps but nothing is lost.
#include <cstring>
#include <stdexcept>

#include "gpu/gl_renderer.h"
#include "render/shader_interface.h"
#include "gpu/table_cache.h"

namespace peakcast::gpu {

using namespace render;  // the renderer interface and frame setup this implements

void GlRenderer::submit(const ResidentVolume& v, const ResolvedScene& s, const RenderRequest& req) {
  check_submit(req, ring_count_);
  const auto* gv = dynamic_cast<const GlVolume*>(&v);
  if (!gv) throw std::invalid_argument("the GL renderer draws GPU volumes only (this one was made by another backend)");
  if (ring_.size() < kFramesInFlight) ring_.resize(kFramesInFlight);
  InFlight& f = ring_[(ring_head_ + ring_count_) % ring_.size()];
  const PixelRect rect{0, 0, s.scene.width, s.scene.height};
  check_rect(rect, s.scene.width, s.scene.height);
  f.stats = RenderStats::for_scene(s);
  VariantKey key = prepare(*gv, s, req.path, &f.stats);
  key.rgb8 = true;
  f.w = rect.w;
  f.h = rect.h;
  f.cap = sample_cap(key);
  f.samples = req.sample_stats;
  f.stats.variant = key.name();
  f.stats.sample_cap = f.cap;
  Targets& t = setup_draw(*gv, s, key, rect, nullptr, &f.stats);
  if (!f.timer.begin) f.timer = gpu::GpuTimer::make();
  f.issued = Clock::now();
  dispatch(key, t, f.samples, f.timer);

  // Read-back into the slot's buffer: RGB rows first, then the sample counts (4-byte aligned).
  const size_t rgb = size_t(f.w) * f.h * 3, rgb_padded = (rgb + 3) / 4 * 4;
  const size_t bytes = rgb_padded + (f.samples ? size_t(f.w) * f.h * 4 : 0);
  if (!f.pbo || f.bytes < bytes) {
    f.pbo = gpu::make_buffer();
    glNamedBufferStorage(f.pbo.id(), GLsizeiptr(bytes), nullptr, GL_MAP_READ_BIT | GL_CLIENT_STORAGE_BIT);
    f.bytes = bytes;
  }
  glBindBuffer(GL_PIXEL_PACK_BUFFER, f.pbo.id());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTextureImage(t.color.id(), 0, GL_RGB_INTEGER, GL_UNSIGNED_BYTE, GLsizei(rgb), nullptr);
  if (f.samples) {
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    glGetTextureImage(t.samples.id(), 0, GL_RED, GL_FLOAT, GLsizei(size_t(f.w) * f.h * 4),
                      reinterpret_cast<void*>(rgb_padded));
  }
  glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
  f.fence = gpu::fence_now();
  gpu::check_gl("asynchronous frame");
  ++ring_count_;
}

RenderResult GlRenderer::collect(RenderStats* stats) {
  if (ring_count_ == 0) throw std::logic_error("collect: no frame was submitted");
  InFlight& f = ring_[ring_head_];
  ring_head_ = (ring_head_ + 1) % ring_.size();
  --ring_count_;
  const auto t_wait = Clock::now();
  while (glClientWaitSync(f.fence.get(), GL_SYNC_FLUSH_COMMANDS_BIT, 1'000'000'000) == GL_TIMEOUT_EXPIRED) {
  }
  f.fence.reset();
  // The draw's own time on the GPU is the frame's render time (what the frame budget models).
  f.stats.gpu_ms = f.timer.elapsed_ms();
  f.stats.render_ms = f.stats.gpu_ms;
  RenderResult res;
  res.rect = PixelRect{0, 0, f.w, f.h};
  res.rgb8 = Rgb8Image(f.w, f.h);
  const size_t rgb = res.rgb8.rgb.size(), rgb_padded = (rgb + 3) / 4 * 4;
  const size_t bytes = rgb_padded + (f.samples ? size_t(f.w) * f.h * 4 : 0);
  const auto* mapped =
      static_cast<const uint8_t*>(glMapNamedBufferRange(f.pbo.id(), 0, GLsizeiptr(bytes), GL_MAP_READ_BIT));
  if (!mapped) throw std::runtime_error("collect: the frame's pixel buffer could not be mapped");
  std::memcpy(res.rgb8.rgb.data(), mapped, rgb);
  if (f.samples) {
    std::vector<float> samples(size_t(f.w) * f.h);
    std::memcpy(samples.data(), mapped + rgb_padded, samples.size() * 4);
    count_samples(samples, f.cap, f.stats);
  }
  glUnmapNamedBuffer(f.pbo.id());
  f.stats.readback_ms = ms_since(t_wait);  // what the render thread waited for the pixels, and copied
  if (stats) *stats = std::move(f.stats);
  return res;
}

}  // namespace peakcast::gpu
