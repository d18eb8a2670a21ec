#include "session/scheduler.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace peakcast {

double estimated_samples_per_ray(const ResolvedScene& s) {
  const double diagonal = glm::length(s.box_max - s.box_min);
  const double step = s.step > 0 ? s.step : 1.0;
  return std::max(1.0, std::floor(diagonal / step) + 1.0);
}

double estimated_still_samples(const ResolvedScene& s) {
  return double(s.scene.width) * double(s.scene.height) * estimated_samples_per_ray(s);
}

Scheduler::Scheduler(SchedulerOptions options) : options_(options) {}

void Scheduler::add_session(const std::shared_ptr<Session>& s) {
  {
    std::lock_guard lock(m_);
    sessions_[s->id()] = s;
    wake_ = true;
  }
  cv_.notify_all();
}

void Scheduler::remove_session(const std::string& id) {
  std::lock_guard lock(m_);
  if (const auto it = sessions_.find(id); it != sessions_.end()) {
    if (const auto s = it->second.lock()) s->leave();
    sessions_.erase(it);
  }
}

size_t Scheduler::session_count() const {
  std::lock_guard lock(m_);
  return sessions_.size();
}

void Scheduler::notify() {
  {
    std::lock_guard lock(m_);
    wake_ = true;
  }
  cv_.notify_all();
}

bool Scheduler::submit_still(StillJob job) {
  {
    std::lock_guard lock(m_);
    if (stopping_) return false;
    // Refinements: one live per viewer (a stale one waits, cancelled, for the render thread to
    // answer it). Scripts' stills: max_queued_stills, whatever refinements wait beside them.
    const auto is_script = [](const auto& w) { return !w->job.refinement(); };
    if (job.refinement()) {
      for (const auto& w : stills_)
        if (w->job.refinement_of == job.refinement_of && !w->job.cancelled->load()) return false;
    } else if (size_t(std::count_if(stills_.begin(), stills_.end(), is_script)) >= options_.max_queued_stills) {
      return false;
    }
    auto w = std::make_shared<StillWork>();
    w->job = std::move(job);
    w->id = next_still_++;
    w->queued = Clock::now();
    const ResolvedScene& s = w->job.scene;
    const double per_row = std::max(1.0, double(s.scene.width) * estimated_samples_per_ray(s));
    w->band_rows = int(std::clamp(std::floor(options_.band_samples / per_row), 1.0, double(s.scene.height)));
    stills_.push_back(std::move(w));
    wake_ = true;
  }
  cv_.notify_all();
  return true;
}

size_t Scheduler::stills_pending() const {
  std::lock_guard lock(m_);
  return stills_.size();
}

std::vector<StillJob> Scheduler::shut_down() {
  std::vector<StillJob> out;
  {
    std::lock_guard lock(m_);
    stopping_ = true;
    // The band being rendered now belongs to the render thread: it sees the flag and answers it.
    for (auto& w : stills_) {
      if (w == rendering_)
        w->job.cancelled->store(true);
      else
        out.push_back(std::move(w->job));
    }
    stills_.clear();
    sessions_.clear();
  }
  cv_.notify_all();
  return out;
}

bool Scheduler::shutting_down() const {
  std::lock_guard lock(m_);
  return stopping_;
}

std::shared_ptr<StillWork> Scheduler::current_still(std::vector<StillJob>& cancelled) {
  while (!stills_.empty() && stills_.front()->job.cancelled->load()) {
    cancelled.push_back(std::move(stills_.front()->job));
    stills_.pop_front();
  }
  // Queued stills whose clients left are answered now too, not when their turn comes.
  for (auto it = stills_.begin(); it != stills_.end();) {
    if ((*it)->job.cancelled->load()) {
      cancelled.push_back(std::move((*it)->job));
      it = stills_.erase(it);
    } else {
      ++it;
    }
  }
  return stills_.empty() ? nullptr : stills_.front();
}

std::optional<FrameJob> Scheduler::take_session_job(Clock::time_point now, std::shared_ptr<Session>& session,
                                                    Clock::time_point& next_wake) {
  const auto min_interval =
      std::chrono::duration<double>(options_.max_fps > 0 ? 1.0 / std::max(1.0, options_.max_fps) : 0.0);
  std::vector<std::shared_ptr<Session>> live;
  for (auto it = sessions_.begin(); it != sessions_.end();) {
    if (auto s = it->second.lock()) {
      live.push_back(std::move(s));
      ++it;
    } else {
      it = sessions_.erase(it);
    }
  }
  for (size_t k = 0; k < live.size(); ++k) {
    auto& s = live[(rr_ + k) % live.size()];
    Clock::time_point wake;
    auto job = s->take_job(now, options_.still_delay, min_interval, wake);
    next_wake = std::min(next_wake, wake);
    if (job) {
      session = s;
      rr_ = (rr_ + k + 1) % live.size();
      return job;
    }
  }
  return std::nullopt;
}

std::optional<Scheduler::Work> Scheduler::next(bool wait) {
  std::unique_lock lock(m_);
  for (;;) {
    if (stopping_) return std::nullopt;
    wake_ = false;
    Work w;
    auto still = current_still(w.cancelled);
    // Alternate: after a viewer's frame, one band of the current still (if any); otherwise the
    // next viewer with work, and a band only when no viewer has one.
    Clock::time_point next_wake = Clock::time_point::max();
    if (!(still && last_was_session_)) {
      w.frame = take_session_job(Clock::now(), w.session, next_wake);
      if (w.frame) {
        last_was_session_ = true;
        return w;
      }
    }
    if (still) {
      if (still->next_row == 0 && still->bands == 0) {
        still->started = Clock::now();
        still->image = Image(still->job.scene.scene.width, still->job.scene.scene.height);
      }
      w.still = still;
      rendering_ = still;
      w.y0 = still->next_row;
      w.rows = std::min(still->band_rows, still->job.scene.scene.height - still->next_row);
      last_was_session_ = false;
      return w;
    }
    if (!w.cancelled.empty()) return w;  // nothing to render, but stills to answer
    last_was_session_ = false;
    if (!wait) return std::nullopt;
    if (next_wake == Clock::time_point::max())
      cv_.wait(lock, [&] { return stopping_ || wake_; });
    else
      cv_.wait_until(lock, next_wake, [&] { return stopping_ || wake_; });
  }
}

void Scheduler::band_done(const std::shared_ptr<StillWork>& still) {
  std::lock_guard lock(m_);
  rendering_.reset();
  if (!still->complete()) return;
  auto it = std::find(stills_.begin(), stills_.end(), still);
  if (it != stills_.end()) stills_.erase(it);
}

void Scheduler::still_failed(const std::shared_ptr<StillWork>& still) {
  std::lock_guard lock(m_);
  rendering_.reset();
  auto it = std::find(stills_.begin(), stills_.end(), still);
  if (it != stills_.end()) stills_.erase(it);
}

}  // namespace peakcast
