// The CPU backend's copy of a volume: the volume's own voxels when they are integers (read as
// stored, mapped to TF coordinates per sample), a copy in TF coordinates when they are floats
// (computed in double, as the GL backend's upload: no denormal or overflow depends on the data's
// scale), after which the float voxels themselves may go (drop_host_voxels). Either way the
// volume is held once in host memory.
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
  // Float volumes: frees the volume's voxels once both grids exist (the copy in TF
  // coordinates is what the sampler reads). Integer volumes: false, their voxels are the copy.
  bool drop_host_voxels() override;
  // The sampler's view (trilinear or tricubic).
  VoxelGrid grid(Filter filter) const;

 private:
  std::unique_ptr<float[]> unit_;  // float volumes in TF coordinates, plus padding
  size_t copy_bytes_ = 0;
  float scale_ = 1.f, bias_ = 0.f;
};

}  // namespace peakcast::cpu
