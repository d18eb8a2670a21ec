// The CPU backend's table bits (cpu/table_bits.h): a clear bit must mean that the lookup it
// stands for finds nothing, exactly, and a set bit that it may find something. Checked cell by
// cell against the real tables of a narrow-band TF (most cells empty) and a wide one.
#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

#include "core/peaks.h"
#include "core/preintegration.h"
#include "core/transfer_function.h"
#include "cpu/table_bits.h"
#include "render/frame_setup.h"
#include "render/shader_interface.h"

using namespace peakcast;

namespace {

// Narrow: two thin peaks, zero elsewhere. Wide: opacity almost everywhere.
std::vector<TransferFunction> test_tfs() {
  const std::vector<std::vector<TfPoint>> points = {
      {{0, 0, 0, 1, 0},
       {0.49, 0, 0, 1, 0},
       {0.5, 1, 0.8, 0.3, 0.8},
       {0.51, 0, 0, 1, 0},
       {0.8, 0, 0, 0, 0},
       {0.81, 0, 1, 0, 0.5},
       {0.82, 0, 0, 0, 0},
       {1, 0, 0, 0, 0}},
      {{0, 0, 0, 0, 0}, {0.1, 1, 0, 0, 0.2}, {0.6, 0, 1, 0, 0.9}, {1, 0, 0, 1, 0.4}}};
  std::vector<TransferFunction> tfs(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    tfs[k].points = points[k];
    tfs[k].opacity_unit = 1.0;
  }
  return tfs;
}

bool rgba_nonzero(const std::vector<float>& t, size_t texel) {
  return t[4 * texel] != 0.f || t[4 * texel + 1] != 0.f || t[4 * texel + 2] != 0.f || t[4 * texel + 3] != 0.f;
}

TEST(TableBits, PreintegrationCellClearOnlyWhereItsFourTexelsAreZero) {
  for (const auto& tf : test_tfs()) {
    const PreintegrationTable table = build_preintegration(tf, 0.0, 1.0, 1.0, 64);
    const int n = table.size, m = n - 1;
    const auto bits = cpu::preint_cell_bits(table.rgba, n);
    int clear = 0, set = 0;
    for (int j = 0; j < m; ++j)
      for (int i = 0; i < m; ++i) {
        bool any = false;
        for (int dj = 0; dj < 2; ++dj)
          for (int di = 0; di < 2; ++di) any = any || rgba_nonzero(table.rgba, size_t(j + dj) * n + size_t(i + di));
        EXPECT_EQ(cpu::test_bit(bits.data(), size_t(j) * m + size_t(i)), any) << i << "," << j;
        (any ? set : clear)++;
      }
    EXPECT_GT(set, 0);  // the TF draws something
    // The narrow TF: segments between values on one side of both peaks add nothing.
    if (tf.points.size() > 4) {
      EXPECT_GT(clear, m * m / 8);
    }
  }
}

TEST(TableBits, PeakTexelClearOnlyWhereNoLayerHoldsAPeak) {
  for (const auto& tf : test_tfs()) {
    const PeakTable table = build_peak_table(find_peaks(tf), 0.0, 1.0, 32);
    const std::vector<float> texels = render::peak_texels(table, 0.0, 1.0);
    const auto bits = cpu::peak_texel_bits(texels, table.bins);
    const size_t layer = size_t(table.bins) * size_t(table.bins);
    int set = 0;
    for (int j = 0; j < table.bins; ++j)
      for (int i = 0; i < table.bins; ++i) {
        const size_t k = size_t(j) * table.bins + size_t(i);
        bool any = false;
        for (int l = 0; l < table.layers; ++l)
          for (int s = 0; s < 4; ++s) any = any || texels[4 * (l * layer + k) + s] != render::kNoPeakTexel;
        EXPECT_EQ(cpu::test_bit(bits.data(), k), any) << i << "," << j;
        set += any;
      }
    EXPECT_EQ(set > 0, !find_peaks(tf).empty());
  }
}

TEST(TableBits, TfCellClearOnlyWhereBothTexelsAreTransparent) {
  for (const auto& tf : test_tfs()) {
    std::vector<float> rgba = tf.bake(TransferFunction::kTableSize, 0.0, 1.0);
    for (size_t k = 3; k < rgba.size(); k += 4) rgba[k] = 1.f - rgba[k];  // transparency, as the renderer's table
    const int n = TransferFunction::kTableSize;
    const auto bits = cpu::tf_cell_bits(rgba, n);
    int clear = 0;
    for (int i = 0; i + 1 < n; ++i) {
      const bool any = rgba[4 * size_t(i) + 3] != 1.f || rgba[4 * size_t(i + 1) + 3] != 1.f;
      EXPECT_EQ(cpu::test_bit(bits.data(), size_t(i)), any) << i;
      clear += !any;
    }
    if (tf.points.size() > 4) {
      EXPECT_GT(clear, n / 2);
    }
  }
}

TEST(TableBits, RefuseTablesSmallerThanTheirSize) {
  EXPECT_THROW(cpu::preint_cell_bits(std::vector<float>(4 * 15), 4), std::invalid_argument);
  EXPECT_THROW(cpu::preint_cell_bits(std::vector<float>(4), 1), std::invalid_argument);
  EXPECT_THROW(cpu::peak_texel_bits(std::vector<float>(4 * 8), 3), std::invalid_argument);
  EXPECT_THROW(cpu::tf_cell_bits(std::vector<float>(4 * 7), 8), std::invalid_argument);
  EXPECT_NO_THROW(cpu::tf_cell_bits(std::vector<float>(4 * 8), 8));
}

}  // namespace
