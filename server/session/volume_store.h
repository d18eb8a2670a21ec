// The server's volumes: loaded from the configured data directories (or preloaded by the
// operator), shared by every session that views them. The GPU memory budget belongs to the
// Residency: the store asks it before keeping a volume.
#pragma once

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <functional>
#include <map>
#include <set>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/macrocells.h"
#include "core/volume.h"
#include "core/volume_io.h"
#include "session/residency.h"

namespace peakcast {
namespace distributed {
struct SequenceStatistics;
}

// A pyramid the memory budget opened at a coarser level than its finest: viewers see that level,
// while stills draw the finest one brick after another (distributed/brick_sequence.h). The whole
// volume's statistics for those bricks are reduced once, at the first such still, and kept.
struct FullResolution {
  std::filesystem::path path;
  LoadOptions options;       // level 0, the time point and channel shown
  int64_t budget_bytes = 0;  // --memory-budget-mib: the level held and level 0's bricks together
  // What level 0's bricks (a still's, the statistics') may read beside the level held: what it
  // leaves of the budget, at least a quarter of the budget.
  int64_t brick_budget(int64_t held_bytes) const { return std::max(budget_bytes - held_bytes, budget_bytes / 4); }
  std::mutex reduce;  // one reduction at a time; a second asker waits for the first's
  // Null until reduced (VolumeStore::full_statistics); never waits for a reduction.
  std::shared_ptr<const distributed::SequenceStatistics> statistics() const;
  void set_statistics(std::shared_ptr<const distributed::SequenceStatistics> s);

 private:
  mutable std::mutex ready_;
  std::shared_ptr<const distributed::SequenceStatistics> statistics_;
};

struct VolumeEntry {
  std::string id;
  std::filesystem::path path;
  std::shared_ptr<const Volume> volume;
  // Built with the volume on the loader pool; the render thread passes them to GlVolume.
  VolumeMacrocells macrocells;  // none for a distributed volume (the ranks build their bricks')
  // What the memory budget counts (Residency): the voxels this process holds for the volume.
  int64_t resident_bytes = 0;
  // The GPU upload's time, once the render thread made the copy (-1 before): the last load
  // phase, reported with the others in info().
  std::atomic<double> upload_ms{-1.0};
  bool preloaded = false;
  int64_t time = 0;                      // the time point held (Volume::time_point); the store's id is the series'
  bool uploaded = false;                 // sent by a client (POST /api/volumes); `name` is the one it gave
  std::string name;                      // empty: the file's name
  std::string owner;                     // an upload's owner (net/access.h), shown in its info; empty: none
  std::shared_ptr<FullResolution> full;  // set when the level held is not the finest
  // A preview (VolumeStore::set_preview): the entry of the finer level read since, which
  // sessions viewing this one move to (the same world box: camera and TF stay).
  std::shared_ptr<VolumeEntry> newer() const;
  void set_newer(std::shared_ptr<VolumeEntry> e);
  nlohmann::json info(bool with_histogram) const;

 private:
  mutable std::mutex newer_m_;
  std::shared_ptr<VolumeEntry> newer_;
};

class VolumeStore {
 public:
  // `loader`: how a file becomes a volume; empty: load_volume, whole (mpirun peakcast serve
  // passes the ranks' brick loader, distributed::Coordinator::load).
  VolumeStore(std::vector<std::filesystem::path> data_dirs, Residency& residency, LoadOptions options = {},
              VolumeLoader loader = {});

