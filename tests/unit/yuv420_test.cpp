// The video encoders' RGB to 4:2:0 (server/encode/yuv420.h): the SIMD conversion gives the
// scalar one's bytes on every SIMD target this machine has, for widths that leave a scalar tail
// and for planes with padded strides; and the scalar one is BT.709 limited range.
#include <gtest/gtest.h>

#include <hwy/targets.h>

#include <cstdint>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include "encode/yuv420.h"

namespace peakcast::encode {
namespace {

struct Planes {
  std::vector<uint8_t> y, u, v;
  Yuv420Planes view;
  Planes(int w, int h, int pad) : y(size_t(w + pad) * h, 7), u(size_t(w / 2 + pad) * (h / 2), 7), v(u.size(), 7) {
    view = {y.data(), u.data(), v.data(), w + pad, w / 2 + pad, w / 2 + pad};
  }
};

// The first byte where two planes differ, or -1.
long first_difference(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i] != b[i]) return long(i);
  return -1;
}

TEST(Yuv420, SimdEqualsScalarOnEveryTarget) {
  std::mt19937 rng(3);
  const auto targets = hwy::SupportedAndGeneratedTargets();
  ASSERT_FALSE(targets.empty());
  for (const int64_t target : targets) {
    hwy::SetSupportedTargetsForTest(target);
    for (const auto& [w, h, pad] :
         {std::tuple{2, 2, 0}, {30, 4, 0}, {64, 8, 3}, {130, 6, 0}, {1024, 16, 32}, {998, 10, 1}}) {
      std::vector<uint8_t> rgb(size_t(w) * h * 3);
      for (auto& c : rgb) c = uint8_t(rng());
      for (size_t i = 0; i < rgb.size() && w > 8; i += 97) rgb[i] = (i / 97) % 2 ? 255 : 0;  // the extremes
      Planes simd(w, h, pad), scalar(w, h, pad);
      rgb_to_yuv420_bt709(rgb.data(), w, h, simd.view);
      rgb_to_yuv420_bt709_scalar(rgb.data(), w, h, scalar.view);
      const std::string at = hwy::TargetName(target) + std::string(" ") + std::to_string(w) + "x" + std::to_string(h);
      EXPECT_EQ(first_difference(simd.y, scalar.y), -1) << "Y, " << at;
      EXPECT_EQ(first_difference(simd.u, scalar.u), -1) << "Cb, " << at;
      EXPECT_EQ(first_difference(simd.v, scalar.v), -1) << "Cr, " << at;
    }
  }
  hwy::SetSupportedTargetsForTest(0);
}

TEST(Yuv420, ScalarIsBt709LimitedRange) {
  // Black, white and the primaries over a 2x2 block each: Y in 16..235, Cb and Cr in 16..240,
  // at BT.709's values (Y = 16 + 219 (0.2126 R + 0.7152 G + 0.0722 B), ...), rounded.
  const struct {
    uint8_t r, g, b;
    int y, u, v;
  } cases[] = {{0, 0, 0, 16, 128, 128},  {255, 255, 255, 235, 128, 128}, {255, 0, 0, 63, 102, 240},
               {0, 255, 0, 173, 42, 26}, {0, 0, 255, 32, 240, 118},      {128, 128, 128, 126, 128, 128}};
  for (const auto& c : cases) {
    std::vector<uint8_t> rgb(2 * 2 * 3);
    for (int i = 0; i < 4; ++i) {
      rgb[3 * i] = c.r;
      rgb[3 * i + 1] = c.g;
      rgb[3 * i + 2] = c.b;
    }
    Planes p(2, 2, 0);
    rgb_to_yuv420_bt709_scalar(rgb.data(), 2, 2, p.view);
    EXPECT_EQ(p.y[0], c.y) << int(c.r) << "," << int(c.g) << "," << int(c.b);
    EXPECT_EQ(p.y[3], c.y);
    EXPECT_EQ(p.u[0], c.u) << int(c.r) << "," << int(c.g) << "," << int(c.b);
    EXPECT_EQ(p.v[0], c.v) << int(c.r) << "," << int(c.g) << "," << int(c.b);
  }
}

}  // namespace
}  // namespace peakcast::encode
