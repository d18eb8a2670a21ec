#include "render/frame_setup.h"

#include <algorithm>
#include <chrono>

#include "render/small_cache.h"
#include <cmath>
#include <limits>
#include <sstream>

#include "core/sampling.h"
#include "render/shader_interface.h"

namespace peakcast::render {

namespace {
constexpr size_t kOccupancyEntries = 4;  // sessions with different TFs take turns without rebuilds
}  // namespace

std::string tf_signature(const TransferFunction& tf, double lo, double hi) {
  std::ostringstream s;
  s.precision(17);
  s << lo << ' ' << hi << ' ' << tf.opacity_unit;
  for (const auto& p : tf.points) s << ' ' << p.value << ' ' << p.r << ' ' << p.g << ' ' << p.b << ' ' << p.a;
  return s.str();
}

const Occupancy& OccupancyCache::get(const std::string& key, const std::function<Occupancy()>& build, size_t& builds) {
  auto it = std::find_if(entries_.begin(), entries_.end(), [&](const Entry& e) { return e.key == key; });
  if (it != entries_.end()) {
    std::rotate(entries_.begin(), it, it + 1);
    return *entries_.front().occupancy;
  }
  if (entries_.size() >= kOccupancyEntries) entries_.pop_back();
  entries_.insert(entries_.begin(), Entry{key, std::make_shared<const Occupancy>(build())});
  ++builds;
  return *entries_.front().occupancy;
}

FrameSetup setup_frame(const ResidentVolume& gv, const ResolvedScene& s, RenderPath path, const SetupOptions& o,
                       OccupancyCache& cache, size_t& builds) {
  static const Occupancy kNoSkipping;
  FrameSetup f;
  const MacrocellGrid& cells = gv.macrocells(s.scene.render.filter);
  f.tf_sig = tf_signature(s.tf, gv.tf_lo(), gv.tf_hi());
  const auto t0 = std::chrono::steady_clock::now();
  if (s.scene.render.classification == Classification::Peaks) f.peaks = find_peaks(s.tf);
  std::vector<double> peak_values;
  for (const auto& p : f.peaks) peak_values.push_back(p.value);
  // Occupancy depends on the grid, the TF over the value range and the peaks: a camera move
  // reuses it. A virtual sample reads a Catmull-Rom window two steps either side: its cell's
  // range is the union over the cells that window can reach (ring), widened by Lee's (M - m)/8
  // (eq. 8), the most the spline overshoots its samples. Windows reaching too far sample
  // without skipping.
  f.occupancy = &kNoSkipping;
  const bool vs = s.scene.render.virtual_samples != 0;
  const int ring = vs ? virtual_sample_ring(plan_sampling(s), s, cells.cell) : 0;
  if (s.scene.render.space_skipping && ring >= 0) {
    const double overshoot = vs ? o.vs_widening : 0.0;
    const int reach = vs && o.vs_widening > 0.0 ? ring : 0;  // widening 0 (a test's): neither
    f.occupancy_key = f.tf_sig + " cells " + std::to_string(gv.serial()) + " " + cells.to_string() + " peaks " +
                      std::to_string(f.peaks.size()) + " overshoot " + std::to_string(overshoot) + " ring " +
                      std::to_string(reach) + (o.leaps ? "" : " no leaps");
    f.occupancy = &cache.get(
        f.occupancy_key,
        [&] {
          return classify_cells(reach ? dilate_ranges(cells, reach) : cells, s.tf, gv.tf_lo(), gv.tf_hi(), peak_values,
                                TransferFunction::kTableSize, overshoot);
        },
        builds);
  }
  f.key = choose_variant(s, f.occupancy->empty_cells, path, f.peaks.size());
  if (o.force_variant) {
    o.force_variant(f.key);
    f.key.space_skipping = f.key.space_skipping && !f.occupancy_key.empty();  // forced only where occupancy was built
  }
  f.table_ms = ms_since(t0);
  return f;
}

std::vector<uint8_t> traversal_distances(const Occupancy& occupancy, bool leaps) {
  std::vector<uint8_t> distance = occupancy.distance;
  if (!leaps)
    for (auto& d : distance) d = std::min<uint8_t>(d, 1);
  return distance;
}

std::string step_tf_key(const ResolvedScene& s, const std::string& tf_sig) {
  const double exponent = double(float(plan_sampling(s).step)) / double(float(s.tf.opacity_unit));
  return tf_sig + " opacity exponent " + std::to_string(exponent);
}

std::vector<float> step_tf_table(const ResolvedScene& s, double lo, double hi) {
  const double exponent = double(float(plan_sampling(s).step)) / double(float(s.tf.opacity_unit));
  std::vector<float> table = s.tf.bake(TransferFunction::kTableSize, lo, hi);
  // Kept a normal float (GPUs flush denormals to zero, which would make the step's every chord
  // opaque), except where the TF is opaque itself.
  for (size_t k = 3; k < table.size(); k += 4) {
    const double T = std::pow(std::max(0.0, 1.0 - double(table[k])), exponent);
    table[k] = T > 0.0 ? float(std::max(T, double(std::numeric_limits<float>::min()))) : 0.f;
  }
  return table;
}

std::string tables_key(const ResolvedScene& s, double lo, double hi, size_t peak_count) {
  const RenderSettings& r = s.scene.render;
  std::ostringstream key;
  key.precision(17);
  key << tf_signature(s.tf, lo, hi) << ' ' << to_string(r.classification) << ' ' << r.peak_table_bins << ' '
      << r.max_peaks << ' ' << r.secant_iterations << ' ' << r.preint_table_size << ' ' << r.preint_method << ' '
      << peak_count << ' ' << (r.classification == Classification::Preint ? plan_sampling(s).step : 0.0);
  return key.str();
}

std::vector<float> peak_texels(const PeakTable& table, double lo, double hi) {
  std::vector<float> texels(table.texels.size());
  for (size_t k = 0; k < texels.size(); ++k)
    texels[k] = table.texels[k] == PeakTable::kNoPeak ? kNoPeakTexel : float((table.texels[k] - lo) / (hi - lo));
  return texels;
}

std::vector<glm::vec2> cell_ranges(const MacrocellGrid& cells, double lo, double hi) {
  std::vector<glm::vec2> out(cells.size());
  const double scale = 1.0 / (hi - lo), pad = 1e-5;  // float samples round within ~1e-7 of their cell's range
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = glm::vec2(float((cells.min[i] - lo) * scale - pad), float((cells.max[i] - lo) * scale + pad));
  return out;
}

std::vector<glm::vec4> tf_point_pairs(const TransferFunction& tf, double lo, double hi) {
  std::vector<glm::vec4> points;
  for (const auto& p : tf.points) {
    points.emplace_back(float((p.value - lo) / (hi - lo)), 0.f, 0.f, 0.f);
    points.emplace_back(float(p.r), float(p.g), float(p.b), float(p.a));
  }
  return points;
}

PreintegrationTable scene_preintegration(const ResolvedScene& s, double lo, double hi) {
  const RenderSettings& r = s.scene.render;
  return build_preintegration(s.tf, lo, hi, plan_sampling(s).step, r.preint_table_size, preint_method(r));
}

}  // namespace peakcast::render
