#include "gpu/gl_volume.h"

#include <chrono>
#include <stdexcept>
#include <vector>

#include "core/value_range.h"
#include "render/small_cache.h"

namespace peakcast::gpu {

using namespace render;  // the renderer interface and frame setup this implements

GlVolume::GlVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells)
    : ResidentVolume(std::move(volume), std::move(cells)) {
  const auto t0 = std::chrono::steady_clock::now();
  const Volume& v = *volume_;
  const auto& d = v.dims();
  GLenum internal = GL_R8, type = GL_UNSIGNED_BYTE;
  double texel_to_stored = 255.0;
  if (v.type() == VoxelType::U16) {
    internal = GL_R16;
    type = GL_UNSIGNED_SHORT;
    texel_to_stored = 65535.0;
  } else if (v.type() == VoxelType::F32) {
    internal = GL_R32F;
    type = GL_FLOAT;
    texel_to_stored = 1.0;
  }
  GLint max_size = 0;
  glGetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_size);
  for (int a = 0; a < 3; ++a)
    if (d[a] > max_size)
      throw std::runtime_error("volume dimension " + std::to_string(d[a]) + " exceeds the GPU's 3D texture limit " +
                               std::to_string(max_size));
  texture_ = gpu::make_texture(GL_TEXTURE_3D);
  glTextureStorage3D(texture_.id(), 1, internal, GLsizei(d[0]), GLsizei(d[1]), GLsizei(d[2]));
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  const ValueRange range = table_range(v.min_value, v.max_value);
  // Integer voxels go up as they are and are mapped to TF coordinates in the shader. Float
  // voxels go up already in TF coordinates, computed in double: raw, a volume of denormal values
  // (1e-40) would be flushed to zero by the GPU and 1 / (hi - lo) would overflow a float, so the
  // picture would depend on the data's scale.
  const bool normalise = v.type() == VoxelType::F32;
  const size_t slice = size_t(d[0] * d[1]) * voxel_bytes(v.type());
  const int64_t slab = normalise ? 8 : 64;  // slices per upload: the driver's (and our) staging stays small
  std::vector<float> unit;
  for (int64_t z = 0; z < d[2]; z += slab) {
    const int64_t n = std::min<int64_t>(slab, d[2] - z);
    const uint8_t* src = v.data() + size_t(z) * slice;
    if (normalise) {
      const size_t count = size_t(d[0] * d[1]) * size_t(n);
      unit.resize(count);
      const float* f = reinterpret_cast<const float*>(src);
      for (size_t i = 0; i < count; ++i) unit[i] = float(range.to_unit(double(f[i]) + v.value_offset));
      src = reinterpret_cast<const uint8_t*>(unit.data());
    }
    glTextureSubImage3D(texture_.id(), 0, 0, 0, GLint(z), GLsizei(d[0]), GLsizei(d[1]), GLsizei(n), GL_RED, type, src);
  }
  if (glGetError() == GL_OUT_OF_MEMORY) throw std::runtime_error("GPU out of memory uploading the volume");
  glTextureParameteri(texture_.id(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTextureParameteri(texture_.id(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
    glTextureParameteri(texture_.id(), wrap, GL_CLAMP_TO_EDGE);
  gpu::check_gl("volume upload");
  upload_ms_ = ms_since(t0);

  scale_ = normalise ? 1.0f : float(texel_to_stored / (range.hi - range.lo));
  bias_ = normalise ? 0.0f : float((v.value_offset - range.lo) / (range.hi - range.lo));
  ensure_trilinear_grid();
}

bool GlVolume::drop_host_voxels() {
  if (!has_both_grids()) return false;  // a grid may still need the voxels
  volume_->drop_voxels();
  return true;
}

void GlVolume::bind(unsigned unit) const { glBindTextureUnit(unit, texture_.id()); }

}  // namespace peakcast::gpu
