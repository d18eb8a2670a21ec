#include "render/gpu_volume.h"
#include "core/value_range.h"

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <vector>

namespace peakcast::render {

namespace {
double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

GpuVolume::GpuVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells)
    : volume_(std::move(volume)), cells_trilinear_(std::move(cells.trilinear)), cells_tricubic_(std::move(cells.tricubic)) {
  if (cells_trilinear_) check_macrocells(*cells_trilinear_, *volume_, FilterSupport::Trilinear);
  if (cells_tricubic_) check_macrocells(*cells_tricubic_, *volume_, FilterSupport::Tricubic);
  if (!volume_->has_voxels()) throw std::invalid_argument("GpuVolume: the volume's voxels were dropped");
  const auto t0 = std::chrono::steady_clock::now();
  static std::atomic<uint64_t> next_serial{1};
  serial_ = next_serial++;
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
  lo_ = range.lo;
  hi_ = range.hi;
  // Integer voxels go up as they are and are mapped to TF coordinates in the shader. Float
  // voxels go up already in TF coordinates, computed in double: raw, a volume of denormal values
  // (1e-40) would be flushed to zero by the GPU and 1 / (hi - lo) would overflow a float, so the
  // picture would depend on the data's scale (DESIGN §6).
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

  scale_ = normalise ? 1.0f : float(texel_to_stored / (hi_ - lo_));
  bias_ = normalise ? 0.0f : float((v.value_offset - lo_) / (hi_ - lo_));
  if (!cells_trilinear_) {
    const auto t1 = std::chrono::steady_clock::now();
    cells_trilinear_ = std::make_shared<const MacrocellGrid>(build_macrocells(v, 0, FilterSupport::Trilinear));
    macrocell_ms_ += ms_since(t1);
  }
}

const MacrocellGrid& GpuVolume::macrocells(Filter filter) const {
  if (filter != Filter::Tricubic) return *cells_trilinear_;
  if (!cells_tricubic_) {  // most views never ask for the wider filter support
    if (!volume_->has_voxels()) throw std::logic_error("GpuVolume: no tricubic grid and no voxels to build it");
    const auto t1 = std::chrono::steady_clock::now();
    cells_tricubic_ = std::make_shared<const MacrocellGrid>(build_macrocells(*volume_, 0, FilterSupport::Tricubic));
    macrocell_ms_ += ms_since(t1);
  }
  return *cells_tricubic_;
}

bool GpuVolume::drop_host_voxels() {
  if (!cells_trilinear_ || !cells_tricubic_) return false;  // a grid may still need the voxels
  volume_->drop_voxels();
  return true;
}

void GpuVolume::bind(unsigned unit) const { glBindTextureUnit(unit, texture_.id()); }

}  // namespace peakcast::render
