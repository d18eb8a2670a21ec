// One bit per lookup cell of the peak and preintegration tables, saying whether a lookup there
// can find anything. The tables are large (128² × 4 layers of four floats; 256² RGBA floats)
// and a ray reads them at scattered places, once per segment: most reads miss the cache and
// most find nothing (a TF's opacity is zero over most pairs of values). The bits fit in L1
// (2 KiB, 8 KiB), and a clear bit gives exactly what the lookup would have given.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace peakcast::cpu {

// Bit j * bins + i: slot 0 of texel (i, j) in layer 0 holds a peak (is not kNoPeakTexel). The
// lookup stops at the first empty slot, so a clear bit means no peak in any layer.
std::vector<uint64_t> peak_texel_bits(const std::vector<float>& texels, int bins);

// Bit j * (n - 1) + i, for the cells i, j < n - 1 of an n x n RGBA table: one of the four
// texels a bilinear lookup in that cell reads, (i..i+1, j..j+1), has a non-zero component.
// A clear bit: the lookup interpolates zeros, and is exactly zero.
std::vector<uint64_t> preint_cell_bits(const std::vector<float>& rgba, int n);

// Bit i, for the cells i < n - 1 of an n-entry TF table (colour and transparency, as
// render::step_tf_table makes it): texel i or i + 1, which a linear lookup in that cell reads,
// has a non-zero opacity (transparency below 1). A clear bit: the lookup's opacity is zero.
std::vector<uint64_t> tf_cell_bits(const std::vector<float>& rgba, int n);

inline bool test_bit(const uint64_t* bits, size_t k) { return (bits[k >> 6] >> (k & 63)) & 1u; }

}  // namespace peakcast::cpu
