// A volume made ready for one rendering backend, with its macrocell grids (docs/architecture.md):
// the GL backend's GlVolume (a 3D texture) or the CPU backend's CpuVolume (the host voxels).
// One per loaded volume, shared by every session that views it; render thread only.
#pragma once

#include <cstdint>
#include <memory>

#include "core/macrocells.h"
#include "core/scene.h"
#include "core/volume.h"

namespace peakcast::render {

class ResidentVolume {
 public:
  virtual ~ResidentVolume() = default;
  ResidentVolume(const ResidentVolume&) = delete;
  ResidentVolume& operator=(const ResidentVolume&) = delete;

  const Volume& volume() const { return *volume_; }
  std::shared_ptr<const Volume> shared() const { return volume_; }
  // The grid of a filter's support: of grid_dims(volume()), the whole volume's for a brick
  // (given, never built from the brick). A missing grid is built here (trilinear: in the
  // constructor; tricubic: at first use) on the calling thread: fine for the CLI and tests, a
  // stall for the server's render thread, which gets both from the loader.
  const MacrocellGrid& macrocells(Filter filter) const;
  double upload_ms() const { return upload_ms_; }        // the backend's copy, made in the constructor
  double macrocell_ms() const { return macrocell_ms_; }  // grids built on this thread so far
  // Bytes the backend holds for the voxels: the texture, or the CPU copy when there is one
  // besides the volume's own voxels (0 otherwise).
  virtual size_t resident_bytes() const = 0;
  // The TF table's domain: the volume's value range (table_range).
  double tf_lo() const { return lo_; }
  double tf_hi() const { return hi_; }
  // Frees the volume's host voxels (Volume::drop_voxels) when the backend holds its own copy
  // and both grids exist; false (nothing freed) otherwise. The server calls it only for a copy
  // whose voxels live elsewhere: its probes read the host voxels (Residency).
  virtual bool drop_host_voxels() = 0;
  // The voxels live in the ranks' bricks of a distributed volume, not in this process.
  bool voxels_elsewhere() const { return elsewhere_; }
  uint64_t serial() const { return serial_; }  // unique per copy: caches key on it, not on addresses

 protected:
  // Checks the grids against the volume (std::invalid_argument) and takes the value range.
  ResidentVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells);
  // A copy whose voxels live elsewhere (the ranks' bricks of a distributed volume): the volume
  // may have none, and there are no grids (macrocells() throws).
  struct VoxelsElsewhere {};
  ResidentVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells, VoxelsElsewhere);
  // Builds the trilinear grid when the loader did not: derived constructors call it once their
  // copy is made (it reads the voxels).
  void ensure_trilinear_grid();
  bool has_both_grids() const { return cells_trilinear_ && cells_tricubic_; }
  // A brick (a region read) cannot build its grids from its voxels: std::invalid_argument.
  void no_brick_grid() const;

  std::shared_ptr<const Volume> volume_;
  double upload_ms_ = 0.0;

 private:
  bool elsewhere_ = true;  // cleared by the constructor for a copy made here
  std::shared_ptr<const MacrocellGrid> cells_trilinear_;
  mutable std::shared_ptr<const MacrocellGrid> cells_tricubic_;
  mutable double macrocell_ms_ = 0.0;
  double lo_ = 0, hi_ = 1;
  uint64_t serial_ = 0;
};

}  // namespace peakcast::render
