// Serving under MPI: a session's ray texture reaches the workers inside the render commands
// (distributed/ray_texture_sync.h): whole once, then only the new strokes; each worker keeps one spec
// per texture, whose lineage stays put, so its renderer applies only the new strokes.
#include <gtest/gtest.h>

#include <memory>

#include "core/ray_texture.h"
#include "distributed/ray_texture_sync.h"

using namespace peakcast;

namespace {

Stroke stroke(RayChannel c, double u, double value) {
  Stroke s;
  s.channel = c;
  s.u = u;
  s.v = 0.5;
  s.radius = 0.2;
  s.value = value;
  return s;
}

// Through CBOR, as the render command carries it.
nlohmann::json wire(const nlohmann::json& j) { return nlohmann::json::from_cbor(nlohmann::json::to_cbor(j)); }

TEST(RayTextureSync, WholeOnceThenOnlyTheNewStrokes) {
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "volume"}, {"size", {40, 20}}}));
  spec = with_stroke(*spec, stroke(RayChannel::Termination, 0.3, 0.2));
  distributed::RayTextureSender sender;
  distributed::RayTextureReceiver receiver;
  nlohmann::json m = sender.message(*spec);
  EXPECT_EQ(m["from"], 0);
  EXPECT_EQ(m["strokes"].size(), 1u);
  const auto first = receiver.apply(wire(m));
  EXPECT_EQ(first->mapping, RayTextureMapping::Volume);
  EXPECT_EQ(first->width, 40);
  EXPECT_EQ(first->height, 20);
  EXPECT_EQ(to_json(*first), to_json(*spec));

  spec = with_stroke(*spec, stroke(RayChannel::Step, 0.6, 3.0));
  spec = with_stroke(*spec, stroke(RayChannel::Blend, 0.4, -0.5));
  m = sender.message(*spec);
  EXPECT_EQ(m["from"], 1);
  EXPECT_EQ(m["strokes"].size(), 2u);  // only what the workers lack
  const auto second = receiver.apply(wire(m));
  EXPECT_EQ(to_json(*second), to_json(*spec));
  EXPECT_EQ(second->lineage, first->lineage);  // the worker's renderer applies the two new strokes only

  m = sender.message(*spec);  // nothing new
  EXPECT_EQ(m["strokes"].size(), 0u);
  EXPECT_EQ(receiver.apply(wire(m))->lineage, first->lineage);

  // Another texture (a new lineage) goes whole, and is a new lineage on the worker too.
  auto other = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {8, 8}}}));
  const auto received = receiver.apply(wire(sender.message(*other)));
  EXPECT_NE(received->lineage, first->lineage);
}

TEST(RayTextureSync, ATextureWithFewerStrokesThanSentGoesWholeAgain) {
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {8, 8}}}));
  spec = with_stroke(*spec, stroke(RayChannel::Termination, 0.3, 0.2));
  spec = with_stroke(*spec, stroke(RayChannel::Step, 0.6, 2.0));
  distributed::RayTextureSender sender;
  distributed::RayTextureReceiver receiver;
  const auto first = receiver.apply(wire(sender.message(*spec)));
  RayTextureSpec fewer = *spec;  // the same lineage, one stroke less
  fewer.strokes.pop_back();
  const nlohmann::json m = sender.message(fewer);
  EXPECT_TRUE(m["whole"].get<bool>());
  const auto again = receiver.apply(wire(m));
  EXPECT_EQ(to_json(*again), to_json(fewer));
  EXPECT_NE(again->lineage, first->lineage);  // the worker's renderer builds it anew
}

TEST(RayTextureSync, APngsTexelsGoAsBinary) {
  auto spec = std::make_shared<RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {3, 2}}}));
  auto image = std::make_shared<RayTextureImage>();
  image->width = 3;
  image->height = 2;
  for (int k = 0; k < 18; ++k) image->texels.push_back(0.125f * float(k) + 0.001f);
  spec->image = image;
  spec->png = "paint.png";
  distributed::RayTextureSender sender;
  distributed::RayTextureReceiver receiver;
  const auto got = receiver.apply(wire(sender.message(*spec)));
  ASSERT_TRUE(got->image);
  EXPECT_EQ(got->image->texels, image->texels);
  EXPECT_EQ(got->png, "paint.png");
}

TEST(RayTextureSync, TexelsThatDoNotFitTheSizeAreRefused) {
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {3, 2}}}));
  distributed::RayTextureSender sender;
  nlohmann::json m = sender.message(*spec);
  m["png"] = "paint.png";
  m["image"] = nlohmann::json::binary(std::vector<uint8_t>(5 * sizeof(float), 0));  // 18 floats for 3x2
  distributed::RayTextureReceiver receiver;
  try {
    receiver.apply(wire(m));
    ADD_FAILURE() << "texels of the wrong count were taken";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("do not fit its size"), std::string::npos) << e.what();
  }
}

TEST(RayTextureSync, RanksOutOfStepAreRefusedByName) {
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"size", {8, 8}}}));
  distributed::RayTextureSender sender;
  sender.message(*spec);
  spec = with_stroke(*spec, stroke(RayChannel::Termination, 0.5, 0.3));
  distributed::RayTextureReceiver fresh;  // missed the first command
  try {
    fresh.apply(wire(sender.message(*spec)));
    ADD_FAILURE() << "a continuation of a texture this rank never got was applied";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("continues from 0"), std::string::npos) << e.what();
  }
}

TEST(RayTextureSync, BothSidesForgetTheOldestAlike) {
  distributed::RayTextureSender sender;
  distributed::RayTextureReceiver receiver;
  std::vector<std::shared_ptr<const RayTextureSpec>> specs;
  for (size_t k = 0; k <= distributed::kKeptRayTextures; ++k) {  // one more than both keep
    const RayTextureSpec blank = parse_ray_texture({{"mapping", "view"}, {"size", {4, 4}}});
    specs.push_back(with_stroke(blank, stroke(RayChannel::Step, 0.5, 2.0)));
    receiver.apply(wire(sender.message(*specs.back())));
  }
  // The newest is held: a continuation from its one stroke.
  const auto newest = with_stroke(*specs.back(), stroke(RayChannel::Blend, 0.5, 0.3));
  nlohmann::json m = sender.message(*newest);
  EXPECT_EQ(m["from"], 1);
  EXPECT_EQ(receiver.apply(wire(m))->strokes.size(), 2u);
  // The first was forgotten on both sides: it goes whole again, and the receiver takes it.
  const auto first = with_stroke(*specs[0], stroke(RayChannel::Termination, 0.5, 0.3));
  m = sender.message(*first);
  EXPECT_EQ(m["from"], 0);
  EXPECT_EQ(m["strokes"].size(), 2u);
  EXPECT_EQ(receiver.apply(wire(m))->strokes.size(), 2u);
}

}  // namespace
