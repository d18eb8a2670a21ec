#include "session/volume_store.h"

#include <algorithm>

namespace fs = std::filesystem;

namespace peakcast {

nlohmann::json VolumeEntry::info(bool with_histogram) const {
  const Volume& v = *volume;
  nlohmann::json j = {{"id", id},
                      {"name", path.filename().string()},
                      {"dims", {v.dims()[0], v.dims()[1], v.dims()[2]}},
                      {"dtype", to_string(v.source_type())},
                      {"spacing", {v.spacing.x, v.spacing.y, v.spacing.z}},
                      {"origin", {v.origin.x, v.origin.y, v.origin.z}},
                      {"range", {v.min_value, v.max_value}},
                      {"bytes", v.byte_size()},
                      {"load_ms", v.load_ms},
                      {"nonfinite_replaced", v.nonfinite_replaced}};
  if (with_histogram) j["histogram"] = v.histogram;
  return j;
}

VolumeStore::VolumeStore(std::vector<fs::path> dirs, int64_t budget, LoadOptions options)
    : dirs_(std::move(dirs)), budget_(budget), options_(options) {}

std::shared_ptr<VolumeEntry> VolumeStore::add(const std::string& id, const fs::path& path, bool preloaded) {
  std::lock_guard load(load_m_);
  if (auto e = find(id)) return e;
  // Header-sized check first would need every format's header reader; loading is bounded by the
  // voxel limit, and the budget is checked before the volume is kept.
  auto vol = std::make_shared<Volume>(load_volume(path, options_));
  // Here, on the loader pool, not at first render: the em volume's grids take ~1 s of CPU.
  VolumeMacrocells cells = build_volume_macrocells(*vol);
  const int64_t bytes = int64_t(vol->byte_size());
  std::lock_guard lock(m_);
  int64_t resident = 0;
  for (auto& [_, e] : entries_) resident += int64_t(e->volume->byte_size());
  if (resident + bytes > budget_) {
    // Drop volumes no session uses (the store holds the only reference), oldest id first.
    for (auto it = entries_.begin(); it != entries_.end() && resident + bytes > budget_;) {
      if (!it->second->preloaded && it->second.use_count() == 1) {
        resident -= int64_t(it->second->volume->byte_size());
        it = entries_.erase(it);
      } else {
        ++it;
      }
    }
  }
  if (resident + bytes > budget_)
    throw VolumeError(path, "GPU memory budget: this volume needs " + std::to_string(bytes >> 20) +
                                " MiB, " + std::to_string(resident >> 20) + " MiB of " + std::to_string(budget_ >> 20) +
                                " MiB are in use by volumes that sessions are viewing");
  auto e = std::make_shared<VolumeEntry>();
  e->id = id;
  e->path = path;
  e->volume = std::move(vol);
  e->macrocells = std::move(cells);
  e->preloaded = preloaded;
  entries_[id] = e;
  if (default_.empty()) default_ = id;
  return e;
}

std::shared_ptr<VolumeEntry> VolumeStore::preload(const fs::path& path) {
  std::string id = path.stem().string();
  if (auto e = find(id); e && e->path != path) id = path.parent_path().filename().string() + "/" + id;
  return add(id, path, true);
}

std::shared_ptr<VolumeEntry> VolumeStore::get(const std::string& id_or_path) {
  if (auto e = find(id_or_path)) return e;
  const fs::path resolved = resolve_in_roots(id_or_path, dirs_);
  {
    std::lock_guard lock(m_);
    for (auto& [_, e] : entries_)
      if (e->path == resolved) return e;
  }
  return add(id_or_path, resolved, false);
}

std::shared_ptr<VolumeEntry> VolumeStore::find(const std::string& id) const {
  std::lock_guard lock(m_);
  auto it = entries_.find(id);
  return it == entries_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<VolumeEntry>> VolumeStore::list() const {
  std::lock_guard lock(m_);
  std::vector<std::shared_ptr<VolumeEntry>> out;
  for (auto& [_, e] : entries_) out.push_back(e);
  return out;
}

std::string VolumeStore::default_id() const {
  std::lock_guard lock(m_);
  return default_;
}

int64_t VolumeStore::resident_bytes() const {
  std::lock_guard lock(m_);
  int64_t total = 0;
  for (auto& [_, e] : entries_) total += int64_t(e->volume->byte_size());
  return total;
}

}  // namespace peakcast
