// A scalar volume held in its native voxel type (docs/scenes.md).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/voxel_memory.h"

namespace peakcast {

// How voxels are kept in memory and on the GPU (R8 / R16 / R32F).
enum class VoxelType { U8, U16, F32 };

// How voxels were stored in the file; signed integers are shifted to unsigned on load and the
// shift is kept in Volume::value_offset so that physical values keep their meaning.
enum class SourceType { U8, I8, U16, I16, F32 };

const char* to_string(VoxelType t);
const char* to_string(SourceType t);
size_t voxel_bytes(VoxelType t);
size_t source_bytes(SourceType t);
VoxelType storage_type(SourceType t);
double storage_offset(SourceType t);  // physical = stored + offset
// Parses "uint8", "int16", "float32", ... (NRRD, JSON sidecar and CLI spellings). Throws.
SourceType parse_source_type(const std::string& name);

using Dims = std::array<int64_t, 3>;

struct VolumeHeader {
  Dims dims{0, 0, 0};
  glm::dvec3 spacing{1.0, 1.0, 1.0};
  glm::dvec3 origin{0.0, 0.0, 0.0};
  SourceType source = SourceType::U8;
  bool big_endian = false;
  std::string unit;        // the spacing's unit, an SI symbol (core/length_unit.h); "": the file names none
  std::string value_unit;  // Volume::value_unit
  int64_t time_point = 0, time_points = 1;  // a time series: the point read, of how many
  int64_t voxel_count() const { return dims[0] * dims[1] * dims[2]; }
};

class Volume {
 public:
  Volume() = default;
  // Allocates uninitialised storage for the header's dims in storage_type(header.source), plus
  // kTailPadding zero bytes after the last voxel.
  static constexpr size_t kTailPadding = 16;
  explicit Volume(const VolumeHeader& header);
  // The header's dims, type, spacing and origin without voxels (has_voxels() is false): a
  // distributed volume on the rank that serves it, whose voxels live in the ranks' bricks.
  static Volume header_only(const VolumeHeader& header);

  const Dims& dims() const { return dims_; }
  int64_t voxel_count() const { return dims_[0] * dims_[1] * dims_[2]; }
  VoxelType type() const { return type_; }
  SourceType source_type() const { return source_; }
  size_t byte_size() const { return size_t(voxel_count()) * voxel_bytes(type_); }
  // The voxels, x fastest. kTailPadding readable zero bytes follow them: the CPU backend's
  // gathers load 4 bytes at a voxel's address (cpu/sampler.h).
  uint8_t* data() { return data_.get(); }
  const uint8_t* data() const { return data_.get(); }
  // The voxels, freed once another copy holds them: a brick's once its backend copy is made
  // (render --memory-budget-mib), a distributed volume's on the serving rank once the ranks'
  // bricks hold them. Everything but the voxels stays (dims, spacing, range, histogram). The one
  // mutation of a shared volume: callers guarantee no other thread reads voxels any more (the
  // server keeps every other volume's voxels: its probes read them on the loader pool).
  void drop_voxels() const { data_.reset(); }
  bool has_voxels() const { return data_ != nullptr || voxel_count() == 0; }

  glm::dvec3 spacing{1.0, 1.0, 1.0};
  glm::dvec3 origin{0.0, 0.0, 0.0};
  double value_offset = 0.0;  // physical value = stored value + value_offset
  std::string unit;           // spacing and origin's unit ("µm"; core/length_unit.h); "": unknown
  // What the values are: "HU" (Hounsfield units: a CT series, or a file that says so), "": the
  // data's own units, unknown. The viewer's CT presets place their values in HU only then.
  std::string value_unit;
  // A DICOM series' modality ("CT", "MR") and SeriesDescription; "" for other formats.
  std::string modality, description;
  // A time series (an OME-Zarr with a t axis): the time point these voxels are, of how many.
  int64_t time_point = 0, time_points = 1;

