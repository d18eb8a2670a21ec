// rgb_to_yuv420_bt709: each pair of rows at once, 2N pixels a step (N = int32 lanes), the rest
// of a row in scalar code. Integer arithmetic throughout, so every target gives the scalar bytes.
#include "encode/yuv420.h"

#include <cstddef>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "encode/yuv420.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#ifndef PEAKCAST_YUV420_SCALAR
#define PEAKCAST_YUV420_SCALAR
namespace peakcast::encode::detail {

// BT.709 limited range, x 65536: Y from one pixel, Cb and Cr from the sums of a 2x2 block (so
// shifted by 18, not 16). Offsets include the rounding half.
constexpr int kYr = 11966, kYg = 40254, kYb = 4064, kYoff = (16 << 16) + 32768;
constexpr int kCbR = -6597, kCbG = -22187, kCbB = 28784;
constexpr int kCrR = 28784, kCrG = -26148, kCrB = -2637;
constexpr int kCoff = (512 << 16) + 131072;

inline uint8_t luma(const uint8_t* p) { return uint8_t((kYr * p[0] + kYg * p[1] + kYb * p[2] + kYoff) >> 16); }

// Pixels [x0, w) of the row pair (x0 even).
inline void row_pair_scalar(const uint8_t* row0, const uint8_t* row1, int x0, int w, uint8_t* y0, uint8_t* y1,
                            uint8_t* cb, uint8_t* cr) {
  for (int x = x0; x < w; ++x) {
    y0[x] = luma(row0 + 3 * x);
    y1[x] = luma(row1 + 3 * x);
  }
  for (int x = x0 / 2; x < w / 2; ++x) {
    const uint8_t *a = row0 + 6 * x, *b = row1 + 6 * x;
    const int R = a[0] + a[3] + b[0] + b[3], G = a[1] + a[4] + b[1] + b[4], B = a[2] + a[5] + b[2] + b[5];
    cb[x] = uint8_t((kCbR * R + kCbG * G + kCbB * B + kCoff) >> 18);
    cr[x] = uint8_t((kCrR * R + kCrG * G + kCrB * B + kCoff) >> 18);
  }
}

struct RowPair {
  const uint8_t *row0, *row1;
  uint8_t *y0, *y1, *cb, *cr;
};

inline RowPair row_pair(const uint8_t* rgb, int w, const Yuv420Planes& o, int r) {
  const size_t top = size_t(2 * r);
  return {rgb + top * size_t(w) * 3,
          rgb + (top + 1) * size_t(w) * 3,
          o.y + top * size_t(o.y_stride),
          o.y + (top + 1) * size_t(o.y_stride),
          o.u + size_t(r) * size_t(o.u_stride),
          o.v + size_t(r) * size_t(o.v_stride)};
}

inline void convert_scalar(const uint8_t* rgb, int w, int h, const Yuv420Planes& o) {
  for (int r = 0; r < h / 2; ++r) {
    const RowPair p = row_pair(rgb, w, o, r);
    row_pair_scalar(p.row0, p.row1, 0, w, p.y0, p.y1, p.cb, p.cr);
  }
}

}  // namespace peakcast::encode::detail
#endif

HWY_BEFORE_NAMESPACE();
namespace peakcast::encode {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

void ConvertRows(const uint8_t* rgb, int w, int h, const Yuv420Planes& o) {
  using namespace detail;
#if HWY_TARGET == HWY_SCALAR  // one lane: nothing to gain, and no ConcatEven
  convert_scalar(rgb, w, h, o);
#else
  const hn::ScalableTag<int32_t> d32;
  const hn::Rebind<uint8_t, decltype(d32)> d8;  // as many u8 lanes as int32 lanes
  using V = hn::Vec<decltype(d32)>;
  const int n = int(hn::Lanes(d32));
  struct Rgb {
    V r, g, b;
  };
  const auto load = [&](const uint8_t* p) HWY_ATTR {
    hn::Vec<decltype(d8)> r, g, b;
    hn::LoadInterleaved3(d8, p, r, g, b);
    return Rgb{hn::PromoteTo(d32, r), hn::PromoteTo(d32, g), hn::PromoteTo(d32, b)};
  };
  const auto store_luma = [&](const Rgb& c, uint8_t* out) HWY_ATTR {
    const V y = hn::Add(hn::Add(hn::Mul(c.r, hn::Set(d32, kYr)), hn::Mul(c.g, hn::Set(d32, kYg))),
                        hn::Add(hn::Mul(c.b, hn::Set(d32, kYb)), hn::Set(d32, kYoff)));
    hn::StoreU(hn::DemoteTo(d8, hn::ShiftRight<16>(y)), d8, out);
  };
  // The sums of each horizontal pair of pixels: lanes 0..n-1 from the 2n pixels in lo, hi.
  const auto pairs = [&](V lo, V hi)
                         HWY_ATTR { return hn::Add(hn::ConcatEven(d32, hi, lo), hn::ConcatOdd(d32, hi, lo)); };
  const auto chroma = [&](V R, V G, V B, int cr, int cg, int cb) HWY_ATTR {
    const V s = hn::Add(hn::Add(hn::Mul(R, hn::Set(d32, cr)), hn::Mul(G, hn::Set(d32, cg))),
                        hn::Add(hn::Mul(B, hn::Set(d32, cb)), hn::Set(d32, kCoff)));
    return hn::DemoteTo(d8, hn::ShiftRight<18>(s));
  };
  for (int r = 0; r < h / 2; ++r) {
    const RowPair p = row_pair(rgb, w, o, r);
    int x = 0;
    for (; x + 2 * n <= w; x += 2 * n) {
      const Rgb a0 = load(p.row0 + 3 * x), b0 = load(p.row0 + 3 * (x + n));
      const Rgb a1 = load(p.row1 + 3 * x), b1 = load(p.row1 + 3 * (x + n));
      store_luma(a0, p.y0 + x);
      store_luma(b0, p.y0 + x + n);
      store_luma(a1, p.y1 + x);
      store_luma(b1, p.y1 + x + n);
      const V R = hn::Add(pairs(a0.r, b0.r), pairs(a1.r, b1.r));
      const V G = hn::Add(pairs(a0.g, b0.g), pairs(a1.g, b1.g));
      const V B = hn::Add(pairs(a0.b, b0.b), pairs(a1.b, b1.b));
      hn::StoreU(chroma(R, G, B, kCbR, kCbG, kCbB), d8, p.cb + x / 2);
      hn::StoreU(chroma(R, G, B, kCrR, kCrG, kCrB), d8, p.cr + x / 2);
    }
    row_pair_scalar(p.row0, p.row1, x, w, p.y0, p.y1, p.cb, p.cr);
  }
#endif
}

}  // namespace HWY_NAMESPACE
}  // namespace peakcast::encode
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace peakcast::encode {
HWY_EXPORT(ConvertRows);

void rgb_to_yuv420_bt709(const uint8_t* rgb, int width, int height, const Yuv420Planes& out) {
  HWY_DYNAMIC_DISPATCH(ConvertRows)(rgb, width, height, out);
}

void rgb_to_yuv420_bt709_scalar(const uint8_t* rgb, int width, int height, const Yuv420Planes& out) {
  detail::convert_scalar(rgb, width, height, out);
}

}  // namespace peakcast::encode
#endif
