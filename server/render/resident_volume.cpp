#include "render/resident_volume.h"

#include <atomic>
#include <chrono>
#include <stdexcept>

#include "core/value_range.h"
#include "render/small_cache.h"

namespace peakcast::render {

ResidentVolume::ResidentVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells)
    : ResidentVolume(std::move(volume), std::move(cells), VoxelsElsewhere{}) {
  if (!volume_->has_voxels()) throw std::invalid_argument("ResidentVolume: the volume's voxels were dropped");
  elsewhere_ = false;
}

ResidentVolume::ResidentVolume(std::shared_ptr<const Volume> volume, VolumeMacrocells cells, VoxelsElsewhere)
    : volume_(std::move(volume)),
      cells_trilinear_(std::move(cells.trilinear)),
      cells_tricubic_(std::move(cells.tricubic)) {
  if (!volume_) throw std::invalid_argument("ResidentVolume: no volume");
  if (cells_trilinear_) check_macrocells(*cells_trilinear_, *volume_, FilterSupport::Trilinear);
  if (cells_tricubic_) check_macrocells(*cells_tricubic_, *volume_, FilterSupport::Tricubic);
  static std::atomic<uint64_t> next_serial{1};
  serial_ = next_serial++;
  const ValueRange range = table_range(volume_->min_value, volume_->max_value);
  lo_ = range.lo;
  hi_ = range.hi;
}

void ResidentVolume::ensure_trilinear_grid() {
  if (cells_trilinear_) return;
  no_brick_grid();
  const auto t1 = Clock::now();
  cells_trilinear_ = std::make_shared<const MacrocellGrid>(build_macrocells(*volume_, 0, FilterSupport::Trilinear));
  macrocell_ms_ += ms_since(t1);
}

void ResidentVolume::no_brick_grid() const {
  if (grid_dims(*volume_) != volume_->dims())
    throw std::invalid_argument(
        "ResidentVolume: a brick walks the whole volume's macrocell grids, which its voxels "
        "cannot build: pass them (core/macrocell_share.h)");
}

const MacrocellGrid& ResidentVolume::macrocells(Filter filter) const {
  if (filter != Filter::Tricubic) {
    if (!cells_trilinear_) throw std::logic_error("ResidentVolume: no macrocell grid (the voxels live elsewhere)");
    return *cells_trilinear_;
  }
  if (!cells_tricubic_) {  // most views never ask for the wider filter support
    if (!volume_->has_voxels()) throw std::logic_error("ResidentVolume: no tricubic grid and no voxels to build it");
    no_brick_grid();
    const auto t1 = Clock::now();
    cells_tricubic_ = std::make_shared<const MacrocellGrid>(build_macrocells(*volume_, 0, FilterSupport::Tricubic));
    macrocell_ms_ += ms_since(t1);
  }
  return *cells_tricubic_;
}

}  // namespace peakcast::render
