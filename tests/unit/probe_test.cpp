// The probe (reference/reference_renderer.h probe_reference): the ray's first visible surface, or
// where along a pixel's ray the accumulated opacity passes one half, on a ramp whose answers are
// known in closed form.
#include <gtest/gtest.h>

#include <cmath>

#include "core/generators.h"
#include "reference/reference_renderer.h"

using namespace peakcast;

namespace {

Volume ramp() {  // value x / 32 on the box [0,32] x [0,16] x [0,16]
  GeneratorSpec g;
  g.kind = GeneratorKind::Ramp;
  g.dims = {33, 17, 17};
  g.type = SourceType::F32;
  return generate_volume(g);
}

// Seen orthographically along +x from x < 0: 9 x 9 pixels over an 8 x 8 window around y = z = 8,
// or a 40 x 40 one that reaches past the box.
ResolvedScene scene(const Volume& v, const nlohmann::json& tf, const nlohmann::json& render, double window = 8) {
  nlohmann::json j = {{"volume", "x"},
                      {"image", {{"width", 9}, {"height", 9}}},
                      {"camera",
                       {{"eye", {-100, 8, 8}},
                        {"center", {16, 8, 8}},
                        {"up", {0, 0, 1}},
                        {"projection", "orthographic"},
                        {"height", window}}},
                      {"tf", tf},
                      {"render", render}};
  return resolve_scene(parse_scene(j), v);
}

constexpr auto kHalf = reference::ProbePick::Half;

const nlohmann::json kOpaqueFromHalf = {
    {"points", {{0.0, 1, 1, 1, 0}, {0.49, 1, 1, 1, 0}, {0.5, 1, 1, 1, 1}, {1.0, 1, 1, 1, 1}}}};

TEST(Probe, PostClassificationFindsTheOpaqueSide) {
  Volume v = ramp();
  const auto p = reference::probe_reference(v, scene(v, kOpaqueFromHalf, {{"step", 0.25}}), 4, 4, kHalf);
  ASSERT_TRUE(p.hit);
  EXPECT_NEAR(p.position.x, 16.0, 1e-9);  // the first sample at 0.5 is at x = 16 (lattice from x = 0)
  EXPECT_NEAR(p.position.y, 8.0, 1e-9);
  EXPECT_NEAR(p.position.z, 8.0, 1e-9);
  EXPECT_NEAR(p.value, 0.5, 1e-6);
  EXPECT_NEAR(p.distance, 116.0, 1e-9);  // from the image plane through the eye
  EXPECT_GT(p.opacity, 0.99);
}

TEST(Probe, PixelsCountFromTheTopLeft) {
  Volume v = ramp();
  // Right is -y and up is +z: pixel (1, 2) lies at y = 8 + 4 * (1 - 2 * 1.5 / 9), z = 8 + 4 * (1 - 2 * 2.5 / 9).
  const auto p = reference::probe_reference(v, scene(v, kOpaqueFromHalf, {{"step", 0.25}}), 1, 2, kHalf);
  ASSERT_TRUE(p.hit);
  EXPECT_NEAR(p.position.y, 8.0 + 4.0 * (1.0 - 3.0 / 9.0), 1e-9);
  EXPECT_NEAR(p.position.z, 8.0 + 4.0 * (1.0 - 5.0 / 9.0), 1e-9);
}

TEST(Probe, APeakSurfaceIsFoundAtItsExactCrossing) {
  Volume v = ramp();
  const nlohmann::json tent = {
      {"points", {{0.0, 1, 0, 0, 0}, {0.6, 1, 0, 0, 0}, {0.625, 1, 0, 0, 0.9}, {0.65, 1, 0, 0, 0}, {1.0, 1, 0, 0, 0}}}};
  const auto p = reference::probe_reference(
      v, scene(v, tent, {{"classification", "peaks"}, {"peak_mode", "peaks_only"}, {"step", 1.0}}), 4, 4);
  ASSERT_TRUE(p.hit);
  EXPECT_NEAR(p.position.x, 20.0, 1e-6);  // 0.625 * 32: regula falsi is exact on a linear field
  EXPECT_DOUBLE_EQ(p.value, 0.625);
  EXPECT_NEAR(p.opacity, 0.9, 1e-9);
}

TEST(Probe, NoHitWhereTheRayStaysBelowOneHalf) {
  Volume v = ramp();
  const nlohmann::json faint = {{"points", {{0.0, 1, 1, 1, 0.001}, {1.0, 1, 1, 1, 0.001}}}};
  const auto p = reference::probe_reference(v, scene(v, faint, {{"step", 1.0}}), 4, 4);
  EXPECT_FALSE(p.hit);
  EXPECT_GT(p.opacity, 0.0);
  EXPECT_LT(p.opacity, 0.5);
  // A pixel whose ray misses the box (the 40-unit window reaches past y, z in [0, 16]).
  const auto miss = reference::probe_reference(v, scene(v, kOpaqueFromHalf, {{"step", 1.0}}, 40), 0, 0);
  EXPECT_FALSE(miss.hit);
  EXPECT_EQ(miss.opacity, 0.0);
}

// A translucent TF (opacity 0.1 per unit from value 0.25, x = 8, on): the eye sees the front, where
// the first surface pick lands; the ray gets half opaque only about 6.6 units deeper.
TEST(Probe, TheFirstSurfaceIsTheFrontOfATranslucentTf) {
  Volume v = ramp();
  const nlohmann::json haze = {
      {"points", {{0.0, 1, 1, 1, 0}, {0.24, 1, 1, 1, 0}, {0.25, 1, 1, 1, 0.1}, {1.0, 1, 1, 1, 0.1}}}};
  const ResolvedScene s = scene(v, haze, {{"step", 0.25}});
  const auto surface = reference::probe_reference(v, s, 4, 4);  // the default pick
  ASSERT_TRUE(surface.hit);
  EXPECT_EQ(surface.pick, reference::ProbePick::Surface);
  EXPECT_NEAR(surface.position.x, 8.0, 1e-9);  // the first sample with TF opacity >= 0.05: value 0.25
  EXPECT_NEAR(surface.value, 0.25, 1e-6);
  const auto half = reference::probe_reference(v, s, 4, 4, kHalf);
  ASSERT_TRUE(half.hit);
  EXPECT_EQ(half.pick, reference::ProbePick::Half);
  // 1 - 0.9^d = 0.5 at d = 6.58 units past x = 8 (samples every 0.25)
  EXPECT_NEAR(half.position.x, 8.0 + std::log(0.5) / std::log(0.9), 0.3);
  EXPECT_EQ(surface.opacity, half.opacity);
  // A TF never that opaque (0.04 per unit) but half opaque after 17 units: the half point answers.
  const nlohmann::json faint = {{"points", {{0.0, 1, 1, 1, 0.04}, {1.0, 1, 1, 1, 0.04}}}};
  const ResolvedScene f = scene(v, faint, {{"step", 0.25}});
  const auto fallback = reference::probe_reference(v, f, 4, 4);
  ASSERT_TRUE(fallback.hit);
  EXPECT_EQ(fallback.pick, reference::ProbePick::Half);
  EXPECT_EQ(fallback.position, reference::probe_reference(v, f, 4, 4, kHalf).position);
  EXPECT_STREQ(reference::to_string(reference::ProbePick::Surface), "surface");
  EXPECT_EQ(reference::parse_probe_pick("half"), kHalf);
  EXPECT_THROW(reference::parse_probe_pick("middle"), std::invalid_argument);
}

TEST(Probe, Refusals) {
  Volume v = ramp();
  const ResolvedScene s = scene(v, kOpaqueFromHalf, {{"step", 1.0}});
  for (auto [x, y] : {std::pair{-1, 0}, {0, -1}, {9, 0}, {0, 9}}) {
    try {
      reference::probe_reference(v, s, x, y);
      ADD_FAILURE() << x << "," << y;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("outside the 9 x 9 image"), std::string::npos) << e.what();
    }
  }
  VolumeHeader h;
  h.dims = {33, 17, 17};
  const Volume bricks = Volume::header_only(h);
  EXPECT_THROW(reference::probe_reference(bricks, s, 4, 4), std::invalid_argument);
}

}  // namespace
