#include "session/session.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "distributed/brick_sequence.h"
#include "render/variant.h"
#include "session/limits.h"

namespace peakcast {

Session::Session(std::string id, std::weak_ptr<FrameSink> sink, PngLocator locate_png)
    : id_(std::move(id)), sink_(std::move(sink)), locate_png_(std::move(locate_png)) {}

std::optional<std::shared_ptr<const RayTextureSpec>> Session::take_ray_texture(
    nlohmann::json& patch, const std::optional<std::shared_ptr<const RayTextureSpec>>& loaded) const {
  if (!patch.is_object() || !patch.contains("ray_texture")) return std::nullopt;
  const nlohmann::json j = patch["ray_texture"];
  patch.erase("ray_texture");
  if (j.is_null()) return std::shared_ptr<const RayTextureSpec>();
  if (loaded) return loaded;
  try {
    return load_ray_texture_png(std::make_shared<const RayTextureSpec>(parse_ray_texture(j)), locate_png_);
  } catch (const SceneError& e) {
    throw protocol::ProtocolError("bad_message", e.what());
  }
}

void Session::touch() {
  dirty_ = true;
  final_pending_ = true;
  last_input_ = Clock::now();
  cancel_refinement();
}

void Session::leave() {
  std::lock_guard lock(m_);
  cancel_refinement();
}

void Session::cancel_refinement() {
  refinement_cancelled_->store(true);
  refinement_cancelled_ = std::make_shared<std::atomic<bool>>(false);
}

void Session::set_full_statistics(const std::shared_ptr<VolumeEntry>& volume,
                                  std::shared_ptr<const distributed::SequenceStatistics> statistics) {
  std::lock_guard lock(m_);
  if (!volume_ || volume->full != volume_->full) return;  // another volume now (a preview's finer level shares it)
  full_statistics_ = std::move(statistics);
  if (!dirty_) final_pending_ = true;  // the view at rest now gets its finest frame too
}

std::optional<uint32_t> Session::refined_frame_id(const std::atomic<bool>& cancelled) {
  std::lock_guard lock(m_);
  if (cancelled.load()) return std::nullopt;
  const uint32_t id = next_frame_id_++;
  outstanding_.insert(id);
  return id;
}

ResolvedScene Session::resolve(const VolumeBox* box) const {
  Scene s = scene_;
  s.render = parse_scene({{"volume", "x"}, {"render", render_json_}}).render;
  s.render.ray_texture = ray_texture_;
  s.width = viewport_.pixel_width();
  s.height = viewport_.pixel_height();
  ResolvedScene r = box ? resolve_scene(s, *box) : resolve_scene(s, *volume_->volume);
  r.tf_derived = tf_derived_;  // derived once, when the volume was opened, and kept since
  return r;
}

std::pair<std::shared_ptr<VolumeEntry>, ResolvedScene> Session::view() const {
  std::lock_guard lock(m_);
  return {volume_, resolve()};
}

void Session::start(std::shared_ptr<VolumeEntry> volume, const protocol::Viewport& vp,
                    const protocol::StatePatch& state, std::optional<std::shared_ptr<const RayTextureSpec>> texture) {
  std::lock_guard lock(m_);
  volume_ = std::move(volume);
  viewport_ = vp;
  scene_ = Scene{};
  scene_.volume = volume_->id;
  scene_.time = volume_->time;
  if (state.render) {
    render_json_ = *state.render;
    if (auto rt = take_ray_texture(render_json_, texture)) ray_texture_ = *rt;
  }
  if (state.background) scene_.background = *state.background;
  scene_.camera = state.camera;
  scene_.tf = state.tf;
  scene_.opacity_unit = state.tf ? state.opacity_unit : 0.0;
  // Defaults resolved now, so the client knows the camera and TF it starts from (a derived TF
  // fits the session's classification: with peaks it has one).
  try {
    const ResolvedScene r = resolve();
    scene_.camera = r.camera;
    scene_.tf = r.tf;
  } catch (const SceneError& e) {
    throw protocol::ProtocolError("bad_message", e.what());
  }
  tf_derived_ = !state.tf;
  camera_version_ = tf_version_ = render_version_ = 1;
  touch();
}

void Session::set_volume(std::shared_ptr<VolumeEntry> volume) {
  std::lock_guard lock(m_);
  volume_ = std::move(volume);
  full_statistics_.reset();
  scene_.volume = volume_->id;
  scene_.time = volume_->time;
  scene_.camera.reset();
  scene_.tf.reset();
  scene_.opacity_unit = 0.0;
  // A crop box or plane is in the old volume's world units: it goes with that volume, as the
  // camera and TF do (the client drops it from its controls and share link with the state).
  if (render_json_.is_object() && render_json_.erase("clip")) render_version_++;
  const ResolvedScene r = resolve();
  scene_.camera = r.camera;
  scene_.tf = r.tf;
  tf_derived_ = true;
  camera_version_++;
  tf_version_++;
  touch();
}

void Session::set_time(std::shared_ptr<VolumeEntry> volume) {
  std::lock_guard lock(m_);
  if (!volume_ || volume->id != volume_->id) return;  // another volume was opened meanwhile
  volume_ = std::move(volume);
  full_statistics_.reset();
  scene_.time = volume_->time;
  render_version_++;
  touch();
}

void Session::set_camera(const Camera& c) {
  std::lock_guard lock(m_);
  scene_.camera = c;
  camera_version_++;
  touch();
}

void Session::set_tf(const TransferFunction& tf, double opacity_unit, uint32_t version) {
  std::lock_guard lock(m_);
  scene_.tf = tf;
  scene_.opacity_unit = opacity_unit;
  tf_derived_ = false;
  tf_version_ = version ? version : tf_version_ + 1;
  touch();
}

void Session::merge_render(const nlohmann::json& patch, std::optional<std::shared_ptr<const RayTextureSpec>> loaded) {
  nlohmann::json rest = patch;
  const auto texture = take_ray_texture(rest, loaded);  // parsed (a PNG read) before the lock is taken
  std::lock_guard lock(m_);
  nlohmann::json merged = render_json_;
  merged.merge_patch(rest);
  const nlohmann::json before = render_json_;
  const auto texture_before = ray_texture_;
  render_json_ = merged;
  if (texture) ray_texture_ = *texture;
  try {
    if (volume_) resolve();  // e.g. a step below the volume's floor
  } catch (const SceneError& e) {
    render_json_ = before;
    ray_texture_ = texture_before;
    throw protocol::ProtocolError("bad_message", e.what());
  }
  render_version_++;
  touch();
}

size_t Session::add_stroke(const Stroke& stroke) {
  std::lock_guard lock(m_);
  if (!ray_texture_)
    throw protocol::ProtocolError(
        "bad_message", "stroke: the session has no ray texture; send render.ray_texture {mapping, size} first");
  try {
    ray_texture_ = with_stroke(*ray_texture_, stroke);
  } catch (const SceneError& e) {
    throw protocol::ProtocolError("bad_message", e.what());
  }
  render_version_++;
  touch();
  return ray_texture_->strokes.size();
}

void Session::set_quality(const protocol::QualityMsg& q, int max_kbps) {
  std::lock_guard lock(m_);
  if (q.interactive_scale) quality_.interactive_scale = *q.interactive_scale;
  if (q.interactive_ms) quality_.interactive_ms = *q.interactive_ms;
  if (q.interactive_quality) quality_.interactive_quality = *q.interactive_quality;
  if (q.final_quality) quality_.final_quality = *q.final_quality;
  if (q.final_format) quality_.final_png = *q.final_format == "png";
  if (q.codec) quality_.codec = *q.codec;
  if (q.kbps) quality_.kbps = std::min(*q.kbps, max_kbps);
  final_pending_ = true;  // re-send the still at the new quality
  cancel_refinement();
}

void Session::set_viewport(const protocol::Viewport& vp) {
  std::lock_guard lock(m_);
  viewport_ = vp;
  touch();
}

void Session::request_key_frame() { video_->request_key_frame(); }

void Session::ack(uint32_t frame_id) {
  std::lock_guard lock(m_);
  outstanding_.erase(frame_id);
}

void Session::frame_dropped(uint32_t frame_id) { ack(frame_id); }

void Session::interactive_rendered(int64_t pixels, double render_ms) {
  if (pixels <= 0 || !(render_ms >= 0.0) || !std::isfinite(render_ms)) return;
  std::lock_guard lock(m_);
  // Weighted over the last few frames: one slow frame (a page fault, a neighbour's still band)
  // moves the resolution a little, a heavier view moves it within a few frames.
  interactive_cost_.add(double(pixels), render_ms);
}

void Session::FrameCost::add(double pixels, double ms) {
  const double old = w > 0 ? 0.6 : 0.0, now = w > 0 ? 0.4 : 1.0;
  w = old * w + now;
  x = old * x + now * pixels;
  y = old * y + now * ms;
  xx = old * xx + now * pixels * pixels;
  xy = old * xy + now * pixels * ms;
}

void Session::FrameCost::fit(double& fixed, double& per_pixel) const {
  const double mx = x / w, my = y / w;
  const double var = xx / w - mx * mx, cov = xy / w - mx * my;
  fixed = 0.0;
  per_pixel = mx > 0 ? my / mx : 0.0;
  // Only sizes well apart tell a fixed part from a part per pixel (a standard deviation of 14%
  // of the mean: frames a third apart); neighbouring 64ths and a few percent of jitter would make
  // up an intercept.
  if (!(var > 0.02 * mx * mx)) return;
  const double slope = cov / var, intercept = my - slope * mx;
  if (slope > 0 && intercept > 0) {
    fixed = intercept;
    per_pixel = slope;
  }
}

double Session::interactive_scale(int width, int height) const {
  const double most = quality_.interactive_scale;
  if (quality_.interactive_ms <= 0.0 || interactive_cost_.w <= 0.0) return most;
  double fixed = 0.0, per_pixel = 0.0;
  interactive_cost_.fit(fixed, per_pixel);
  const double view = double(width) * double(height);
  if (!(per_pixel > 0.0) || fixed + view * most * most * per_pixel <= quality_.interactive_ms) return most;
  // The pixels the budget leaves after the fixed part (none: the smallest frame).
  const double affordable = std::max(0.0, quality_.interactive_ms - fixed) / per_pixel;
  const double fit = std::sqrt(affordable / view);
  // In steps of 1/64 of the full size, rounded down: the resolution does not flicker with
  // every frame's noise.
  const double stepped = std::floor(fit * 64.0) / 64.0;
  return std::clamp(stepped, most / Quality::kMaxInteractiveReduction, most);
}

uint32_t Session::in_flight() const {
  std::lock_guard lock(m_);
  return uint32_t(outstanding_.size());
}

std::string Session::volume_id() const {
  std::lock_guard lock(m_);
  return volume_ ? volume_->id : "";
}

nlohmann::json Session::state_json() const {
  std::lock_guard lock(m_);
  Scene full = scene_;  // every render setting, defaults included: what the client shows and restores
  full.render = parse_scene({{"volume", "x"}, {"render", render_json_}}).render;
  full.render.ray_texture = ray_texture_;
  nlohmann::json s = scene_to_json(full);
  s["image"] = {{"width", viewport_.pixel_width()}, {"height", viewport_.pixel_height()}};
  // The versions frames will echo: a client counts on from these to match frames to its input.
  s["versions"] = {{"camera", camera_version_}, {"tf", tf_version_}, {"render", render_version_}};
  return s;
}

std::optional<FrameJob> Session::take_job(Clock::time_point now, std::chrono::milliseconds still_delay,
                                          std::chrono::duration<double> min_interval, Clock::time_point& wake) {
  std::lock_guard lock(m_);
  wake = Clock::time_point::max();
  if (volume_) {
    // A preview's finer level has been read: the same world box, so the view stays; it is drawn again.
    if (auto newer = volume_->newer()) {
      while (auto next = newer->newer()) newer = std::move(next);
      volume_ = std::move(newer);
      final_pending_ = true;  // at rest: a final frame of it, no interactive one
      cancel_refinement();
    }
  }
  if (!volume_ || !(dirty_ || final_pending_)) return std::nullopt;
  if (int(outstanding_.size()) >= limits::kMaxFramesInFlight) return std::nullopt;  // an ack wakes us
  const bool quiet = now - last_input_ >= still_delay;
  const auto next_allowed = last_frame_ + std::chrono::duration_cast<Clock::duration>(min_interval);
  if (!quiet) {
    if (!dirty_) {  // interactive frame already shows the newest state: wait for the still
      wake = last_input_ + still_delay;
      return std::nullopt;
    }
    if (now < next_allowed) {
      wake = std::min(next_allowed, last_input_ + still_delay);
      return std::nullopt;
    }
  }
  FrameJob job;
  job.final = quiet;
  job.volume = volume_;
  job.quality = quality_;
  try {
    job.scene = resolve();
  } catch (const std::exception&) {
    dirty_ = final_pending_ = false;  // validated on input; nothing renderable
    return std::nullopt;
  }
  if (!job.final && quality_.codec != "jpeg") {
    // Video: one coded size per view (the view at interactive_scale); frames the budget renders
    // smaller are scaled up to it, so only a resize or a setting starts a new stream.
    job.video = video_;
    auto& v = job.video_settings;
    v.codec = *encode::video_codec_from_name(quality_.codec);
    std::tie(v.width, v.height) =
        video_coded_size(job.scene.scene.width, job.scene.scene.height, quality_.interactive_scale);
    v.kbps = quality_.kbps;
    v.quality = quality_.interactive_quality;
  }
  if (!job.final) {  // reduced resolution and coarser sampling while the input moves
    const double scale = interactive_scale(job.scene.scene.width, job.scene.scene.height);
    job.scene.scene.width = std::max(1, int(job.scene.scene.width * scale));
    job.scene.scene.height = std::max(1, int(job.scene.scene.height * scale));
    // Uniform: twice the step. Differential: the footprint of the smaller image already makes
    // the steps 1 / interactive_scale longer (s_k counts pixels), so s_k stays.
    if (job.scene.scene.render.sampling != Sampling::Differential) job.scene.step *= 2.0;
  }
  job.frame_id = next_frame_id_++;
  job.camera_version = camera_version_;
  job.tf_version = tf_version_;
  job.render_version = render_version_;
  job.input_time = last_input_;
  outstanding_.insert(job.frame_id);
  last_frame_ = now;
  dirty_ = false;
  if (job.final) final_pending_ = false;
  if (job.final && full_statistics_ && volume_->full) {
    auto refine = std::make_shared<FrameJob::Refinement>();
    try {
      refine->scene = resolve(&full_statistics_->box);
    } catch (const std::exception&) {
      return job;  // the held level's frame goes alone
    }
    refine->statistics = full_statistics_;
    refine->cancelled = refinement_cancelled_;
    job.refine = std::move(refine);
  }
  return job;
}

}  // namespace peakcast
