#include "cpu/cpu_volume.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "core/parallel.h"
#include "core/value_range.h"

namespace peakcast::cpu {

VoxelGrid make_voxel_grid(const Volume& v, const uint8_t* data, VoxelType type, float scale, float bias,
                          bool tricubic) {
  VoxelGrid g;
  g.data = data;
  g.type = type;
  for (int a = 0; a < 3; ++a) {
    g.n[a] = v.dims()[a];
    g.hi[a] = float(g.n[a] - 1);
    g.base_max[a] = int32_t(std::max<int64_t>(g.n[a] - 2, 0));
  }
  g.stride_y = g.n[0];
  g.stride_z = g.n[0] * g.n[1];
  g.next_y = g.n[1] > 1 ? g.stride_y : 0;
  g.next_z = g.n[2] > 1 ? g.stride_z : 0;
  g.scale = scale;
  g.bias = bias;
  g.tricubic = tricubic;
  // The SIMD gathers address voxels with 32-bit lanes (bytes for integers, elements for floats).
  const int64_t units = v.voxel_count() * (type == VoxelType::F32 ? 1 : int64_t(voxel_bytes(type)));
  g.simd_offsets = units + 16 < int64_t(std::numeric_limits<int32_t>::max());
  return g;
}

// Float voxels can be read where they lie, mapped to TF coordinates per sample in float as
// integers are, when that keeps the TF coordinate to within ~1e-5: the stored values and the bias
// at most 64 ranges from 0 (no cancellation beyond 64 float ulps), and the scale a normal float
// (no overflow, no denormal). Otherwise (an offset far larger than the range, a range near the
// float limits) the copy in TF coordinates, computed in double.
bool CpuVolume::floats_in_place(const Volume& v, double scale, double bias) {
  constexpr double kReach = 64.0;
  const double stored = std::max(std::abs(v.min_value - v.value_offset), std::abs(v.max_value - v.value_offset));
  return std::isfinite(stored) && std::isnormal(float(scale)) && stored * scale <= kReach && std::abs(bias) <= kReach &&
         stored <= 1e30;
}

CpuVolume::CpuVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells)
    : ResidentVolume(std::move(volume), std::move(cells)) {
  const auto t0 = std::chrono::steady_clock::now();
  const Volume& v = *volume_;
  const ValueRange range = table_range(v.min_value, v.max_value);
  const double scale = 1.0 / (range.hi - range.lo), bias = (v.value_offset - range.lo) / (range.hi - range.lo);
  if (v.type() == VoxelType::F32 && !floats_in_place(v, scale, bias)) {
    const size_t n = size_t(v.voxel_count());
    constexpr size_t kPad = Volume::kTailPadding / sizeof(float);
    unit_ = allocate_voxels<float>(n + kPad);
    std::fill_n(unit_.get() + n, kPad, 0.f);
    const float* f = reinterpret_cast<const float*>(v.data());
    parallel_chunks(n, [&](size_t b, size_t e, int) {
      for (size_t i = b; i < e; ++i) unit_[i] = float(range.to_unit(double(f[i]) + v.value_offset));
    });
    copy_bytes_ = n * sizeof(float);
  } else {
    scale_ = float(scale);
    bias_ = float(bias);
  }
  upload_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  ensure_trilinear_grid();
}

CpuVolume::~CpuVolume() = default;

bool CpuVolume::drop_host_voxels() {
  if (!unit_ || !has_both_grids()) return false;
  volume_->drop_voxels();
  return true;
}

VoxelGrid CpuVolume::grid(Filter filter) const {
  const bool tricubic = filter == Filter::Tricubic;
  if (unit_)
    return make_voxel_grid(*volume_, reinterpret_cast<const uint8_t*>(unit_.get()), VoxelType::F32, 1.f, 0.f, tricubic);
  return make_voxel_grid(*volume_, volume_->data(), volume_->type(), scale_, bias_, tricubic);
}

}  // namespace peakcast::cpu
