// The ray-cast shader variant for a scene (docs/architecture.md, "leave out what a scene does
// not need"). Derived from the scene, never set by hand; reported in the frame stats.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/scene.h"

namespace peakcast::render {

enum class RenderPath { Fragment, Compute };

struct VariantKey {
  RenderPath path = RenderPath::Fragment;
  bool cpu = false;  // drawn by the CPU backend (cpu/): its name starts "cpu" instead of the GL path
  bool tricubic = false;
  bool shading = false;
  bool space_skipping = false;  // only when the TF leaves some macrocell empty
  bool orthographic = false;
  bool differential = false;  // Knoll §5, perspective cameras only (orthographic: uniform at the footprint)
  bool adaptive = false;      // Knoll §6.2 per-macrocell step multipliers (brings the cell traversal)
  int virtual_samples = 0;    // Lee 2010: 0, 3 or 7 Catmull-Rom samples between true ones
  bool peaks = false;         // peak finding between samples
  PeakMode peak_mode = PeakMode::DvrPlusPeaks;
  bool preintegration = false;
  // An intensity projection (shaders/ray/projection.glsl kProjection*: 1 max, 2 min, 3 mean), or 0.
  int projection = 0;
  // A maximum or minimum projection skips the cells that cannot change it (it reads their value
  // ranges, render::cell_ranges): shaders/ray/projection.glsl projection_skips.
  bool projection_skips() const { return (projection == 1 || projection == 2) && virtual_samples == 0; }
  bool rgb8 = false;                // output quantised to 8-bit RGB on the GPU (RenderOutput::Rgb8)
  bool ray_texture = false;         // Raspe 2008 per-ray controls (any render.ray_texture)
  bool ray_texture_volume = false;  // ... indexed by the entry point (else by the pixel)
  // Distributed rendering (render/brick.h): one brick's part of each ray, premultiplied, no
  // background. Set by render_brick, never chosen from a scene.
  bool brick = false;

  std::vector<std::string> defines() const;
  std::string name() const;  // e.g. "frag+tricubic+skip", "cpu+trilinear+preint"
};

// What this build renders; the server's welcome lists it so clients build their controls from it.
nlohmann::json capabilities();

// peak_count: peaks of the scene's TF (no peaks -> no peak-finding code).
VariantKey choose_variant(const ResolvedScene& scene, int64_t empty_cells, RenderPath path, size_t peak_count = 0);

}  // namespace peakcast::render
