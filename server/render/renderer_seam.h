// A renderer's test seam: what tests and benchmarks switch to show what the product's choices
// save or prevent. Only tests and peakcast-bench include this; the product never does.
#pragma once

#include <functional>
#include <utility>

#include "render/renderer.h"

namespace peakcast::render {

class RendererSeam {
 public:
  // TF tables, peak/preintegration tables and occupancy grids built so far (tiles interleaved
  // with another session's frames must not rebuild them).
  static size_t table_builds(const Renderer& r) { return r.seam_.table_builds; }
  // How far the cells' value ranges are widened for virtual samples, as a fraction of each
  // range: Lee's 1/8 (kCatmullRomOvershoot); 0 shows the skipped-cell streaks it prevents
  // (Lee Fig. 14).
  static void set_virtual_sample_widening(Renderer& r, double fraction) { r.seam_.vs_widening = fraction; }
  // Off: the traversal steps through every empty macrocell one at a time instead of leaping by
  // the empty-space distance (the leaps must skip exactly what the steps skip).
  static void set_empty_space_leaps(Renderer& r, bool on) { r.seam_.leaps = on; }
  // Changes the variant chosen for every later frame (nullptr: none): puts back code the
  // scene's variant leaves out, to show the omission changes no pixel and to time what it
  // saves. Only features whose tables the frame builds anyway may be forced on (peaks, space
  // skipping, the differential lattice).
  static void force_variant(Renderer& r, std::function<void(VariantKey&)> change) {
    r.seam_.force_variant = std::move(change);
  }
};

}  // namespace peakcast::render
