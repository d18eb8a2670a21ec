// What the render thread does next. Viewers' frames are taken round robin from
// the sessions (newest state wins inside each session); scripted stills wait in a bounded queue
// and are rendered in bands of rows that alternate with viewers' frames, so a viewer's frame
// waits for at most one band however many stills are queued. No GL here: the policy is tested in
// memory (tests/net/scheduler_test.cpp).
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"
#include "session/session.h"

namespace peakcast {
namespace distributed {
struct SequenceStatistics;
class SequenceRun;
struct SequenceResult;
}  // namespace distributed

struct StillResult {
  std::vector<uint8_t> bytes;
  std::string content_type;
  double render_ms = 0, encode_ms = 0, wait_ms = 0, samples_per_ray = 0;
  int bands = 0, width = 0, height = 0;
  int bricks = 0;  // a still of a pyramid's finest level: the bricks drawn (bands is the same)
  std::string variant;
  std::vector<std::string> warnings;  // what the render found on the way (X-Warning), beside the scene's
  std::string error, error_code;      // error: the job failed (message for the client; code from proto/)
};

// A scripted still (REST). `done` is called exactly once: with the image, or with an error
// (render failure, cancelled, server shutting down).
struct StillJob {
  std::shared_ptr<VolumeEntry> volume;
  ResolvedScene scene;
  bool png = true;
  bool raw_rgb = false;    // the 8-bit RGB bytes themselves (format=rgb), no encoding
  bool rgba = false;       // a PNG with alpha and no background (format=rgba)
  bool raw_float = false;  // the float RGBA image as drawn, float32 little-endian (format=float)
  int quality = 95;
  // Set for a pyramid held coarser than its finest level (VolumeEntry::full): the still draws the
  // finest level brick after brick, `scene` resolved against these statistics' box.
  std::shared_ptr<const distributed::SequenceStatistics> full_statistics;
  std::function<void(StillResult)> done;
  // Optional, on the render thread after each brick of a still by bricks: the share done, and of how many.
  std::function<void(double share, int bricks)> progress;
  // Set by the connection when its client goes away: the still stops at the next band.
  std::shared_ptr<std::atomic<bool>> cancelled = std::make_shared<std::atomic<bool>>(false);
  // A viewer's view at rest drawn at the finest level (RenderService::queue_refinement): the
  // viewer's session id, empty for a script's still. Not counted against max_queued_stills, so
  // scripts' stills cannot keep a view coarse nor a viewer's refinement refuse a script; at most
  // one live (not cancelled: input or leaving cancels it) per viewer.
  std::string refinement_of;
  bool refinement() const { return !refinement_of.empty(); }
};

// Estimated filter evaluations per ray: the box diagonal over the step, at least one. An upper
// bound for uniform sampling; what the cost cap and the band size are computed from.
double estimated_samples_per_ray(const ResolvedScene& s);
// Estimated samples of a whole still: pixels x samples per ray.
double estimated_still_samples(const ResolvedScene& s);

// A still in progress: bands of rows rendered one at a time into `image`.
struct StillWork {
  StillJob job;
  uint64_t id = 0;
  Clock::time_point queued, started;
  int band_rows = 1;  // rows per band, from SchedulerOptions::band_samples
  int next_row = 0;   // first row not yet rendered
  int bands = 0;
  Image image;
  double render_ms = 0, samples_total = 0;
  int64_t rays_hit = 0;
  std::string variant;
  std::vector<std::string> warnings;  // StillResult::warnings
  // A still of the finest level: one brick per turn instead of a band (job.full_statistics).
  std::shared_ptr<distributed::SequenceRun> bricks;
  // Its bands of rows (distributed::image_tiles: the image buffers stay within a share of the
  // budget), the band being drawn and the bands drawn so far.
  int tile = 0, tiles = 1;
  std::shared_ptr<distributed::SequenceResult> drawn;
  bool bricks_done = false;
  bool by_bricks() const { return job.full_statistics != nullptr; }
  bool complete() const { return by_bricks() ? bricks_done : next_row >= job.scene.scene.height; }
};

struct SchedulerOptions {
  size_t max_queued_stills = 4;  // scripts' stills waiting + in progress; beyond: refused (503)
  double band_samples = 1.5e7;   // estimated samples per band (~50-100 ms on llvmpipe)
  std::chrono::milliseconds still_delay{150};
  double max_fps = 60.0;  // per session; 0: no limit (tests)
};

class Scheduler {
 public:
  explicit Scheduler(SchedulerOptions options);

  // Connection side (any thread).
  void add_session(const std::shared_ptr<Session>& s);
  void remove_session(const std::string& id);
  size_t session_count() const;
  void notify();  // some session's state or acks changed
  // Queues a still; returns false (and keeps nothing) when the queue is full or shutting down.
  // Scripts' stills count against max_queued_stills; a viewer may have one live refinement.
  bool submit_still(StillJob job);
  size_t stills_pending() const;  // queued + in progress

  // Shutdown: next() returns nullopt from now on; the stills not finished are handed back so the
  // caller can refuse them, except a band being rendered now: that still is marked cancelled and
  // the render thread answers it when the band ends.
  std::vector<StillJob> shut_down();
  bool shutting_down() const;

  // Render-thread side. Blocks until there is work; nullopt once shutting down.
  struct Work {
    std::shared_ptr<Session> session;  // a viewer's frame...
    std::optional<FrameJob> frame;
    std::shared_ptr<StillWork> still;  // ...or the next band of a still: rows [y0, y0 + rows)
    int y0 = 0, rows = 0;
    std::vector<StillJob> cancelled;  // stills whose clients went away: answer them
  };
  // wait false: nullopt at once when nothing is ready (the render thread has a frame in flight
  // to finish meanwhile).
  std::optional<Work> next(bool wait = true);
  // The band handed out by next() is in still->image: the still leaves the scheduler when complete.
  void band_done(const std::shared_ptr<StillWork>& still);
  // The still failed: it leaves the scheduler.
  void still_failed(const std::shared_ptr<StillWork>& still);

 private:
  std::optional<FrameJob> take_session_job(Clock::time_point now, std::shared_ptr<Session>& session,
                                           Clock::time_point& wake);           // lock held
  std::shared_ptr<StillWork> current_still(std::vector<StillJob>& cancelled);  // lock held

  SchedulerOptions options_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::map<std::string, std::weak_ptr<Session>> sessions_;
  std::deque<std::shared_ptr<StillWork>> stills_;  // front: in progress once started
  std::shared_ptr<StillWork> rendering_;           // handed out by next(), until band_done/still_failed
  uint64_t next_still_ = 1;
  size_t rr_ = 0;                  // round-robin start among sessions
  bool last_was_session_ = false;  // alternate with stills
  bool stopping_ = false, wake_ = false;
};

}  // namespace peakcast
