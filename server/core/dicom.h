// DICOM series (docs/scenes.md, "DICOM"): a folder of slice files of one series opens as one
// volume, read through GDCM (Debian's libgdcm). Slices are ordered by their position along the
// slice normal, never by file name or instance number; the rescale slope and intercept are
// applied (CT: Hounsfield units). Patient names and other identifiers are never read into
// anything peakcast keeps, logs or answers: only geometry, pixel format, modality and the
// series' description and UID.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/volume_io.h"

namespace peakcast::dicom {

// What one slice file says of itself (dicom_series.cpp reads it; dicom_geometry.cpp orders it).
struct SliceHeader {
  std::filesystem::path file;
  std::string series_uid, description, modality;
  bool has_position = false, has_orientation = false, has_spacing = false;
  glm::dvec3 position{0.0};
  glm::dvec3 row{1, 0, 0}, col{0, 1, 0};        // ImageOrientationPatient: along a row, down a column
  double row_spacing = 1.0, col_spacing = 1.0;  // PixelSpacing: between rows (y), between columns (x)
  double thickness = 0.0;                       // SliceThickness; 0: not given
  int rows = 0, cols = 0, frames = 1, samples = 1;
  int bits_allocated = 0, bits_stored = 0;
  bool is_signed = false, monochrome1 = false;
  double slope = 1.0, intercept = 0.0;
};

// The slices of a series in volume order: ascending along the normal row x col.
struct SeriesGeometry {
  std::vector<size_t> order;  // indices into the slices given
  double gap = 1.0;           // the positions' spacing along the normal (SliceThickness for one slice)
  glm::dvec3 origin{0.0};     // the first slice's position
};
// Orders the slices and checks they form a grid: one orientation and size, distinct positions,
// even gaps (within 1% of the mean), and each step along the normal (a gantry tilt is refused).
// Throws VolumeError naming `dir`, the gap or the tilt, and the files.
SeriesGeometry order_slices(const std::filesystem::path& dir, const std::vector<SliceHeader>& slices);

// A series found in a folder, as the data browser lists it.
struct SeriesSummary {
  std::string uid, description, modality;
  int64_t slices = 0;
  int rows = 0, cols = 0;
};

// A folder and, after its last '#', which of its series ("" when the path names none):
// "ct/#1.2.840.113619.2" by SeriesInstanceUID or "ct/#Bone 1.0" by description. A path that
// exists as it is names no series.
struct SeriesPath {
  std::filesystem::path folder;
  std::string series;
};
SeriesPath split_series_path(const std::filesystem::path& path);

// True when the folder holds a DICOM file (the "DICM" mark at byte 128) among its first entries.
bool is_dicom_folder(const std::filesystem::path& dir);
// Every series of the folder's DICOM files (not its subfolders), in the order of their UIDs.
std::vector<SeriesSummary> list_series(const std::filesystem::path& dir);
// The series that `path` names (a folder of one series, or a folder '#' a series) as a volume.
// Refuses a folder of several series without a choice, naming them.
Volume read_series(const std::filesystem::path& path, const LoadOptions& options);

}  // namespace peakcast::dicom
