#include "session/render_service.h"

#include <cstdio>
#include <future>

#include "encode/png.h"
#include "gpu/egl_context.h"
#include "gpu/shader_cache.h"
#include "render/raycaster.h"

namespace peakcast {
namespace {

uint64_t micros(Clock::time_point t) {
  return uint64_t(std::chrono::duration_cast<std::chrono::microseconds>(t.time_since_epoch()).count());
}

double ms_between(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

}  // namespace

// GL state that lives on the render thread only.
struct RenderService::Impl {
  std::unique_ptr<gpu::EglContext> context;
  std::unique_ptr<gpu::ShaderCache> shaders;
  std::unique_ptr<render::Raycaster> caster;
  struct Resident {
    std::weak_ptr<VolumeEntry> entry;
    std::unique_ptr<render::GpuVolume> gpu;
  };
  std::map<const VolumeEntry*, Resident> volumes;

  render::GpuVolume& gpu_volume(const std::shared_ptr<VolumeEntry>& e, Metrics& metrics) {
    // Drop copies of volumes the store has let go.
    for (auto it = volumes.begin(); it != volumes.end();)
      it = it->second.entry.expired() ? volumes.erase(it) : std::next(it);
    auto& r = volumes[e.get()];
    if (!r.gpu) {
      r.entry = e;
      r.gpu = std::make_unique<render::GpuVolume>(e->volume);
    }
    int64_t bytes = 0;
    for (auto& [_, v] : volumes) bytes += int64_t(v.gpu->gpu_bytes());
    metrics.set("peakcast_gpu_volumes", "", double(volumes.size()));
    metrics.set("peakcast_gpu_volume_bytes", "", double(bytes));
    return *r.gpu;
  }
};

RenderService::RenderService(VolumeStore& volumes, Metrics& metrics, RenderServiceOptions options)
    : volumes_(volumes), metrics_(metrics), options_(std::move(options)) {}

RenderService::~RenderService() { stop(); }

void RenderService::start() {
  pool_ = std::make_unique<encode::EncodePool>(options_.encode_threads);
  std::promise<std::string> ready;
  auto started = ready.get_future();
  thread_ = std::thread([this, &ready] {
    auto impl = std::make_unique<Impl>();
    try {
      impl->context = gpu::EglContext::create();
      impl->shaders = std::make_unique<gpu::ShaderCache>(options_.shader_dir);
      impl->caster = std::make_unique<render::Raycaster>(*impl->shaders);
      ready.set_value(impl->context->info().to_string());
    } catch (...) {
      ready.set_exception(std::current_exception());
      return;
    }
    thread_impl_ = std::move(impl);
    loop();
    thread_impl_.reset();  // GL objects die on the thread that owns the context
  });
  try {
    gl_renderer_ = started.get();
  } catch (...) {
    thread_.join();
    throw;
  }
}

void RenderService::stop() {
  {
    std::lock_guard lock(m_);
    if (stopping_) return;
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  pool_.reset();  // drains encodes
}

std::string RenderService::gl_renderer() const { return gl_renderer_; }

void RenderService::add_session(const std::shared_ptr<Session>& s) {
  {
    std::lock_guard lock(m_);
    sessions_[s->id()] = s;
    wake_ = true;
  }
  cv_.notify_all();
}

void RenderService::remove_session(const std::string& id) {
  std::lock_guard lock(m_);
  sessions_.erase(id);
}

size_t RenderService::session_count() const {
  std::lock_guard lock(m_);
  return sessions_.size();
}

void RenderService::notify() {
  {
    std::lock_guard lock(m_);
    wake_ = true;
  }
  cv_.notify_all();
}

void RenderService::submit_still(StillJob job) {
  {
    std::lock_guard lock(m_);
    stills_.push_back(std::move(job));
    wake_ = true;
  }
  cv_.notify_all();
}

void RenderService::loop() {
  Impl& impl = *thread_impl_;
  const auto min_interval = std::chrono::duration<double>(1.0 / std::max(1.0, options_.max_fps));
  size_t rr = 0;  // round-robin start among sessions
  for (;;) {
    std::optional<StillJob> still;
    std::shared_ptr<Session> session;
    std::optional<FrameJob> job;
    {
      std::unique_lock lock(m_);
      for (;;) {
        if (stopping_) return;
        wake_ = false;
        if (!stills_.empty()) {
          still = std::move(stills_.front());
          stills_.pop_front();
          break;
        }
        Clock::time_point next_wake = Clock::time_point::max();
        const auto now = Clock::now();
        std::vector<std::shared_ptr<Session>> live;
        for (auto it = sessions_.begin(); it != sessions_.end();) {
          if (auto s = it->second.lock()) {
            live.push_back(std::move(s));
            ++it;
          } else {
            it = sessions_.erase(it);
          }
        }
        for (size_t k = 0; k < live.size() && !job; ++k) {
          auto& s = live[(rr + k) % live.size()];
          Clock::time_point wake;
          job = s->take_job(now, options_.still_delay, min_interval, wake);
          if (job) {
            session = s;
            rr = (rr + k + 1) % std::max<size_t>(1, live.size());
          }
          next_wake = std::min(next_wake, wake);
        }
        if (job) break;
        if (next_wake == Clock::time_point::max())
          cv_.wait(lock, [&] { return stopping_ || wake_; });
        else
          cv_.wait_until(lock, next_wake, [&] { return stopping_ || wake_; });
      }
    }
    if (still) {
      StillJob sj = std::move(*still);
      try {
        render::RenderStats st;
        Image img = impl.caster->render(impl.gpu_volume(sj.volume, metrics_), sj.scene, render::GpuPath::Fragment, &st);
        metrics_.observe("peakcast_render_ms", "kind=\"rest\"", st.render_ms);
        pool_->submit([sj = std::move(sj), img = std::move(img), st](encode::JpegEncoder& enc) {
          StillResult r;
          const auto t0 = Clock::now();
          const auto rgb = encode::to_rgb8(img);
          r.bytes = sj.png ? encode::encode_png(rgb.data(), img.width, img.height)
                           : enc.encode(rgb.data(), img.width, img.height, sj.quality, encode::Subsampling::S444);
          r.content_type = sj.png ? "image/png" : "image/jpeg";
          r.encode_ms = ms_between(t0, Clock::now());
          r.render_ms = st.render_ms;
          r.samples_per_ray = st.samples_mean;
          r.variant = st.variant;
          sj.done(std::move(r));
        });
      } catch (const std::exception& e) {
        StillResult r;
        r.error = e.what();
        sj.done(std::move(r));
      }
      continue;
    }
    // A session frame.
    auto sink = session->sink();
    if (!sink) {
      session->frame_dropped(job->frame_id);
      continue;
    }
    try {
      render::RenderStats st;
      Image img = impl.caster->render(impl.gpu_volume(job->volume, metrics_), job->scene, render::GpuPath::Fragment, &st);
      const auto rendered = Clock::now();
      const char* kind = job->final ? "kind=\"final\"" : "kind=\"interactive\"";
      metrics_.observe("peakcast_render_ms", kind, st.render_ms);
      pool_->submit([this, job = std::move(*job), img = std::move(img), st, rendered, sink,
                     session](encode::JpegEncoder& enc) {
        const auto t0 = Clock::now();
        const auto rgb = encode::to_rgb8(img);
        const bool png = job.final && job.quality.final_png;
        const int q = job.final ? job.quality.final_quality : job.quality.interactive_quality;
        std::vector<uint8_t> bytes =
            png ? encode::encode_png(rgb.data(), img.width, img.height)
                : enc.encode(rgb.data(), img.width, img.height, q,
                             job.final ? encode::Subsampling::S444 : encode::Subsampling::S420);
        const auto encoded = Clock::now();
        metrics_.observe("peakcast_encode_ms", job.final ? "kind=\"final\"" : "kind=\"interactive\"",
                         ms_between(t0, encoded));
        protocol::FrameHeader h;
        h.frame_id = job.frame_id;
        h.flags = (job.final ? protocol::FrameHeader::kFinal : protocol::FrameHeader::kInteractive) |
                  (png ? protocol::FrameHeader::kPng : 0u);
        h.camera_version = job.camera_version;
        h.tf_version = job.tf_version;
        h.render_version = job.render_version;
        h.width = uint32_t(img.width);
        h.height = uint32_t(img.height);
        h.quality = png ? 100u : uint32_t(q);
        h.t_input_us = micros(job.input_time);
        h.t_render_done_us = micros(rendered);
        h.t_encode_done_us = micros(encoded);
        const size_t image_bytes = bytes.size();
        sink->deliver_frame(protocol::encode_frame(h, bytes), job.frame_id, job.final);
        nlohmann::json stats = {{"type", "stats"},
                                {"frame", job.frame_id},
                                {"final", job.final},
                                {"width", img.width},
                                {"height", img.height},
                                {"render_ms", st.render_ms},
                                {"encode_ms", ms_between(t0, encoded)},
                                {"table_ms", st.table_ms},
                                {"samples_per_ray", st.samples_mean},
                                {"samples_per_ray_max", st.samples_max},
                                {"bytes", image_bytes},
                                {"variant", st.variant},
                                {"peaks", st.peaks},
                                {"empty_macrocells", st.empty_cells}};
        sink->deliver_text(stats.dump());
      });
    } catch (const std::exception& e) {
      session->frame_dropped(job->frame_id);
      sink->deliver_text(protocol::error_message("render_failed", e.what()));
    }
  }
}

}  // namespace peakcast
