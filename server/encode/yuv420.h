// RGB to BT.709 limited-range 4:2:0, what the video encoders are fed (docs/streaming.md).
// 16-bit fixed point (coefficients x 65536, rounded); each chroma sample is the mean of its
// 2x2 block (centre-sited). The SIMD version (Highway, the best x86 target chosen at run time)
// gives the same bytes as the scalar one, which stays as its reference.
#pragma once

#include <cstdint>

namespace peakcast::encode {

struct Yuv420Planes {
  uint8_t* y;
  uint8_t* u;  // Cb
  uint8_t* v;  // Cr
  int y_stride, u_stride, v_stride;
};

// rgb: width * height * 3 bytes, rows packed, row 0 at the top. width and height even.
void rgb_to_yuv420_bt709(const uint8_t* rgb, int width, int height, const Yuv420Planes& out);
void rgb_to_yuv420_bt709_scalar(const uint8_t* rgb, int width, int height, const Yuv420Planes& out);

}  // namespace peakcast::encode
