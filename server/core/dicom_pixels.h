// A DICOM series' pixels into one volume (dicom_pixels.cpp): decoded slice by slice through
// GDCM, rescaled, and kept in the narrowest type that holds the values exactly.
#pragma once

#include <filesystem>
#include <vector>

#include "core/dicom.h"

namespace peakcast::dicom {

// The kept type (docs/scenes.md, "DICOM"): physical = stored x slope + intercept, per slice.
// 8-bit slices without a rescale stay uint8; integer slopes and intercepts give uint16 for
// unsigned slices whose values are all in 0..65535, else int16 when they fit it (CT in HU: the
// intercept makes them negative), else uint16 when they fit it; anything else float32. MONOCHROME1
// (bright is low) is inverted over the series' range: lo + hi - value.
Volume read_pixels(const std::filesystem::path& dir, const std::vector<SliceHeader>& slices, const SeriesGeometry& g,
                   const LoadOptions& options);

}  // namespace peakcast::dicom
