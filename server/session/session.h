// One viewer's state (docs/architecture.md): written by its connection (newest wins), read by
// the render thread as snapshots. Flow control: at most limits::kMaxFramesInFlight
// un-acknowledged frames; a client that stops acking gets no more frames and costs no more memory.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/ray_texture_png.h"
#include "core/scene.h"
#include "session/limits.h"
#include "session/protocol.h"
#include "session/video_channel.h"
#include "session/volume_store.h"

namespace peakcast {
namespace distributed {
struct SequenceStatistics;
}

using Clock = std::chrono::steady_clock;

// Where a session's output goes: its connection. Called from encode threads; implementations
// post onto their own strand.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // `video`: one frame of the session's video stream, which the next one refers to: never
  // replaced by a newer frame once encoded (docs/streaming.md).
  virtual void deliver_frame(std::vector<uint8_t> bytes, uint32_t frame_id, bool final, bool video) = 0;
  virtual void deliver_text(std::string text) = 0;
  // A frame's stats, after its frame: a sink that drops a frame as older than one it already has
  // drops these too, so stats never go back to an older frame.
  virtual void deliver_stats(std::string text, uint32_t /*frame_id*/) { deliver_text(std::move(text)); }
};

struct Quality {
  double interactive_scale = 0.5;  // resolution ratio while input arrives (the most it may be)
  // Render-time budget of an interactive frame, ms (VTK's desired update rate): when the last
  // interactive frames took longer, the next ones drop below interactive_scale to hold it, down
  // to interactive_scale / kMaxInteractiveReduction; 0: always interactive_scale.
  double interactive_ms = 30.0;
  static constexpr double kMaxInteractiveReduction = 2.0;
  int interactive_quality = 70;  // JPEG, 4:2:0
  int final_quality = 95;        // JPEG, 4:4:4
  bool final_png = false;
  std::string codec = "jpeg";  // interactive frames: jpeg, h264, vp9 or av1 (docs/streaming.md)
  int kbps = 8000;             // a video stream's bit-rate ceiling (the server's --max-kbps at the start)
};

// Everything the render thread needs for one frame.
struct FrameJob {
  std::shared_ptr<VolumeEntry> volume;
  ResolvedScene scene;  // at the frame's resolution and step
  bool final = false;
  uint32_t frame_id = 0;
  uint32_t camera_version = 0, tf_version = 0, render_version = 0;
  Quality quality;
  Clock::time_point input_time;
  // An interactive frame of a video session: the session's stream and its settings now.
  std::shared_ptr<VideoChannel> video;
  encode::VideoSettings video_settings;
  // A final frame of a pyramid held coarser than its finest level (VolumeEntry::full): the same
  // view at the finest level, drawn by bricks after this frame (docs/chunked-volumes.md).
  struct Refinement {
    ResolvedScene scene;  // resolved against the finest level
    std::shared_ptr<const distributed::SequenceStatistics> statistics;
    std::shared_ptr<std::atomic<bool>> cancelled;  // set by the session's next input
  };
  std::shared_ptr<const Refinement> refine;
};

class Session {
 public:
  // `locate_png` finds render.ray_texture.png files (the server's data directories); without
  // one, PNG ray textures are refused.
  Session(std::string id, std::weak_ptr<FrameSink> sink, PngLocator locate_png = {});
  const std::string& id() const { return id_; }
  std::shared_ptr<FrameSink> sink() const { return sink_.lock(); }

