#include "session/residency.h"

#include <algorithm>
#include <string>

#include "render/renderer.h"
#include "session/volume_store.h"

namespace peakcast {

Residency::Residency(int64_t budget_bytes) : budget_(budget_bytes) {}

Residency::~Residency() = default;

int64_t Residency::count_locked() const {
  admitted_.erase(std::remove_if(admitted_.begin(), admitted_.end(), [](auto& w) { return w.expired(); }),
                  admitted_.end());
  int64_t total = 0;
  for (auto& w : admitted_)
    if (auto e = w.lock()) total += e->resident_bytes;
  return total;
}

void Residency::admit(const std::shared_ptr<VolumeEntry>& e, const std::function<void()>& release_unused) {
  const int64_t bytes = e->resident_bytes;
  if (bytes > budget_)
    throw VolumeError(e->path, "GPU memory budget: this volume needs " + std::to_string(bytes >> 20) +
                                   " MiB, more than the whole budget of " + std::to_string(budget_ >> 20) + " MiB");
  bool fits;
  {
    std::lock_guard lock(m_);
    fits = count_locked() + bytes <= budget_;
  }
  if (!fits && release_unused) release_unused();
  std::lock_guard lock(m_);
  const int64_t in_use = count_locked();
  if (in_use + bytes > budget_)
    throw VolumeError(e->path, "GPU memory budget: this volume needs " + std::to_string(bytes >> 20) + " MiB, " +
                                   std::to_string(in_use >> 20) + " MiB of " + std::to_string(budget_ >> 20) +
                                   " MiB are in use by volumes that sessions are viewing");
  admitted_.push_back(e);
}

int64_t Residency::counted_bytes() const {
  std::lock_guard lock(m_);
  return count_locked();
}

size_t Residency::counted_volumes() const {
  std::lock_guard lock(m_);
  count_locked();
  return admitted_.size();
}

render::ResidentVolume& Residency::acquire(const std::shared_ptr<VolumeEntry>& e, render::Renderer& renderer) {
  for (auto it = copies_.begin(); it != copies_.end();)
    it = it->second.entry.expired() ? copies_.erase(it) : std::next(it);
  auto& c = copies_[e.get()];
  if (!c.gpu) {
    c.entry = e;
    c.gpu = renderer.make_resident(e->volume, e->macrocells);  // grids built by the loader
    // The host voxels stay: probes read them on the loader pool, at any time (ws_probe.cpp,
    // rest_routes.cpp). The GL texture is in the GPU's own memory, and the CPU backend reads
    // the voxels where they lie (docs/operations.md, "Host memory"). Only a distributed copy
    // lets the whole volume go: its voxels are the ranks' bricks, and probes are refused there.
    if (c.gpu->voxels_elsewhere()) c.gpu->drop_host_voxels();
    e->upload_ms = c.gpu->upload_ms();
  }
  return *c.gpu;
}

int64_t Residency::gpu_bytes() const {
  int64_t total = 0;
  for (auto& [_, c] : copies_) total += int64_t(c.gpu->resident_bytes());
  return total;
}

size_t Residency::gpu_volumes() const { return copies_.size(); }

void Residency::release_gpu() { copies_.clear(); }

}  // namespace peakcast
