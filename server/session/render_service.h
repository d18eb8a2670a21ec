// The render thread (docs/architecture.md): owns the renderer (render/backend.h) and, with the
// GL backend, the one GL context and every GL object. It asks the
// scheduler what to do next (a viewer's frame, or the next band of a still), renders through the
// GPU residency's copy of the volume, and hands the image to the encode pool, whose threads
// deliver to the session's connection or answer the still.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "core/metrics.h"
#include "encode/encode_pool.h"
#include "render/renderer.h"
#include "session/residency.h"
#include "session/scheduler.h"

namespace peakcast {

struct RenderServiceOptions {
  std::filesystem::path shader_dir;
  int encode_threads = 2;
  SchedulerOptions scheduling;
  std::string egl_device;     // gpu::EglContext::create's choice; empty: PEAKCAST_EGL_DEVICE, else auto
  std::string backend;        // auto | gl | cpu (render/backend.h); empty: PEAKCAST_BACKEND, else auto
  std::string program_cache;  // auto | off | a folder (render/backend.h); empty: PEAKCAST_PROGRAM_CACHE
  // Distributed rendering (mpirun peakcast serve): the opened backend's renderer handed to this,
  // on the render thread, which returns the renderer frames go through (distributed::MpiRenderer).
  std::function<std::unique_ptr<render::Renderer>(std::unique_ptr<render::Renderer>)> wrap_renderer;
  int ranks = 1;  // the processes that render each frame (health, metrics)
};

class RenderService {
 public:
  RenderService(Residency& residency, Metrics& metrics, RenderServiceOptions options);
  ~RenderService();

  // Opens the backend on the render thread (the GL context for gl); throws if that fails.
  void start();
  // Refuses the queued stills (error "shutting_down"), stops after the band or frame being
  // rendered now, answers that still too, drains the encodes and joins. Idempotent.
  void stop();
  std::string gl_renderer() const;                  // the backend's description (render/backend.h)
  std::string backend() const { return backend_; }  // "gl" or "cpu"
  int ranks() const { return options_.ranks; }

  void add_session(const std::shared_ptr<Session>& s) { scheduler_.add_session(s); }
  void remove_session(const std::string& id) { scheduler_.remove_session(id); }
  void notify() { scheduler_.notify(); }
  size_t session_count() const { return scheduler_.session_count(); }
  // False when the still queue is full or the server is stopping: the caller answers 503.
  bool submit_still(StillJob job);
  size_t stills_pending() const { return scheduler_.stills_pending(); }
  // The share of the latest still done: its bands, or its bricks (a pyramid's finest level).
  double still_progress() const { return still_progress_; }

 private:
  struct Impl;
  void loop();
  bool submit_frame(Scheduler::Work& w);  // false: not submitted (the viewer went away, or it failed)
  void collect_frame();                   // the oldest frame submitted: to the encode pool
  void render_band(Scheduler::Work& w);
  // After a final frame of a pyramid held coarser: the same view at the finest level, queued as
  // a still whose progress and image go to the viewer (FrameJob::refine).
  void queue_refinement(const std::shared_ptr<Session>& session, const std::shared_ptr<FrameSink>& sink, FrameJob job);
  void render_brick(Scheduler::Work& w);  // the next brick of a still of a pyramid's finest level
  void still_turn_done(Scheduler::Work& w);
  void refuse(StillJob& job, const std::string& code, const std::string& message);

  Residency& residency_;
  Metrics& metrics_;
  RenderServiceOptions options_;
  Scheduler scheduler_;
  std::string gl_renderer_, backend_;
  std::unique_ptr<encode::EncodePool> pool_;
  std::unique_ptr<Impl> impl_;  // touched only by the render thread
  std::thread thread_;
  bool stopped_ = false;
  std::atomic<double> still_progress_{0.0};
};

}  // namespace peakcast
