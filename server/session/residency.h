// The one owner of the GPU memory budget for volumes. The volume store asks it
// before keeping a volume (admit, on the loader pool); the render thread asks it for a volume's
// GPU copy (acquire), made on first use and freed once nobody holds the volume any more. A volume
// counts against the budget from admission until the last session viewing it lets go.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

namespace peakcast {

struct VolumeEntry;
namespace render {
class Renderer;
class ResidentVolume;
}  // namespace render

class Residency {
 public:
  explicit Residency(int64_t budget_bytes);
  ~Residency();
  Residency(const Residency&) = delete;
  Residency& operator=(const Residency&) = delete;

  int64_t budget() const { return budget_; }
  // Any thread. Counts `e` against the budget. When it does not fit, `release_unused` is called
  // once (without locks held) to let the store drop volumes nobody views; then the count is taken
  // again. Throws VolumeError naming the budget when it still does not fit.
  void admit(const std::shared_ptr<VolumeEntry>& e, const std::function<void()>& release_unused);
  int64_t counted_bytes() const;  // admitted volumes somebody still holds
  size_t counted_volumes() const;

  // Render thread only: the volume's copy for `renderer`'s backend (made on first use: the
  // texture upload, or the CPU backend's view). Copies of volumes nobody holds any more are
  // freed first. One renderer per residency.
  render::ResidentVolume& acquire(const std::shared_ptr<VolumeEntry>& e, render::Renderer& renderer);
  int64_t gpu_bytes() const;   // render thread: bytes the backend's copies hold besides the volumes
  size_t gpu_volumes() const;  // render thread
  void release_gpu();          // render thread, before its GL context goes

 private:
  int64_t count_locked() const;  // prunes expired entries first
  const int64_t budget_;
  mutable std::mutex m_;
  mutable std::vector<std::weak_ptr<VolumeEntry>> admitted_;
  struct Copy {
    std::weak_ptr<VolumeEntry> entry;
    std::unique_ptr<render::ResidentVolume> gpu;
  };
  std::map<const VolumeEntry*, Copy> copies_;  // render thread only
};

}  // namespace peakcast