  // Operator-given volumes (--volume): any readable path. Throws VolumeError.
  std::shared_ptr<VolumeEntry> preload(const std::filesystem::path& path);
  // An id of a loaded volume, or a path inside a data directory (loaded now). A volume the
  // residency cannot admit within the GPU budget is refused with a VolumeError.
  // `progress` hears how much of a file being loaded now was read (LoadOptions::progress).
  std::shared_ptr<VolumeEntry> get(const std::string& id_or_path, std::function<void(double)> progress = {});
  std::shared_ptr<VolumeEntry> find(const std::string& id) const;  // nullptr when not loaded
  // Time point `time` of the volume `id_or_path` (a time series: its info's `times`): held, or
  // read now, `progress` told. The series' own entry (get) is its time point 0, read first.
  // SceneError naming `time` past its last point; VolumeError as get.
  std::shared_ptr<VolumeEntry> at_time(const std::string& id_or_path, int64_t time,
                                       std::function<void(double)> progress = {});
  std::shared_ptr<VolumeEntry> find_time(const std::string& id, int64_t time) const;  // held, or nullptr
  // Reads the `count` time points after `time` (wrapping) that are not held, each only while it
  // fits in the memory budget beside what is counted there, letting go of the series' time points
  // outside that window that nobody views when it does not. On the caller's thread (the `ahead`
  // pool); failures are logged.
  void read_ahead(const std::string& id, int64_t time, int count);
  std::vector<std::shared_ptr<VolumeEntry>> list() const;
  // What /api/volumes lists: every loaded volume's info, and the uploads not loaded now (their
  // info as it was when they were uploaded).
  nlohmann::json listing() const;
  std::string default_id() const;
  const std::vector<std::filesystem::path>& data_dirs() const { return dirs_; }
  const LoadOptions& load_options() const { return options_; }

  // Uploads (session/upload_store.h): an uploaded file read now and kept under `id`; one listed
  // again at start-up, read when first asked for; one removed (sessions viewing it keep their
  // copy until they switch).
  // `options`: the store's, as the upload store adjusted them (one file, its budget).
  std::shared_ptr<VolumeEntry> add_upload(const std::string& id, const std::filesystem::path& path,
                                          const std::string& name, const std::string& owner,
                                          const LoadOptions& options);
  void register_upload(const std::string& id, const std::filesystem::path& path, const std::string& name,
                       const std::string& owner, nlohmann::json info);
  void remove_upload(const std::string& id);
  bool known(const std::string& id) const;  // loaded, or an upload that can be
  // The finest level's statistics for entry.full's stills: reduced by bricks on the caller's
  // thread the first time (a loader-pool thread; seconds to minutes), then kept. Throws VolumeError.
  // `stop`: checked between bricks (a reduction of terabytes stops with the server).
  static std::shared_ptr<const distributed::SequenceStatistics> full_statistics(VolumeEntry& entry,
                                                                                const std::atomic<bool>& stop);
  // Pyramids whose level within the memory budget has more than `voxels` voxels open first at
  // their finest level within `voxels` (a first look in a second); the level within the budget
  // is then read by `background` and replaces it (VolumeEntry::newer). voxels 0: off.
  void set_preview(int64_t voxels, std::function<void(std::function<void()>)> background);

 private:
  std::shared_ptr<VolumeEntry> add(const std::string& id, const std::filesystem::path& path, bool preloaded,
                                   const std::string& upload_name = "", std::function<void(double)> progress = {},
                                   const LoadOptions* options = nullptr, const std::string& owner = "",
                                   int64_t time = 0);
  // entries_'s key: the id for time point 0, else the id and the time point.
  static std::string key_of(const std::string& id, int64_t time);
  LoadOptions options_of(const VolumeEntry& base) const;  // another time point's read of base's file
  std::string without_paths(std::string message, const std::filesystem::path& resolved, const std::string& asked) const;
  struct Upload {
    std::filesystem::path path;
    std::string name, owner;
    nlohmann::json info;
  };
  std::map<std::string, Upload> uploads_;
  std::set<std::string> deleted_;  // uploads removed: asked for again, they are named as deleted
  std::vector<std::filesystem::path> dirs_;
  Residency& residency_;
  LoadOptions options_;
  VolumeLoader loader_;
  bool in_process_ = false;  // the store's own loader (not the ranks'): pyramids can draw full stills
  int64_t preview_voxels_ = 0;
  std::function<void(std::function<void()>)> background_;
  // The level within the budget of a pyramid opened at `preview`, read now (background_).
  void read_finer(const std::shared_ptr<VolumeEntry>& preview, int level);
  // After the loader: the finest statistics' handle, admission, the macrocell grids.
  void finish_entry(const std::shared_ptr<VolumeEntry>& e);
  mutable std::mutex m_;
  std::mutex load_m_;  // one load at a time: a second request for the same file waits, then finds it
  std::map<std::string, std::shared_ptr<VolumeEntry>> entries_;
  std::string default_;
};

}  // namespace peakcast
