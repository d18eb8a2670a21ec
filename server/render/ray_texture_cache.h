// The ray textures of the sessions painting at once, on the host (Raspe & Müller 2008 §3.2):
// one entry per lineage and termination holding the texels of its first `strokes` strokes. A
// new lineage is built whole; new strokes of a held one are applied and only the texels they
// touched are reported, so a backend refreshes its copy by that rectangle alone. `Extra` is
// the backend's per-entry copy (the GL texture; nothing for the CPU).
#pragma once

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "core/ray_texture.h"

namespace peakcast::render {

template <class Extra>
class RayTextureCache {
 public:
  struct Entry {
    std::string key;  // lineage, termination
    size_t strokes = 0;
    RayTexture texels;
    Extra extra{};
  };
  struct Update {
    Entry* entry = nullptr;
    bool created = false;  // built whole: the backend makes its copy from scratch
    TexelRect dirty;       // texels changed since the backend's copy was made
    size_t applied = 0;    // strokes applied now
    double ms = 0.0;
  };
  static constexpr size_t kEntries = 8;  // sessions painting at once, before rebuilds
  // Host texels held before the least recently used go (a few 2048^2 textures, not eight).
  static constexpr size_t kBytes = size_t(192) << 20;

  Update get(const RayTextureSpec& spec, double termination) {
    const auto t0 = std::chrono::steady_clock::now();
    const std::string key = std::to_string(spec.lineage) + " termination " + std::to_string(termination);
    Update u;
    auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; });
    if (it != entries_.end()) {
      std::rotate(entries_.begin(), it, it + 1);
      if (entries_.front().strokes > spec.strokes.size()) entries_.erase(entries_.begin());  // an older spec: rebuilt
    }
    if (it == entries_.end() || entries_.empty() || entries_.front().key != key) {
      if (entries_.size() >= kEntries) entries_.pop_back();
      entries_.insert(entries_.begin(), Entry{key, spec.strokes.size(), build_ray_texture(spec, termination), {}});
      size_t bytes = 0;
      for (const auto& c : entries_) bytes += c.texels.texels().size() * sizeof(float);
      while (bytes > kBytes && entries_.size() > 1) {
        bytes -= entries_.back().texels.texels().size() * sizeof(float);
        entries_.pop_back();
      }
      u.created = true;
      u.dirty = {0, 0, entries_.front().texels.width(), entries_.front().texels.height()};
      u.applied = spec.strokes.size();
    } else {
      Entry& e = entries_.front();
      for (size_t i = e.strokes; i < spec.strokes.size(); ++i) u.dirty.merge(e.texels.apply(spec.strokes[i]));
      u.applied = spec.strokes.size() - e.strokes;
      e.strokes = spec.strokes.size();
    }
    u.entry = &entries_.front();
    u.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return u;
  }

 private:
  std::vector<Entry> entries_;
};

}  // namespace peakcast::render