  // Connection side. Each throws protocol::ProtocolError for a state the volume refuses.
  // `texture`: the state's render.ray_texture already parsed with its PNG read (the connection
  // reads PNGs on the loader pool); without it the session parses the state's own.
  void start(std::shared_ptr<VolumeEntry> volume, const protocol::Viewport& vp, const protocol::StatePatch& state,
             std::optional<std::shared_ptr<const RayTextureSpec>> texture = std::nullopt);
  void set_volume(std::shared_ptr<VolumeEntry> volume);  // resets camera and TF to the volume's defaults
  // Another time point of the volume viewed (VolumeStore::at_time): camera, TF and settings stay.
  void set_time(std::shared_ptr<VolumeEntry> volume);
  void set_camera(const Camera& c);
  void set_tf(const TransferFunction& tf, double opacity_unit, uint32_t version);
  // ray_texture in the patch replaces the texture (null: none); `texture`, when given, is that
  // texture already parsed with its PNG read.
  void merge_render(const nlohmann::json& patch,
                    std::optional<std::shared_ptr<const RayTextureSpec>> texture = std::nullopt);
  // One painted stroke appended to the ray texture (a new spec of the same lineage, so the
  // renderer applies just this stroke). Returns the texture's stroke count. Throws
  // ProtocolError when the session has no ray texture or it is full.
  size_t add_stroke(const Stroke& stroke);
  void set_quality(const protocol::QualityMsg& q, int max_kbps = limits::kMaxKbps);  // kbps above max_kbps: max_kbps
  void set_viewport(const protocol::Viewport& vp);
  void request_key_frame();  // a video client lost a frame: the next interactive frame is a key frame
  void ack(uint32_t frame_id);
  // The render thread's report of an interactive frame: its pixels and render time, which set
  // the next interactive frames' resolution (Quality::interactive_ms).
  void interactive_rendered(int64_t pixels, double render_ms);
  void frame_dropped(uint32_t frame_id);  // the connection replaced it before sending
  nlohmann::json state_json() const;      // volume, camera, tf, render, viewport: what the client restores
  std::string volume_id() const;          // the volume viewed now
  // The volume and the scene of the session's next final frame (the viewport's full size): what
  // a probe looks at. Throws SceneError when the state does not resolve.
  std::pair<std::shared_ptr<VolumeEntry>, ResolvedScene> view() const;
  // The finest level's statistics of `volume` (a pyramid held coarser), once reduced: from then
  // on each final frame of it is followed by one of the finest level. Ignored when the session
  // has moved to another volume meanwhile.
  void set_full_statistics(const std::shared_ptr<VolumeEntry>& volume,
                           std::shared_ptr<const distributed::SequenceStatistics> statistics);
  // A frame id for a final frame of the finest level, counted in flight like any frame; nullopt
  // when `cancelled` (new input since). Checked under the session's lock, which input takes to
  // cancel: a frame of the newer view cannot take an id before a stale refinement's.
  std::optional<uint32_t> refined_frame_id(const std::atomic<bool>& cancelled);
  // The viewer left: a refinement of its view still queued is stale (answered, never drawn).
  void leave();

  // Render-thread side. When there is nothing to do now, `wake` says when to ask again
  // (Clock::time_point::max() when only new input can create work).
  std::optional<FrameJob> take_job(Clock::time_point now, std::chrono::milliseconds still_delay,
                                   std::chrono::duration<double> min_interval, Clock::time_point& wake);
  uint32_t in_flight() const;

 private:
  void touch();              // a state change arrived (lock held)
  void cancel_refinement();  // the finest level's frame being drawn is stale (lock held)
  // Takes render.ray_texture out of a render patch: the new texture (its PNG read), or null
  // for none; nullopt when the patch does not name it. Throws ProtocolError.
  std::optional<std::shared_ptr<const RayTextureSpec>> take_ray_texture(
      nlohmann::json& patch, const std::optional<std::shared_ptr<const RayTextureSpec>>& loaded) const;
  ResolvedScene resolve(const VolumeBox* box = nullptr) const;  // lock held; box: another level's
  std::string id_;
  std::weak_ptr<FrameSink> sink_;
  mutable std::mutex m_;
  std::shared_ptr<VolumeEntry> volume_;
  Scene scene_;
  bool tf_derived_ = false;  // scene_.tf was derived from the histogram, not sent by the client
  nlohmann::json render_json_ = nlohmann::json::object();  // render settings but the ray texture
  std::shared_ptr<const RayTextureSpec> ray_texture_;      // null: none
  PngLocator locate_png_;
  protocol::Viewport viewport_;
  // The resolution ratio of the next interactive frame of a width x height view (m_ held).
  double interactive_scale(int width, int height) const;
  Quality quality_;
  std::shared_ptr<VideoChannel> video_ = std::make_shared<VideoChannel>();
  // Interactive render ms as a fixed part plus a part per pixel (a distributed frame's broadcast
  // and compositing, a tile's set-up): a least-squares line through the last frames, each
  // weighted 0.4 and the older ones 0.6 as much at every new frame. w == 0: none yet.
  struct FrameCost {
    double w = 0, x = 0, y = 0, xx = 0, xy = 0;  // weighted sums of 1, pixels, ms, pixels², pixels·ms
    void add(double pixels, double ms);
    // ms = fixed + per_pixel * pixels; a line through the origin while the frames' sizes hardly
    // differ (nothing tells the parts apart), and where the fit is not a rising line.
    void fit(double& fixed, double& per_pixel) const;
  };
  FrameCost interactive_cost_;
  uint32_t camera_version_ = 0, tf_version_ = 0, render_version_ = 0;
  bool dirty_ = false, final_pending_ = false;
  Clock::time_point last_input_{}, last_frame_{};
  uint32_t next_frame_id_ = 1;
  std::set<uint32_t> outstanding_;
  std::shared_ptr<const distributed::SequenceStatistics> full_statistics_;  // null: no refinement
  std::shared_ptr<std::atomic<bool>> refinement_cancelled_ = std::make_shared<std::atomic<bool>>(false);
};

}  // namespace peakcast
