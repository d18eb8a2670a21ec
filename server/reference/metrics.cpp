#include "reference/metrics.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <stdexcept>

namespace peakcast::reference {

ImageError compare(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height)
    throw std::invalid_argument("image sizes differ: " + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                " vs " + std::to_string(b.width) + "x" + std::to_string(b.height));
  ImageError e;
  double sum = 0;
  size_t off = 0;
  const size_t n = size_t(a.width) * a.height;
  for (size_t p = 0; p < n; ++p) {
    bool pixel_off = false;
    for (int c = 0; c < 3; ++c) {
      const double d = std::abs(double(a.rgba[p * 4 + c]) - double(b.rgba[p * 4 + c]));
      sum += d * d;
      e.max_abs = std::max(e.max_abs, d);
      pixel_off |= d > 1.0 / 255.0;
    }
    off += pixel_off;
  }
  e.rmse = std::sqrt(sum / double(std::max<size_t>(n * 3, 1)));
  e.psnr = e.rmse > 0 ? std::min(200.0, 20.0 * std::log10(1.0 / e.rmse)) : 200.0;
  e.share_off = double(off) / double(std::max<size_t>(n, 1));
  return e;
}

std::string ImageError::to_json() const {
  return nlohmann::json{{"rmse", rmse}, {"psnr", psnr}, {"max_abs", max_abs}, {"share_off_1_255", share_off}}.dump(
      -1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace peakcast::reference
