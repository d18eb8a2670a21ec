#include "distributed/brick_frame.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/sampling.h"

namespace peakcast::distributed {

int brick_ghost(const ResolvedScene& s) {
  const RenderSettings& r = s.scene.render;
  int ghost = ghost_voxels(r.filter == Filter::Tricubic, r.shading);
  // Segment methods close a brick's last segment with the visit one step past its box; virtual
  // samples read two visits past its last segment's start and one before its first (the
  // Catmull-Rom window). A step is the longest any ray of the scene takes (the uniform step, or
  // a differential lattice's at the box corner farthest from the eye), times the largest
  // adaptive multiplier with adaptive sampling.
  const int visits = r.virtual_samples > 0 ? 2 : (r.classification != Classification::Post ? 1 : 0);
  const double multiplier = (r.adaptive ? kMaxAdaptiveMultiplier : 1) * max_step_multiplier(s.ray_texture.get());
  if (visits > 0)
    ghost += int(std::ceil(visits * multiplier * longest_step(plan_sampling(s), s) / s.min_spacing - 1e-9));
  return ghost;
}

double max_step_multiplier(const RayTextureSpec* t) {
  if (!t) return 1.0;
  double most = 1.0;  // the default texel
  if (t->image)
    for (size_t k = 0; k < t->image->texels.size(); k += 3) most = std::max(most, double(t->image->texels[k]));
  else if (!t->png.empty())
    most = kMaxStepMultiplier;  // not read yet
  // Each stroke raises the largest texel at most to its value (set), by it (add), by its factor
  // (multiply): a bound, whatever the strokes overlap.
  for (const Stroke& st : t->strokes) {
    if (st.channel != RayChannel::Step) continue;
    if (st.mode == StrokeMode::Set) most = std::max(most, st.value);
    if (st.mode == StrokeMode::Add) most += std::max(st.value, 0.0);
    if (st.mode == StrokeMode::Multiply) most *= std::max(st.value, 1.0);
  }
  return std::min(most, kMaxStepMultiplier);
}

std::vector<float> opacity_over(const std::vector<float>* front, const Image& layer) {
  std::vector<float> out(layer.samples.size());
  for (size_t p = 0; p < out.size(); ++p) {
    const float a = front ? (*front)[p] : -1.f;
    // A ray this brick sampled consumed here: its opacity counts from now on (none before: -1).
    out[p] = layer.samples[p] > 0.f ? std::max(a, 0.f) + (1.f - std::max(a, 0.f)) * layer.rgba[p * 4 + 3] : a;
  }
  return out;
}

MacrocellShare brick_macrocell_share(const Volume& voxels, const Brick& brick, const Index3& dims,
                                     FilterSupport support) {
  const auto [lo, hi] = counted_box(brick, dims);
  return macrocell_share(voxels, Dims{dims[0], dims[1], dims[2]}, Dims{lo[0], lo[1], lo[2]}, Dims{hi[0], hi[1], hi[2]},
                         support);
}

render::Brick frame_brick(const Brick& b, const Index3& dims) {
  render::Brick c;
  for (int a = 0; a < 3; ++a) {
    c.read_lo[a] = double(b.read_lo[a]);
    c.own_lo[a] = double(b.lo[a]);
    c.own_hi[a] = double(b.hi[a]);
    c.at_start[a] = b.lo[a] == 0;
    c.at_end[a] = b.hi[a] == dims[a] - 1;
  }
  return c;
}

std::vector<float> composite_over(const std::vector<std::vector<float>>& layers, const std::vector<int>& order) {
  if (layers.empty() || order.size() != layers.size())
    throw std::invalid_argument("composite_over: one order entry per layer");
  std::vector<float> out(layers[0].size(), 0.f);
  for (int k : order) {
    const std::vector<float>& l = layers.at(size_t(k));
    if (l.size() != out.size()) throw std::invalid_argument("composite_over: layers of different sizes");
    for (size_t p = 0; p < out.size(); p += 4) {
      const float t = 1.f - out[p + 3];
      for (int c = 0; c < 4; ++c) out[p + c] += t * l[p + c];
    }
  }
  return out;
}

Image finish_composite(const std::vector<float>& rgba, int width, int height, const glm::dvec3& background) {
  if (rgba.size() != size_t(width) * size_t(height) * 4) throw std::invalid_argument("finish_composite: size mismatch");
  Image img(width, height);
  const glm::vec3 bg(background);
  for (size_t p = 0; p < size_t(width) * size_t(height); ++p) {
    const float a = rgba[p * 4 + 3];
    for (int c = 0; c < 3; ++c) img.rgba[p * 4 + c] = rgba[p * 4 + c] + (1.f - a) * bg[c];
    img.rgba[p * 4 + 3] = a;
  }
  return img;
}

}  // namespace peakcast::distributed
