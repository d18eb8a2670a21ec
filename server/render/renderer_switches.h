// What tests and peakcast-bench switch on a renderer to show what the product's choices save or
// prevent: a subclass of the product's renderer (Switchable<gpu::GlRenderer>, and the like), made
// by the test fixture or the benchmark in place of the product's. Only tests and peakcast-bench
// include this; the product never changes these choices.
#pragma once

#include <cstddef>
#include <functional>
#include <utility>

#include "render/frame_setup.h"
#include "render/variant.h"

namespace peakcast::render {

class RendererSwitches {
 public:
  virtual ~RendererSwitches() = default;
  // Off: the traversal steps through every empty macrocell one at a time instead of leaping by
  // the empty-space distance (the leaps must skip exactly what the steps skip).
  virtual void set_empty_space_leaps(bool on) = 0;
  // How far the cells' value ranges are widened for virtual samples, as a fraction of each
  // range: Lee's 1/8 (kCatmullRomOvershoot); 0 shows the skipped-cell streaks it prevents
  // (Lee Fig. 14).
  virtual void set_virtual_sample_widening(double fraction) = 0;
  // Changes the variant chosen for every later frame (nullptr: none): puts back code the
  // scene's variant leaves out, to show the omission changes no pixel and to time what it
  // saves. Only features whose tables the frame builds anyway may be forced on (peaks, space
  // skipping, the differential lattice).
  virtual void force_variant(std::function<void(VariantKey&)> change) = 0;
  // TF tables, peak/preintegration tables and occupancy grids built so far (tiles interleaved
  // with another session's frames must not rebuild them).
  virtual size_t table_builds() const = 0;
};

// The product's renderer `Base` with its switches reachable; `Interface` (a RendererSwitches)
// lets a subclass add its own (the benchmark's bare sampling loop).
template <class Base, class Interface = RendererSwitches>
class Switchable : public Base, public Interface {
 public:
  using Base::Base;
  void set_empty_space_leaps(bool on) override { this->setup_options_.leaps = on; }
  void set_virtual_sample_widening(double fraction) override { this->setup_options_.vs_widening = fraction; }
  void force_variant(std::function<void(VariantKey&)> change) override {
    this->setup_options_.force_variant = std::move(change);
  }
  size_t table_builds() const override { return this->table_builds_; }
};

}  // namespace peakcast::render
