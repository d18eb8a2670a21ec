// POST /api/slice's drawing (core/slice_view.h): which voxel lands on which pixel, for every axis
// and up, a fitted image, an oblique plane, a pyramid level, the grey window and the refusals.
#include <gtest/gtest.h>

#include "core/slice_view.h"

namespace peakcast {
namespace {

// 4 x 3 x 2 voxels, value i + 10 j + 100 k (uint16), spacing (1, 2, 3).
Volume counting_volume() {
  VolumeHeader h;
  h.dims = {4, 3, 2};
  h.spacing = {1, 2, 3};
  h.origin = {10, 20, 30};
  h.source = SourceType::U16;
  Volume v(h);
  auto* p = reinterpret_cast<uint16_t*>(v.data());
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i) p[i + 4 * (j + 3 * k)] = uint16_t(i + 10 * j + 100 * k);
  v.finalize_statistics();
  return v;
}

// The window 0..255 makes each pixel's grey the voxel's value.
SliceRequest axis(int a, int64_t index) {
  SliceRequest s;
  s.axis = a;
  s.index = index;
  s.window = std::array<double, 2>{0, 255};
  return s;
}

ResolvedScene scene_for(const Volume& v, std::optional<glm::dvec3> up = std::nullopt) {
  Scene s;
  s.volume = "v";
  if (up) {
    Camera c;
    c.eye = {0, 0, 100};
    c.up = *up;
    if (std::abs(up->z) > 0.5) c.eye = {100, 0, 0};
    s.camera = c;
  }
  return resolve_scene(s, v);
}

std::vector<int> values(const SliceImage& img) {
  std::vector<int> out;
  for (size_t p = 0; p < img.rgb.size(); p += 3) out.push_back(img.rgb[p]);
  return out;
}

TEST(SliceView, AxisSlicesAreSeenFromThePositiveSideWithTheDefaultUp) {
  const Volume v = counting_volume();
  // z from +z, +y up: +x right, the top row is the last y.
  SliceImage z = draw_slice(v, scene_for(v), axis(2, 1), std::nullopt);
  EXPECT_EQ(z.width, 4);
  EXPECT_EQ(z.height, 3);
  EXPECT_EQ(values(z), (std::vector<int>{120, 121, 122, 123, 110, 111, 112, 113, 100, 101, 102, 103}));
  // x from +x, +y up: -z right (z falls to the right), top row the last y.
  SliceImage x = draw_slice(v, scene_for(v), axis(0, 3), std::nullopt);
  EXPECT_EQ(x.width, 2);
  EXPECT_EQ(x.height, 3);
  EXPECT_EQ(values(x), (std::vector<int>{123, 23, 113, 13, 103, 3}));
  // y from +y, +z up: -x right, top row the last z.
  SliceImage y = draw_slice(v, scene_for(v), axis(1, 2), std::nullopt);
  EXPECT_EQ(y.width, 4);
  EXPECT_EQ(y.height, 2);
  EXPECT_EQ(values(y), (std::vector<int>{123, 122, 121, 120, 23, 22, 21, 20}));
}

TEST(SliceView, TheCameraUpIsSnappedIntoTheSlice) {
  const Volume v = counting_volume();
  // z slice with -y up (the camera upside down): +x to the left, the top row y = 0.
  SliceImage z = draw_slice(v, scene_for(v, glm::dvec3(0.1, -1, 0.2)), axis(2, 0), std::nullopt);
  EXPECT_EQ(values(z), (std::vector<int>{3, 2, 1, 0, 13, 12, 11, 10, 23, 22, 21, 20}));
  // z slice with +x up: rows run along x (4 rows of 3).
  SliceImage r = draw_slice(v, scene_for(v, glm::dvec3(1, 0, 0)), axis(2, 0), std::nullopt);
  EXPECT_EQ(r.width, 3);
  EXPECT_EQ(r.height, 4);
  EXPECT_EQ(values(r)[0], 23);  // top: the last x; right = -z x +x = -y, so the left column is the last y
}

TEST(SliceView, AFittedImageKeepsTheWorldAspectAndTheBackground) {
  const Volume v = counting_volume();
  ResolvedScene r = scene_for(v);
  r.scene.background = {1, 0, 0};
  // z slice: 4 x 6 world units (cells) into 8 x 8 pixels: 0.75 a pixel, so 4 / 0.75 = 5.33 pixels
  // wide, centred from 1.33 to 6.67: the first and last columns are the background.
  const SliceImage img = draw_slice(v, r, axis(2, 0), std::array<int, 2>{8, 8});
  ASSERT_EQ(img.width, 8);
  EXPECT_EQ(img.rgb[0], 255);  // top-left: the background
  EXPECT_EQ(img.rgb[1], 0);
  const size_t mid = (size_t(4) * 8 + 4) * 3;
  EXPECT_EQ(img.rgb[mid], img.rgb[mid + 1]);           // inside: grey
  EXPECT_EQ(img.rgb[(size_t(7) * 8 + 7) * 3 + 1], 0);  // bottom row, last column: background
  EXPECT_EQ(img.rgb[(size_t(7) * 8 + 1) * 3 + 0], img.rgb[(size_t(7) * 8 + 1) * 3 + 1]);  // column 1: inside
}

TEST(SliceView, APlaneThroughTheVolumeMatchesTheAxisSliceItEquals) {
  const Volume v = counting_volume();
  SliceRequest p;
  p.axis = -1;
  p.point = {10, 20, 33};  // z = 1
  p.normal = {0, 0, 2};
  p.window = std::array<double, 2>{0, 255};
  const SliceImage plane = draw_slice(v, scene_for(v), p, std::nullopt);
  // Pixels of the smallest spacing (1) over the box's 4 x 5 units: y 24, 23, ..., 20 from the top,
  // each the nearest voxel row (j 2, 2, 1, 1, 0).
  EXPECT_EQ(plane.width, 4);
  EXPECT_EQ(plane.height, 5);
  EXPECT_EQ(values(plane), (std::vector<int>{120, 121, 122, 123, 120, 121, 122, 123, 110, 111,
                                             112, 113, 110, 111, 112, 113, 100, 101, 102, 103}));
  p.normal = {0, 0, 0};
  EXPECT_THROW(draw_slice(v, scene_for(v), p, std::nullopt), SceneError);
}

TEST(SliceView, TheTfColoursTheValuesAndItsOpacityIsIgnored) {
  const Volume v = counting_volume();
  Scene s;
  s.volume = "v";
  s.tf = TransferFunction{{{0, 0, 0, 1, 0}, {123, 1, 0, 0, 0}}};  // blue to red, all transparent
  const ResolvedScene r = resolve_scene(s, v);
  SliceRequest q = axis(2, 1);
  q.window.reset();
  const SliceImage img = draw_slice(v, r, q, std::nullopt);
  EXPECT_GT(img.rgb[0], 240);  // top-left: 120 of 123 -> nearly red, although its opacity is 0
  EXPECT_LT(img.rgb[2], 10);
}

TEST(SliceView, APyramidLevelIsSlicedAtItsOwnIndexAndOutsideIndicesAreRefused) {
  Volume v = counting_volume();
  v.full_dims = {8, 6, 4};  // level 1 of a pyramid: level 0 has twice the voxels a side
  v.full_spacing = {0.5, 1, 1.5};
  const SliceImage img = draw_slice(v, scene_for(v), axis(2, 3), std::nullopt);
  EXPECT_EQ(img.index, 1);  // level-0 index 3 lies in level-1 voxel 1
  EXPECT_EQ(values(img)[0], 120);
  EXPECT_THROW(draw_slice(v, scene_for(v), axis(2, 4), std::nullopt), SceneError);
  EXPECT_THROW(draw_slice(v, scene_for(v), axis(0, -1), std::nullopt), SceneError);
}

TEST(SliceView, ParsingRefusesWhatIsNotASlice) {
  EXPECT_EQ(parse_slice(nlohmann::json::parse(R"({"axis": "y", "index": 3})")).axis, 1);
  EXPECT_EQ(parse_slice(nlohmann::json::parse(R"({"plane": {"point": [0,0,0], "normal": [0,1,0]}})")).axis, -1);
  for (const char* bad :
       {R"({"axis": "w", "index": 1})", R"({"axis": "x"})", R"({"axis": "x", "index": 1.5})", R"({"index": 1})",
        R"({"axis": "x", "index": 1, "plane": {}})", R"({"plane": {"point": [0,0], "normal": [0,0,1]}})",
        R"({"axis": "x", "index": 1, "window": [5, 5]})", R"({"axis": "x", "index": 1, "zoom": 2})", R"([1])"})
    EXPECT_THROW(parse_slice(nlohmann::json::parse(bad)), SceneError) << bad;
}

}  // namespace
}  // namespace peakcast
