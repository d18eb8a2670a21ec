#include "core/auto_tf.h"

#include <algorithm>
#include <cmath>

#include <glm/vec3.hpp>

#include "core/colormaps.h"

namespace peakcast {

namespace {

// The value below which `fraction` of the counted voxels lie (bin-linear).
double percentile(const std::vector<uint64_t>& h, double lo, double hi, double fraction) {
  double total = 0;
  for (uint64_t c : h) total += double(c);
  const double w = (hi - lo) / double(h.size()), target = fraction * total;
  double below = 0;
  for (size_t b = 0; b < h.size(); ++b) {
    if (below + double(h[b]) >= target && h[b] > 0) return lo + w * (double(b) + (target - below) / double(h[b]));
    below += double(h[b]);
  }
  return hi;
}

}  // namespace

glm::dvec3 viridis(double t) { return colormap("viridis", t); }

double otsu_threshold(const std::vector<uint64_t>& h, double lo, double hi) {
  double total = 0, sum = 0;
  for (size_t b = 0; b < h.size(); ++b) {
    total += double(h[b]);
    sum += double(b) * double(h[b]);
  }
  if (h.empty() || total <= 0 || !(hi > lo)) return lo;
  double w0 = 0, sum0 = 0, best = -1;
  size_t split = 0;  // first bin of the upper class
  for (size_t k = 1; k < h.size(); ++k) {
    w0 += double(h[k - 1]);
    sum0 += double(k - 1) * double(h[k - 1]);
    const double w1 = total - w0;
    if (w0 <= 0 || w1 <= 0) continue;
    const double d = sum0 / w0 - (sum - sum0) / w1;
    const double between = w0 * w1 * d * d;
    if (between > best) {
      best = between;
      split = k;
    }
  }
  return lo + (hi - lo) * double(split) / double(h.size());
}

namespace {

// The share of the faces' voxels in the bins at and above the one holding t.
double border_share_above(const std::vector<uint64_t>& border, double lo, double hi, double t) {
  const size_t split =
      size_t(std::clamp(std::lround((t - lo) / (hi - lo) * double(border.size())), 0L, long(border.size())));
  double above = 0, all = 0;
  for (size_t b = 0; b < border.size(); ++b) {
    all += double(border[b]);
    if (b >= split) above += double(border[b]);
  }
  return all > 0 ? above / all : 0.0;
}

TransferFunction derive_upward(const AutoTfInput& in);

}  // namespace

TransferFunction derive_transfer_function(const AutoTfInput& in) {
  const std::vector<uint64_t>* h = in.histogram;
  const std::vector<uint64_t>* border = in.border_histogram;
  if (!h || h->empty() || !border || border->size() != h->size() || !(in.hi > in.lo)) return derive_upward(in);
  if (border_share_above(*border, in.lo, in.hi, otsu_threshold(*h, in.lo, in.hi)) < kBackgroundAbove)
    return derive_upward(in);
  // The background is the upper class: derive the TF of the mirrored values (v -> -v) and mirror
  // it back, so the opacity rises as the value falls below the threshold.
  const std::vector<uint64_t> mirrored(h->rbegin(), h->rend());
  AutoTfInput m = in;
  m.histogram = &mirrored;
  m.border_histogram = nullptr;
  m.lo = -in.hi;
  m.hi = -in.lo;
  TransferFunction tf = derive_upward(m);
  std::reverse(tf.points.begin(), tf.points.end());
  for (auto& p : tf.points) p.value = -p.value;
  return tf;
}

namespace {

TransferFunction derive_upward(const AutoTfInput& in) {
  const double lo = in.lo, hi = in.hi;
  const std::vector<uint64_t>* h = in.histogram;
  double total = 0;
  if (h)
    for (uint64_t c : *h) total += double(c);
  if (!h || h->empty() || total <= 0 || !(hi > lo)) {  // nothing to read: a ramp over the range
    TransferFunction tf;
    tf.points = {{lo, 0, 0, 0, 0}, {hi > lo ? hi : lo + 1, 1, 1, 1, 0.5}};
    return tf;
  }
  const double t = otsu_threshold(*h, lo, hi);
  double top = percentile(*h, lo, hi, 0.999);
  if (!(top > t + 1e-6 * (hi - lo))) top = hi;

  // The mean share of the ramp's full opacity a voxel gets, and from it the opacity at the
  // top that makes a ray of the typical length reach 90% opacity on average (the optical depth
  // adds up: m * L * -ln(1 - a_top) = ln 10), kept within [0.005, 0.8].
  const double bw = (hi - lo) / double(h->size());
  double m = 0;
  for (size_t b = 0; b < h->size(); ++b) {
    const double v = lo + bw * (double(b) + 0.5);
    if (v > t) m += double((*h)[b]) * std::min(1.0, (v - t) / (top - t));
  }
  m /= total;
  const double depth = std::max(m * std::max(in.ray_length, 1.0), 1e-9);
  const double a_top = std::clamp(1.0 - std::exp(-std::log(10.0) / depth), 0.005, 0.8);

  TransferFunction tf;
  constexpr int kStops = 8;
  for (int k = 0; k <= kStops; ++k) {
    const double s = double(k) / kStops;
    const glm::dvec3 c = viridis(s);
    tf.points.push_back({t + s * (top - t), c.r, c.g, c.b, a_top * s});
  }
  if (in.with_peak) {
    // An opacity peak at the threshold: a surface where the background meets the structure,
    // in a light colour that shades well, half transparent so the structure inside shows.
    const double w = 0.01 * (top - t);
    const glm::dvec3 below = viridis(0);
    auto& p = tf.points;
    p.insert(p.begin(), {t - w, below.r, below.g, below.b, 0.0});
    p[1] = {t, 0.95, 0.88, 0.75, 0.7};
    const glm::dvec3 c = viridis(w / (top - t));
    p.insert(p.begin() + 2, {t + w, c.r, c.g, c.b, a_top * w / (top - t)});
  }
  return tf;
}

}  // namespace
}  // namespace peakcast
