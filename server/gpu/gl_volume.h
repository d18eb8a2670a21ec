// The GL backend's copy of a volume: a 3D texture in the native type (R8 / R16 / R32F).
#pragma once

#include <memory>

#include "gpu/gl_objects.h"
#include "render/resident_volume.h"

namespace peakcast::gpu {

class GlVolume : public render::ResidentVolume {
 public:
  // `cells`: grids built off the render thread (VolumeEntry::macrocells; checked against the
  // volume, std::invalid_argument otherwise); see ResidentVolume::macrocells.
  explicit GlVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells = {});

  size_t gpu_bytes() const { return volume_->byte_size(); }
  size_t resident_bytes() const override { return gpu_bytes(); }
  // TF coordinate of a texel value: a * texel + b (the TF table spans [min_value, max_value]).
  float value_scale() const { return scale_; }
  float value_bias() const { return bias_; }
  void bind(unsigned unit) const;
  // The texture is then the only copy.
  bool drop_host_voxels() override;

 private:
  gpu::Texture texture_;
  float scale_ = 1.f, bias_ = 0.f;
};

}  // namespace peakcast::gpu