  // Physical value of voxel (i, j, k); no bounds check.
  double value(int64_t i, int64_t j, int64_t k) const {
    return stored(size_t(i + dims_[0] * (j + dims_[1] * k))) + value_offset;
  }
  double stored(size_t index) const {
    switch (type_) {
      case VoxelType::U8: return data_[index];
      case VoxelType::U16: return reinterpret_cast<const uint16_t*>(data_.get())[index];
      case VoxelType::F32: return reinterpret_cast<const float*>(data_.get())[index];
    }
    return 0.0;
  }
  glm::dvec3 extent() const {  // world size of the box: (n-1) * spacing
    return glm::dvec3(dims_[0] - 1, dims_[1] - 1, dims_[2] - 1) * spacing;
  }

  // Computed by finalize(): physical value range, histogram, non-finite count.
  double min_value = 0.0, max_value = 0.0;
  std::vector<uint64_t> histogram;  // kHistogramBins bins over [min_value, max_value]
  // The voxels on the box's six faces, in the histogram's bins: which values the data's
  // background has (the automatic TF, core/auto_tf.h). Empty where not counted.
  std::vector<uint64_t> border_histogram;
  int64_t nonfinite_replaced = 0;
  // A region read (LoadOptions::region): the file's whole dims and where the region starts in
  // them; for a whole read source_dims is {0, 0, 0}.
  Dims source_dims{0, 0, 0};
  Dims region_lo{0, 0, 0};
  // A level of a chunked pyramid (chunked/): which one, of how many, and level 0's dims.
  int pyramid_level = 0, pyramid_levels = 1;
  Dims full_dims{0, 0, 0};
  // Level 0's spacing for a coarser level ({0, 0, 0}: this volume's own): the default opacity
  // unit and the automatic TF follow it, so every level of a pyramid draws the same picture.
  glm::dvec3 full_spacing{0.0};
  double load_ms = 0.0;        // the whole load_volume call
  double statistics_ms = 0.0;  // of it: range and histogram (finalize_statistics)
  std::string name;
  std::string source_path;  // the file or folder it was read from (load_volume); empty if made

  static constexpr int kHistogramBins = 1024;

  // Computes range and histogram (and nothing else); loaders call it once voxels are in.
  void finalize_statistics();
  // The voxels of the box [lo, hi) of this volume's grid counted into kHistogramBins bins over
  // the stored range [stored_lo, stored_hi], binned as finalize_statistics bins: a distributed
  // volume's histogram is the sum of its bricks' own boxes (distributed/).
  std::vector<uint64_t> box_histogram(const Dims& lo, const Dims& hi, double stored_lo, double stored_hi) const;
  // The voxels of the box [lo, hi) that lie on a face of the whole volume, whose first and last
  // planes along axis a are face_lo[a] and face_hi[a] of this grid (a brick's: the whole volume's
  // planes in the brick's coordinates, which may lie outside it), each passed to count(stored)
  // once. box_border_histogram bins them as box_histogram does.
  void for_each_border_voxel(const Dims& lo, const Dims& hi, const Dims& face_lo, const Dims& face_hi,
                             const std::function<void(double)>& count) const;
  std::vector<uint64_t> box_border_histogram(const Dims& lo, const Dims& hi, const Dims& face_lo, const Dims& face_hi,
                                             double stored_lo, double stored_hi) const;
  // Integer volumes: how many voxels of the box hold each stored value (256 or 65536 counts),
  // from which range and histogram follow exactly (histogram_of_counts), one pass over the voxels.
  // std::logic_error for float volumes.
  std::vector<uint64_t> box_value_counts(const Dims& lo, const Dims& hi) const;
  // The kHistogramBins bins over [stored_lo, stored_hi] of those counts: box_histogram's bins.
  static std::vector<uint64_t> histogram_of_counts(const std::vector<uint64_t>& counts, double stored_lo,
                                                   double stored_hi);
  std::string to_string() const;

 private:
  std::vector<uint64_t> whole_border_histogram(double stored_lo, double stored_hi) const;
  Dims dims_{0, 0, 0};
  VoxelType type_ = VoxelType::U8;
  SourceType source_ = SourceType::U8;
  mutable VoxelArray<uint8_t> data_;
};

}  // namespace peakcast
