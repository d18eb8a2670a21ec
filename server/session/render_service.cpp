#include "session/render_service.h"

#include <algorithm>
#include <cstdio>
#include <deque>
#include <exception>
#include <future>
#include <optional>
#include <tuple>

#include "core/log.h"
#include "distributed/brick_sequence.h"
#include "render/brick.h"
#include "encode/png.h"
#include "render/backend.h"
#include "session/frame_encoder.h"

namespace peakcast {

namespace {

// A still by bricks whose image buffers and grids left its bricks less than half their share: it
// held more than the budget, which the script hears (X-Warning) and not only the log.
std::string budget_warning(const distributed::SequenceResult& r, int64_t budget_bytes) {
  char text[400];
  std::snprintf(text, sizeof text,
                "memory budget: this %dx%d still's image buffers and grids (%.1f MiB) beside its %d bricks left them "
                "less than half of --memory-budget-mib %lld, so it held more than the budget; a smaller image or a "
                "larger budget keeps within it",
                r.image.width, r.image.height, double(r.beside_bytes) / 1048576.0, r.bricks,
                (long long)(budget_bytes >> 20));
  return text;
}

}  // namespace

// The renderer (and GL state) that lives on the render thread only, and the viewers' frames
// submitted to it and not yet collected (oldest first).
struct RenderService::Impl {
  render::RenderBackend backend;
  struct Submitted {
    std::shared_ptr<Session> session;
    std::shared_ptr<FrameSink> sink;
    FrameJob job;
  };
  std::deque<Submitted> submitted;
};

RenderService::RenderService(Residency& residency, Metrics& metrics, RenderServiceOptions options)
    : residency_(residency), metrics_(metrics), options_(std::move(options)), scheduler_(options_.scheduling) {}

RenderService::~RenderService() { stop(); }

void RenderService::start() {
  pool_ = std::make_unique<encode::EncodePool>(options_.encode_threads);
  metrics_.set("peakcast_ranks", "", double(options_.ranks));
  std::promise<std::pair<std::string, std::string>> ready;
  auto started = ready.get_future();
  thread_ = std::thread([this, &ready] {
    auto impl = std::make_unique<Impl>();
    try {
      impl->backend = render::open_backend(render::requested_backend(options_.backend), options_.egl_device,
                                           options_.shader_dir, options_.program_cache);
      if (options_.wrap_renderer) impl->backend.renderer = options_.wrap_renderer(std::move(impl->backend.renderer));
      ready.set_value({impl->backend.description(), render::to_string(impl->backend.backend)});
    } catch (...) {
      ready.set_exception(std::current_exception());
      return;
    }
    impl_ = std::move(impl);
    loop();
    residency_.release_gpu();  // GL objects die on the thread that owns the context
    impl_.reset();
  });
  try {
    std::tie(gl_renderer_, backend_) = started.get();
  } catch (...) {
    thread_.join();
    throw;
  }
}

void RenderService::stop() {
  if (stopped_) return;
  stopped_ = true;
  for (auto& job : scheduler_.shut_down()) refuse(job, "shutting_down", "the server is shutting down");
  if (thread_.joinable()) thread_.join();
  pool_.reset();  // drains encodes
}

std::string RenderService::gl_renderer() const { return gl_renderer_; }

bool RenderService::submit_still(StillJob job) {
  if (!scheduler_.submit_still(std::move(job))) return false;
  metrics_.set("peakcast_stills_queued", "", double(scheduler_.stills_pending()));
  return true;
}

void RenderService::refuse(StillJob& job, const std::string& code, const std::string& message) {
  metrics_.add("peakcast_stills_total", "outcome=\"" + code + "\"", 1);
  StillResult r;
  r.error_code = code;
  r.error = message;
  if (job.done) job.done(std::move(r));
}

void RenderService::loop() {
  // A frame is submitted, then collected: right away, or, where the renderer overlaps work (a
  // GPU), after the next frame is submitted, so the next draw runs while this frame is read
  // back and encoded. A band of a still waits for the frames in flight.
  const bool overlap = impl_->backend.renderer->asynchronous();
  for (;;) {
    auto w = scheduler_.next(impl_->submitted.empty());
    if (!w) {
      if (impl_->submitted.empty()) break;  // shutting down
      collect_frame();                      // nothing else ready: this frame goes now
      continue;
    }
    for (auto& job : w->cancelled) refuse(job, "cancelled", "the client went away");
    if (w->still) {
      while (!impl_->submitted.empty()) collect_frame();
      render_band(*w);
    } else if (w->frame) {
      // A frame whose viewer has gone, or whose submit failed, was never submitted: nothing to collect.
      const bool submitted = submit_frame(*w);
      if (submitted && (!overlap || impl_->submitted.size() >= render::Renderer::kFramesInFlight)) collect_frame();
    }
    metrics_.set("peakcast_stills_queued", "", double(scheduler_.stills_pending()));
  }
  while (!impl_->submitted.empty()) collect_frame();
}

bool RenderService::submit_frame(Scheduler::Work& w) {
  FrameJob& job = *w.frame;
  auto sink = w.session->sink();
  if (!sink) {
    w.session->frame_dropped(job.frame_id);
    return false;
  }
  try {
    // 8-bit RGB straight from the GPU (3 bytes per pixel); the per-pixel sample counts (4 more)
    // only for final frames, whose stats the client shows.
    render::RenderRequest req;
    req.output = render::RenderOutput::Rgb8;
    req.sample_stats = job.final;
    render::Renderer& r = *impl_->backend.renderer;
    r.submit(residency_.acquire(job.volume, r), job.scene, req);
    impl_->submitted.push_back({w.session, std::move(sink), std::move(job)});
    return true;
  } catch (const std::exception& e) {
    w.session->frame_dropped(job.frame_id);
    sink->deliver_text(protocol::error_message("render_failed", e.what()));
    return false;
  }
}

void RenderService::collect_frame() {
  Impl::Submitted s = std::move(impl_->submitted.front());
  impl_->submitted.pop_front();
  try {
    render::RenderStats st;
    render::RenderResult out = impl_->backend.renderer->collect(&st);
    metrics_.set("peakcast_gpu_volumes", "", double(residency_.gpu_volumes()));
    metrics_.set("peakcast_gpu_volume_bytes", "", double(residency_.gpu_bytes()));
    RenderedFrame f;
    f.rendered = Clock::now();
    metrics_.observe("peakcast_render_ms", s.job.final ? "kind=\"final\"" : "kind=\"interactive\"", st.render_ms);
    if (!s.job.final) s.session->interactive_rendered(int64_t(out.rgb8.width) * out.rgb8.height, st.render_ms);
    // At rest: what the session may switch to next is prepared in the background meanwhile.
    if (s.job.final) impl_->backend.renderer->prefetch_variants();
    f.width = out.rgb8.width;
    f.height = out.rgb8.height;
    f.rgb = std::move(out.rgb8.rgb);
    f.stats = st.to_json();
    if (const Volume& v = *s.job.volume->volume; v.pyramid_levels > 1) f.stats["level"] = v.pyramid_level;
    if (const Volume& v = *s.job.volume->volume; v.time_points > 1) f.stats["time"] = v.time_point;
    if (s.job.refine) f.stats["refining"] = true;  // the finest level's frame follows
    f.job = std::move(s.job);
    if (f.job.video) f.video_ticket = f.job.video->take_ticket();  // encoded in the order rendered
    std::optional<FrameJob> refined;  // only when a finest-level frame follows: what it echoes
    if (f.job.refine) refined = f.job;
    // The finest level's frame is queued once the held level's frame is handed to the sink: it
    // then reaches the wire after it, with its stats after the held frame's. Queued here, a quick
    // refinement could overtake the encode, and its frame (a newer id) be replaced in the send
    // queue by the held one, or its stats come between the held frame and the held frame's stats.
    pool_->submit([this, f = std::move(f), sink = s.sink, session = s.session, refined](encode::JpegEncoder& enc) {
      std::exception_ptr failed;  // the held frame failed: its finest level is still owed
      try {
        encode_viewer_frame(enc, f, *sink, metrics_);
      } catch (...) {
        failed = std::current_exception();
      }
      if (refined) queue_refinement(session, sink, *refined);
      if (failed) std::rethrow_exception(failed);
    });
  } catch (const std::exception& e) {
    s.session->frame_dropped(s.job.frame_id);
    s.sink->deliver_text(protocol::error_message("render_failed", e.what()));
  }
}

void RenderService::queue_refinement(const std::shared_ptr<Session>& session, const std::shared_ptr<FrameSink>& sink,
                                     FrameJob job) {
  StillJob still;
  still.volume = job.volume;
  still.scene = job.refine->scene;
  still.full_statistics = job.refine->statistics;
  still.png = job.quality.final_png;
  still.quality = job.quality.final_quality;
  still.cancelled = job.refine->cancelled;
  still.refinement_of = session->id();
  const std::weak_ptr<FrameSink> weak_sink = sink;
  const std::weak_ptr<Session> weak_session = session;
  still.progress = [weak_sink, cancelled = still.cancelled](double share, int bricks) {
    if (auto s = weak_sink.lock(); s && !cancelled->load()) s->deliver_text(protocol::refining_message(share, bricks));
  };
  still.done = [weak_sink, weak_session, cancelled = still.cancelled, job = std::move(job)](StillResult r) {
    auto s = weak_sink.lock();
    auto session = weak_session.lock();
    if (!s || !session || cancelled->load()) return;  // stale: the view moved on
    if (!r.error.empty()) {                           // shutting down or cancelled: nothing to say; a failure: say why
      if (r.error_code == "render_failed" || r.error_code == "encode_failed")
        s->deliver_text(protocol::error_message("render_failed", "the finest level: " + r.error));
      return;
    }
    if (const auto id = session->refined_frame_id(*cancelled)) deliver_refined_frame(*s, *id, job, std::move(r));
  };
  // Refused only when shutting down, or while this viewer's last refinement is still live.
  if (scheduler_.submit_still(std::move(still)))
    metrics_.set("peakcast_stills_queued", "", double(scheduler_.stills_pending()));
}

void RenderService::render_band(Scheduler::Work& w) {
  StillWork& sw = *w.still;
  if (sw.bands == 0)
    metrics_.observe("peakcast_still_wait_ms", "",
                     std::chrono::duration<double, std::milli>(sw.started - sw.queued).count());
  if (sw.by_bricks()) return render_brick(w);
  try {
    // Float output, as `peakcast render` does: the assembled still equals the CLI's image.
    render::RenderStats st;
    render::RenderRequest req;
    req.tile = render::PixelRect{0, w.y0, sw.job.scene.scene.width, w.rows};
    render::RenderResult band = impl_->backend.renderer->render(
        residency_.acquire(sw.job.volume, *impl_->backend.renderer), sw.job.scene, req, &st);
    render::place_tile(sw.image, band.rect, band.image);
    sw.render_ms += st.render_ms;
    sw.samples_total += st.samples_total;
    sw.rays_hit += st.rays_hit;
    sw.variant = st.variant;
    sw.bands++;
    sw.next_row += w.rows;
    still_progress_ = double(sw.next_row) / double(sw.job.scene.scene.height);
    metrics_.observe("peakcast_render_ms", "kind=\"still_band\"", st.render_ms);
  } catch (const std::exception& e) {
    scheduler_.still_failed(w.still);
    return refuse(sw.job, "render_failed", e.what());
  }
  still_turn_done(w);
}

void RenderService::render_brick(Scheduler::Work& w) {
  StillWork& sw = *w.still;
  const FullResolution& full = *sw.job.volume->full;
  try {
    // The first turn opens the sequence (and starts reading its first brick): a still waiting in
    // the queue holds no voxels. A band of rows at a time (image_tiles), each over every brick.
    const int64_t budget = full.brick_budget(int64_t(sw.job.volume->volume->byte_size()));
    if (!sw.bricks && sw.tile == 0) {
      render::check_bricks_draw(sw.job.scene);  // before the first brick is read
      sw.tiles = distributed::image_tiles(sw.job.scene, budget);
      sw.drawn = std::make_shared<distributed::SequenceResult>();
    }
    const render::PixelRect rect = distributed::image_tile(sw.job.scene, sw.tile, sw.tiles);
    if (!sw.bricks)
      sw.bricks = std::make_shared<distributed::SequenceRun>(full.path.string(), full.options, sw.job.full_statistics,
                                                             sw.job.scene, budget, rect);
    const auto t0 = Clock::now();
    sw.bricks->step(*impl_->backend.renderer);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    sw.render_ms += ms;
    sw.bands++;
    still_progress_ = (double(sw.tile) + sw.bricks->progress()) / double(sw.tiles);
    if (sw.job.progress) sw.job.progress(still_progress_, sw.bricks->bricks());
    metrics_.observe("peakcast_render_ms", "kind=\"still_brick\"", ms);
    if (sw.bricks->done()) {
      distributed::add_tile(*sw.drawn, sw.bricks->take(), rect, sw.job.scene);
      sw.bricks.reset();  // no voxels held between bands, nor while the still is encoded
      if (++sw.tile < sw.tiles) return still_turn_done(w);
      distributed::SequenceResult& r = *sw.drawn;
      r.tiles = sw.tiles;
      if (r.budget_too_small) {  // the bricks got half their share: the still held more than the budget
        log::warn("memory budget too small for a full-resolution still's image buffers beside its bricks",
                  {{"width", r.image.width},
                   {"height", r.image.height},
                   {"bricks", r.bricks},
                   {"beside_mib", double(r.beside_bytes) / 1048576.0}});
        sw.warnings.push_back(budget_warning(r, full.budget_bytes));
      }
      sw.image = std::move(r.image);
      sw.variant = "bricks";
      sw.drawn.reset();
      sw.bricks_done = true;
    }
  } catch (const std::exception& e) {
    sw.bricks.reset();
    scheduler_.still_failed(w.still);
    return refuse(sw.job, "render_failed", e.what());
  }
  still_turn_done(w);
}

// After a band or a brick: a cancelled still is answered, a complete one encoded.
void RenderService::still_turn_done(Scheduler::Work& w) {
  StillWork& sw = *w.still;
  if (sw.job.cancelled->load()) {
    scheduler_.still_failed(w.still);
    return scheduler_.shutting_down() ? refuse(sw.job, "shutting_down", "the server is shutting down")
                                      : refuse(sw.job, "cancelled", "the client went away");
  }
  scheduler_.band_done(w.still);
  if (sw.complete())
    pool_->submit([this, still = w.still](encode::JpegEncoder& enc) { encode_still(enc, *still, metrics_); });
}

}  // namespace peakcast
