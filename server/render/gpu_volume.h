// A volume resident on the GPU in its native type (R8 / R16 / R32F), with its macrocell grids.
// One per loaded volume, shared by every session that views it (DESIGN §2).
#pragma once

#include <memory>

#include "core/macrocells.h"
#include "core/scene.h"
#include "core/volume.h"
#include "gpu/gl_objects.h"

namespace peakcast::render {

class GpuVolume {
 public:
  // `cells`: grids built off the render thread (VolumeEntry::macrocells; checked against the
  // volume, std::invalid_argument otherwise). A missing grid is built here (trilinear) or at
  // first use (tricubic), on the calling thread: fine for the CLI and tests, a stall for the
  // server's render thread.
  explicit GpuVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells = {});

  const Volume& volume() const { return *volume_; }
  std::shared_ptr<const Volume> shared() const { return volume_; }
  // Render thread only, like every other member.
  const MacrocellGrid& macrocells(Filter filter) const;
  double upload_ms() const { return upload_ms_; }            // texture upload in the constructor
  double macrocell_ms() const { return macrocell_ms_; }      // grids built on this thread so far
  size_t gpu_bytes() const { return volume_->byte_size(); }
  // TF coordinate of a texel value: a * texel + b (the TF table spans [min_value, max_value]).
  float value_scale() const { return scale_; }
  float value_bias() const { return bias_; }
  double tf_lo() const { return lo_; }
  double tf_hi() const { return hi_; }
  void bind(unsigned unit) const;
  // Frees the host copy of the voxels (Volume::drop_voxels) once both macrocell grids exist:
  // the texture is then the only copy. False (nothing freed) without both grids.
  bool drop_host_voxels();
  uint64_t serial() const { return serial_; }  // unique per upload: caches key on it, not on addresses

 private:
  std::shared_ptr<const Volume> volume_;
  gpu::Texture texture_;
  std::shared_ptr<const MacrocellGrid> cells_trilinear_;
  mutable std::shared_ptr<const MacrocellGrid> cells_tricubic_;
  double upload_ms_ = 0.0;
  mutable double macrocell_ms_ = 0.0;
  float scale_ = 1.f, bias_ = 0.f;
  double lo_ = 0, hi_ = 1;
  uint64_t serial_ = 0;
};

}  // namespace peakcast::render
