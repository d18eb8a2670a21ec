#include "cpu/table_bits.h"

#include <stdexcept>

#include "render/shader_interface.h"

namespace peakcast::cpu {

namespace {
void set_bit(std::vector<uint64_t>& bits, size_t k) { bits[k >> 6] |= uint64_t(1) << (k & 63); }
}  // namespace

std::vector<uint64_t> peak_texel_bits(const std::vector<float>& texels, int bins) {
  const size_t cells = size_t(bins) * size_t(bins);
  if (bins <= 0 || texels.size() < cells * 4) throw std::invalid_argument("peak_texel_bits: table smaller than bins^2");
  std::vector<uint64_t> bits((cells + 63) / 64, 0);
  for (size_t k = 0; k < cells; ++k)
    if (texels[4 * k] != render::kNoPeakTexel) set_bit(bits, k);
  return bits;
}

std::vector<uint64_t> preint_cell_bits(const std::vector<float>& rgba, int n) {
  if (n < 2 || rgba.size() < size_t(n) * size_t(n) * 4)
    throw std::invalid_argument("preint_cell_bits: table smaller than n^2 RGBA");
  auto nonzero = [&](int i, int j) {
    const float* p = rgba.data() + (size_t(j) * size_t(n) + size_t(i)) * 4;
    return p[0] != 0.f || p[1] != 0.f || p[2] != 0.f || p[3] != 0.f;
  };
  const int m = n - 1;
  std::vector<uint64_t> bits((size_t(m) * size_t(m) + 63) / 64, 0);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i)
      if (nonzero(i, j) || nonzero(i + 1, j) || nonzero(i, j + 1) || nonzero(i + 1, j + 1))
        set_bit(bits, size_t(j) * size_t(m) + size_t(i));
  return bits;
}

std::vector<uint64_t> tf_cell_bits(const std::vector<float>& rgba, int n) {
  if (n < 2 || rgba.size() < size_t(n) * 4) throw std::invalid_argument("tf_cell_bits: table smaller than n RGBA");
  std::vector<uint64_t> bits((size_t(n - 1) + 63) / 64, 0);
  for (int i = 0; i + 1 < n; ++i)
    if (rgba[size_t(i) * 4 + 3] != 1.f || rgba[size_t(i + 1) * 4 + 3] != 1.f) set_bit(bits, size_t(i));
  return bits;
}

}  // namespace peakcast::cpu
