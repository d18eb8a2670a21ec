// The CPU backend's copy of a volume: the volume's own voxels, read as stored and mapped to TF
// coordinates per sample, for integers and for floats whose range allows it (floats_in_place);
// otherwise a copy of float voxels in TF coordinates (computed in double, as the GL backend's
// upload: no denormal or overflow depends on the data's scale), after which the float voxels
// themselves may go (drop_host_voxels; the server keeps them for its probes).
#pragma once

#include <memory>

#include "cpu/sampler.h"
#include "render/resident_volume.h"

namespace peakcast::cpu {

class CpuVolume : public render::ResidentVolume {
 public:
  explicit CpuVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells = {});
  ~CpuVolume() override;

  size_t resident_bytes() const override { return copy_bytes_; }
  // A float volume copied in TF coordinates: frees the volume's voxels once both grids exist (the
  // copy is what the sampler reads). Voxels read where they lie: false, they are the copy.
  bool drop_host_voxels() override;
  // Whether float voxels are read where they lie (scale and bias: stored value -> TF coordinate).
  static bool floats_in_place(const Volume& v, double scale, double bias);
  // The sampler's view (trilinear or tricubic).
  VoxelGrid grid(Filter filter) const;

 private:
  VoxelArray<float> unit_;  // float volumes in TF coordinates, plus padding
  size_t copy_bytes_ = 0;
  float scale_ = 1.f, bias_ = 0.f;
};

}  // namespace peakcast::cpu
