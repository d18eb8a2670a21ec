#include "session/volume_store.h"

#include <algorithm>
#include <set>

#include "chunked/chunked_volume.h"
#include "core/length_unit.h"
#include "core/log.h"
#include "core/scene.h"
#include "distributed/brick_sequence.h"

namespace fs = std::filesystem;

namespace peakcast {

nlohmann::json VolumeEntry::info(bool with_histogram) const {
  const Volume& v = *volume;
  nlohmann::json j = {{"id", id},
                      {"name", name.empty() ? path.filename().string() : name},
                      {"uploaded", uploaded},
                      {"dims", {v.dims()[0], v.dims()[1], v.dims()[2]}},
                      {"dtype", to_string(v.source_type())},
                      {"spacing", {v.spacing.x, v.spacing.y, v.spacing.z}},
                      // spacing and origin's unit ("µm"); "units" when the file names none
                      {"units", v.unit.empty() ? kNoUnit : v.unit},
                      {"origin", {v.origin.x, v.origin.y, v.origin.z}},
                      {"range", {v.min_value, v.max_value}},
                      {"bytes", v.byte_size()},
                      {"resident_bytes", resident_bytes},
                      {"load_ms", v.load_ms},
                      // Where loading went: reading the file (and converting), range and
                      // histogram, both macrocell grids, the GPU upload (once made).
                      {"load_phases",
                       {{"read_ms", v.load_ms - v.statistics_ms},
                        {"statistics_ms", v.statistics_ms},
                        {"macrocells_ms", macrocells.build_ms}}},
                      {"nonfinite_replaced", v.nonfinite_replaced},
                      // a time series: how many time points, and the one these voxels are
                      {"times", v.time_points},
                      {"time", v.time_point}};
  if (const double up = upload_ms.load(); up >= 0) j["load_phases"]["upload_ms"] = up;
  if (v.pyramid_levels > 1 || v.pyramid_level > 0) {  // a chunked pyramid: the level shown
    j["level"] = v.pyramid_level;
    j["levels"] = v.pyramid_levels;
    j["full_dims"] = {v.full_dims[0], v.full_dims[1], v.full_dims[2]};
  }
  if (!owner.empty()) j["owner"] = owner;
  if (!v.value_unit.empty()) j["value_unit"] = v.value_unit;  // "HU": the CT presets' values are these
  if (!v.modality.empty()) j["modality"] = v.modality;        // a DICOM series': "CT", "MR", ...
  if (!v.description.empty()) {                               // and its SeriesDescription
    j["description"] = v.description;
    if (name.empty()) j["name"] = v.name + " (" + v.description + ")";
  }
  if (with_histogram) j["histogram"] = v.histogram;
  return j;
}

VolumeStore::VolumeStore(std::vector<fs::path> dirs, Residency& residency, LoadOptions options, VolumeLoader loader)
    : dirs_(std::move(dirs)),
      residency_(residency),
      options_(options),
      loader_(std::move(loader)),
      in_process_(!loader_) {
  if (!loader_)
    loader_ = [](const fs::path& path, const LoadOptions& o) {
      auto v = std::make_shared<Volume>(load_volume(path, o));
      const auto bytes = int64_t(v->byte_size());
      return LoadedVolume{std::move(v), bytes};
    };
}

std::shared_ptr<VolumeEntry> VolumeStore::add(const std::string& id, const fs::path& path, bool preloaded,
                                              const std::string& upload_name, std::function<void(double)> progress,
                                              const LoadOptions* given, const std::string& owner, int64_t time) {
  std::lock_guard load(load_m_);
  const std::string key = key_of(id, time);
  if (auto e = find(key)) return e;
  auto e = std::make_shared<VolumeEntry>();
  e->id = id;
  e->time = time;
  e->path = path;
  e->uploaded = !upload_name.empty();
  e->name = upload_name;
  e->owner = owner;
  LoadOptions options = given ? *given : options_;
  options.progress = std::move(progress);
  options.time_point = time;
  int finer = -1;  // a preview: the level within the budget, read after
  if (in_process_ && preview_voxels_ > 0 && options.memory_budget_bytes > 0 && chunked::is_chunked_volume(path)) {
    const auto cv = chunked::open_chunked(path, {options.time_point, options.channel});
    const int held = chunked::finest_level_within(*cv, options.level, options.memory_budget_bytes);
    const int preview = chunked::finest_level_of_voxels(*cv, held, preview_voxels_);
    if (preview > held) {
      finer = held;
      options.level = preview;
      options.memory_budget_bytes = 0;  // that level, as asked
    }
  }
  LoadedVolume loaded = loader_(path, options);
  e->volume = std::move(loaded.volume);
  e->resident_bytes = loaded.resident_bytes;
  e->preloaded = preloaded;
  finish_entry(e);
  std::lock_guard lock(m_);
  entries_[key] = e;
  if (default_.empty() && time == 0) default_ = id;
  if (finer >= 0) background_([this, e, finer] { read_finer(e, finer); });
  return e;
}

void VolumeStore::finish_entry(const std::shared_ptr<VolumeEntry>& e) {
  if (in_process_ && e->volume->pyramid_level > options_.level && options_.memory_budget_bytes > 0 && !e->full) {
    auto full = std::make_shared<FullResolution>();
    full->path = e->path;
    full->options = options_;
    full->options.level = 0;
    full->options.time_point = e->time;
    full->options.memory_budget_bytes = 0;
    full->budget_bytes = options_.memory_budget_bytes;
    e->full = std::move(full);
  }
  // The residency owns the budget; when the volume does not fit it lets the store drop volumes
  // no session views (the store holds the only reference), oldest id first.
  residency_.admit(e, [this] {
    std::lock_guard lock(m_);
    for (auto it = entries_.begin(); it != entries_.end();)
      it = !it->second->preloaded && it->second.use_count() == 1 ? entries_.erase(it) : std::next(it);
  });
  // Here, on the loader pool, not on the render thread at first use (GlVolume takes them): the
  // em volume's two grids take ~0.6 s of CPU. After admission, so a refused volume costs none.
  if (e->volume->has_voxels()) e->macrocells = build_volume_macrocells(*e->volume);
}

void VolumeStore::set_preview(int64_t voxels, std::function<void(std::function<void()>)> background) {
  preview_voxels_ = background ? voxels : 0;
  background_ = std::move(background);
}

void VolumeStore::read_finer(const std::shared_ptr<VolumeEntry>& preview, int level) {
  auto e = std::make_shared<VolumeEntry>();
  e->id = preview->id;
  e->path = preview->path;
  e->preloaded = preview->preloaded;
  e->time = preview->time;
  e->full = preview->full;  // one reduction of the finest level serves both
  try {
    LoadOptions options = options_;
    options.level = level;
    options.memory_budget_bytes = 0;
    options.time_point = e->time;
    LoadedVolume loaded = loader_(e->path, options);
    e->volume = std::move(loaded.volume);
    e->resident_bytes = loaded.resident_bytes;
    finish_entry(e);
  } catch (const std::exception& ex) {  // the preview stays: it is a picture of the same volume
    log::warn("the level within the memory budget could not be read", {{"volume", e->id}, {"error", ex.what()}});
    return;
  }
  std::lock_guard lock(m_);
  auto it = entries_.find(key_of(e->id, e->time));
  if (it == entries_.end() || it->second != preview) return;  // dropped or replaced meanwhile
  it->second = e;
  preview->set_newer(e);
}

std::shared_ptr<VolumeEntry> VolumeEntry::newer() const {
  std::lock_guard lock(newer_m_);
  return newer_;
}

void VolumeEntry::set_newer(std::shared_ptr<VolumeEntry> e) {
  std::lock_guard lock(newer_m_);
  newer_ = std::move(e);
}

std::shared_ptr<const distributed::SequenceStatistics> VolumeStore::full_statistics(VolumeEntry& entry,
                                                                                    const std::atomic<bool>& stop) {
  FullResolution& f = *entry.full;
  std::lock_guard lock(f.reduce);
  if (auto known = f.statistics()) return known;
  distributed::StatisticsRun run(f.path.string(), f.options, f.brick_budget(int64_t(entry.volume->byte_size())));
  while (!run.done()) {
    if (stop.load()) throw VolumeError(f.path, "the server is shutting down");
    run.step();
  }
  auto statistics = std::make_shared<const distributed::SequenceStatistics>(run.take());
  if (statistics->budget_too_small)  // the bricks got half their share: the reduction held more than the budget
    log::warn("memory budget too small for level 0's statistics beside their bricks", {{"path", f.path.string()}});
  f.set_statistics(std::move(statistics));
  return f.statistics();
}

std::shared_ptr<const distributed::SequenceStatistics> FullResolution::statistics() const {
  std::lock_guard lock(ready_);
  return statistics_;
}

void FullResolution::set_statistics(std::shared_ptr<const distributed::SequenceStatistics> s) {
  std::lock_guard lock(ready_);
  statistics_ = std::move(s);
}

std::shared_ptr<VolumeEntry> VolumeStore::preload(const fs::path& path) {
  std::string id = path.stem().string();
  if (auto e = find(id); e && e->path != path) id = path.parent_path().filename().string() + "/" + id;
  return add(id, path, true);
}

std::shared_ptr<VolumeEntry> VolumeStore::get(const std::string& id_or_path, std::function<void(double)> progress) {
  if (auto e = find(id_or_path)) return e;
  {
    std::unique_lock lock(m_);
    if (auto u = uploads_.find(id_or_path); u != uploads_.end()) {
      const Upload up = u->second;
      lock.unlock();
      return add(id_or_path, up.path, false, up.name, std::move(progress), nullptr, up.owner);
    }
    if (deleted_.count(id_or_path))
      throw VolumeError(id_or_path, "this upload was deleted (DELETE /api/volumes/" + id_or_path +
                                        "); upload the data again for a new id");
  }
  const fs::path resolved = resolve_in_roots(id_or_path, dirs_);
  {
    std::lock_guard lock(m_);
    for (auto& [_, e] : entries_)
      if (e->path == resolved && e->time == 0) return e;
  }
  // A volume's id is never a server path: one asked for by absolute path is known by its path
  // inside the data directory that holds it.
  std::string id = id_or_path;
  if (fs::path(id_or_path).is_absolute())
    for (const fs::path& d : dirs_) {
      std::error_code ec;
      const fs::path rel = resolved.lexically_relative(fs::weakly_canonical(d, ec));
      if (!ec && !rel.empty() && *rel.begin() != "..") {
        id = rel.generic_string();
        break;
      }
    }
  if (auto e = find(id)) return e;
  try {
    return add(id, resolved, false, "", std::move(progress));
  } catch (const VolumeError& e) {
    // Clients see what they asked for, never where it lies on the server.
    throw VolumeError(id_or_path, without_paths(e.what(), resolved, id_or_path));
  }
}

// `message` with the server's paths of `resolved` (the file, its folder) and of the data
// directories replaced by what the client asked for, and the "file: " prefix dropped.
std::string VolumeStore::without_paths(std::string message, const fs::path& resolved, const std::string& asked) const {
  const std::string prefix = resolved.string() + ": ";
  if (message.rfind(prefix, 0) == 0) message = message.substr(prefix.size());
  auto replace_all = [&](const std::string& from, const std::string& to) {
    if (from.empty()) return;
    for (size_t at = 0; (at = message.find(from, at)) != std::string::npos; at += to.size())
      message.replace(at, from.size(), to);
  };
  replace_all(resolved.string(), asked);
  for (const fs::path& d : dirs_) {
    replace_all(fs::weakly_canonical(d).string() + "/", "");
    replace_all(d.string() + "/", "");
  }
  return message;
}

std::string VolumeStore::key_of(const std::string& id, int64_t time) {
  return time == 0 ? id : id + "\x1ft" + std::to_string(time);  // \x1f: never in an id
}

LoadOptions VolumeStore::options_of(const VolumeEntry& base) const {
  LoadOptions o = options_;
  o.single_file = base.uploaded;  // an upload is one file (session/upload_store.cpp)
  return o;
}

std::shared_ptr<VolumeEntry> VolumeStore::find_time(const std::string& id, int64_t time) const {
  return find(key_of(id, time));
}

std::shared_ptr<VolumeEntry> VolumeStore::at_time(const std::string& id_or_path, int64_t time,
                                                  std::function<void(double)> progress) {
  auto base = get(id_or_path, time == 0 ? progress : nullptr);
  if (time == 0) return base;
  if (const std::string why = time_refusal(time, base->volume->time_points); !why.empty()) throw SceneError(why);
  if (auto e = find(key_of(base->id, time))) return e;
  try {
    const LoadOptions o = options_of(*base);
    return add(base->id, base->path, false, base->uploaded ? base->name : "", std::move(progress), &o, base->owner,
               time);
  } catch (const VolumeError& e) {
    throw VolumeError(base->id,
                      "time point " + std::to_string(time) + ": " + without_paths(e.what(), base->path, base->id));
  }
}

void VolumeStore::read_ahead(const std::string& id, int64_t time, int count) {
  const auto base = find(id);
  if (!base || base->volume->time_points < 2 || count < 1) return;
  const int64_t n = base->volume->time_points;
  count = int(std::min<int64_t>(count, n - 1));
  std::set<std::string> window;
  for (int k = 0; k <= count; ++k) window.insert(key_of(id, (time + k) % n));
  auto fits = [&] { return residency_.counted_bytes() + base->resident_bytes <= residency_.budget(); };
  for (int k = 1; k <= count; ++k) {
    const int64_t t = (time + k) % n;
    if (t == 0 || find(key_of(id, t))) continue;
    if (!fits()) {  // let go of the series' time points outside the window that nobody views
      std::lock_guard lock(m_);
      const std::string prefix = id + "\x1ft";
      for (auto it = entries_.begin(); it != entries_.end();)
        it = it->first.rfind(prefix, 0) == 0 && !window.count(it->first) && it->second.use_count() == 1
                 ? entries_.erase(it)
                 : std::next(it);
    }
    if (!fits()) return;  // the budget is full of what is viewed or ahead
    try {
      const LoadOptions o = options_of(*base);
      add(base->id, base->path, false, base->uploaded ? base->name : "", {}, &o, base->owner, t);
    } catch (const std::exception& e) {
      log::warn("a time point could not be read ahead", {{"volume", id}, {"time", t}, {"error", e.what()}});
      return;
    }
  }
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

nlohmann::json VolumeStore::listing() const {
  std::lock_guard lock(m_);
  nlohmann::json out = nlohmann::json::array();
  for (auto& [_, e] : entries_)
    if (e->time == 0) out.push_back(e->info(false));  // a series once, as its time point 0
  for (auto& [id, u] : uploads_)
    if (!entries_.count(id)) out.push_back(u.info);
  return out;
}

std::shared_ptr<VolumeEntry> VolumeStore::add_upload(const std::string& id, const fs::path& path,
                                                     const std::string& name, const std::string& owner,
                                                     const LoadOptions& options) {
  auto e = add(id, path, false, name, {}, &options, owner);
  std::lock_guard lock(m_);
  uploads_[id] = Upload{path, name, owner, e->info(false)};
  return e;
}

void VolumeStore::register_upload(const std::string& id, const fs::path& path, const std::string& name,
                                  const std::string& owner, nlohmann::json info) {
  std::lock_guard lock(m_);
  uploads_[id] = Upload{path, name, owner, std::move(info)};
}

void VolumeStore::remove_upload(const std::string& id) {
  std::lock_guard lock(m_);
  if (uploads_.erase(id)) {
    if (deleted_.size() >= 65536) deleted_.clear();  // a bound on what is remembered
    deleted_.insert(id);
  }
  for (auto it = entries_.begin(); it != entries_.end();)  // with its other time points
    it = it->second->id == id ? entries_.erase(it) : std::next(it);
  if (default_ == id) default_ = entries_.empty() ? "" : entries_.begin()->first;
}

bool VolumeStore::known(const std::string& id) const {
  std::lock_guard lock(m_);
  return entries_.count(id) || uploads_.count(id);
}

std::string VolumeStore::default_id() const {
  std::lock_guard lock(m_);
  return default_;
}

}  // namespace peakcast
