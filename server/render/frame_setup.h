// What every backend derives from a scene before it draws, on the host: the TF's peaks, the
// macrocell occupancy (cached on the TF), the variant, and the per-TF tables (the TF baked for
// the scene's step, the peak table in TF coordinates, the preintegration table). The GL
// backend uploads them (gpu/gl_renderer.cpp, gpu/gl_renderer_tables.cpp); the CPU backend reads them.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec4.hpp>

#include "core/occupancy.h"
#include "core/peaks.h"
#include "core/preintegration.h"
#include "core/scene.h"
#include "render/resident_volume.h"
#include "render/variant.h"

namespace peakcast::render {

// Everything a per-TF table depends on: the points, the opacity unit and the value range.
std::string tf_signature(const TransferFunction& tf, double lo, double hi);

// Occupancy of one volume's grid under one TF, most recently used first.
class OccupancyCache {
 public:
  // The entry named `key`, built by `build` when absent (counted in `builds`).
  const Occupancy& get(const std::string& key, const std::function<Occupancy()>& build, size_t& builds);

 private:
  struct Entry {
    std::string key;
    std::shared_ptr<const Occupancy> occupancy;
  };
  std::vector<Entry> entries_;
};

struct FrameSetup {
  VariantKey key;
  std::vector<Peak> peaks;               // of the TF (classification peaks), even where the variant finds none
  const Occupancy* occupancy = nullptr;  // never null; no empty cells without space skipping
  std::string occupancy_key;             // empty when the frame does not skip space
  std::string tf_sig;
  double table_ms = 0.0;  // peaks and occupancy built for this frame
};

// How a renderer sets up its frames. The product keeps these defaults; the subclasses of tests
// and peakcast-bench (render/renderer_switches.h) change them to show what each choice saves or
// prevents.
struct SetupOptions {
  bool leaps = true;           // leap by the empty-space distance (off: step through every empty cell)
  double vs_widening = 0.125;  // cells' value ranges widened for virtual samples (kCatmullRomOvershoot)
  std::function<void(VariantKey&)> force_variant;  // a change to every frame's chosen variant
};

FrameSetup setup_frame(const ResidentVolume& volume, const ResolvedScene& s, RenderPath path, const SetupOptions& o,
                       OccupancyCache& cache, size_t& builds);

// The empty-space distance per cell a traversal reads: the occupancy's, or, with leaps off
// (SetupOptions::leaps), at most 1 so that every empty cell is stepped through.
std::vector<uint8_t> traversal_distances(const Occupancy& occupancy, bool leaps);

// The TF as TransferFunction::kTableSize entries over [lo, hi]: colour, and in the fourth channel
// the transparency of the scene's uniform step, T = (1 - a)^(step / unit) (VTK's mappers bake the
// opacity 1 - T likewise): a sample that stands for that step composites 1 - T, others correct
// from it, 1 - T^(dt / step) (shaders/ray/compositing.glsl step_opacity). Kept as a transparency, so that a step
// opaque to float precision (1 - T rounds to 1) still corrects to a short chord's opacity (a
// ray's first and last samples, virtual samples). The key names the table (the TF signature and
// the exponent).
std::string step_tf_key(const ResolvedScene& s, const std::string& tf_sig);
std::vector<float> step_tf_table(const ResolvedScene& s, double lo, double hi);

// What the peak and preintegration tables depend on (a camera move reuses them).
std::string tables_key(const ResolvedScene& s, double lo, double hi, size_t peak_count);
// The peak table's texels in TF coordinates, kNoPeakTexel where there is no peak.
std::vector<float> peak_texels(const PeakTable& table, double lo, double hi);
// Per TF point: (value in TF coordinates, 0, 0, 0), then (r, g, b, a).
std::vector<glm::vec4> tf_point_pairs(const TransferFunction& tf, double lo, double hi);
// Per macrocell, (min, max) of its values in TF coordinates, widened outward by a few roundings
// so that a sample computed in float inside the cell never lies outside: what a maximum or
// minimum projection skips by (shaders/ray/projection.glsl). Grid order.
std::vector<glm::vec2> cell_ranges(const MacrocellGrid& cells, double lo, double hi);
// The preintegration table for the scene's step.
PreintegrationTable scene_preintegration(const ResolvedScene& s, double lo, double hi);

}  // namespace peakcast::render
