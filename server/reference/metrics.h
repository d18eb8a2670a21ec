// Error metrics over RGB in [0, 1] (docs/accuracy.md).
#pragma once

#include <string>

#include "core/image.h"

namespace peakcast::reference {

struct ImageError {
  double rmse = 0, psnr = 0, max_abs = 0;
  double share_off = 0;  // pixels with some channel off by more than 1/255
  std::string to_json() const;
};

// Throws std::invalid_argument when the sizes differ. PSNR is capped at 200 dB for equal images.
ImageError compare(const Image& a, const Image& b);

}  // namespace peakcast::reference
