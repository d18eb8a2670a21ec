// Scene parsing (docs/scenes.md): defaults, and each refusal names the key.
#include <gtest/gtest.h>

#include "core/generators.h"
#include "core/scene.h"

using namespace peakcast;

namespace {

void expect_refused(const std::string& text, const std::string& key) {
  try {
    parse_scene_text(text);
    ADD_FAILURE() << "accepted: " << text;
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << "'" << e.what() << "' should name " << key;
  }
}

TEST(Scene, DefaultsFilledFromTheVolume) {
  GeneratorSpec g;
  g.dims = {10, 20, 30};
  g.spacing = {2, 0.5, 1};
  Volume v = generate_volume(g);
  ResolvedScene r = resolve_scene(parse_scene_text(R"({"volume": "v"})"), v);
  EXPECT_EQ(r.step, 0.5);
  EXPECT_EQ(r.tf.opacity_unit, 0.5);
  EXPECT_EQ(r.scene.width, 512);
  EXPECT_EQ(r.camera.center, glm::dvec3(9, 4.75, 14.5));  // half of (n-1)*spacing
  EXPECT_EQ(r.camera.up, glm::dvec3(0, 1, 0));
  EXPECT_GT(r.camera.eye.z, 14.5);
  EXPECT_TRUE(r.tf_derived);  // no TF in the scene: one from the histogram (auto_tf_test.cpp)
  EXPECT_GE(r.tf.points.front().value, v.min_value);
  EXPECT_NEAR(r.scene.render.early_termination, 1 - 1 / 255.0, 1e-12);
}

TEST(Scene, RoundTripsThroughJson) {
  const char* text = R"({"volume": "a.nrrd", "camera": {"eye": [1,2,3], "center": [0,0,0], "up": [0,0,1], "fov_y": 40},
    "image": {"width": 64, "height": 32}, "tf": {"points": [[0,0,0,0,0],[1,1,1,1,1]], "opacity_unit": 2},
    "background": [0.1, 0.2, 0.3], "render": {"filter": "tricubic", "step": 0.25, "shading": true}})";
  Scene s = parse_scene_text(text);
  Scene t = parse_scene(scene_to_json(s));
  EXPECT_EQ(scene_to_json(s), scene_to_json(t));
  EXPECT_EQ(t.render.filter, Filter::Tricubic);
  EXPECT_EQ(t.opacity_unit, 2.0);
  EXPECT_NE(s.to_string().find("tricubic"), std::string::npos);
}

TEST(Scene, ProjectionsParseAndRoundTrip) {
  for (const auto& [name, c] : {std::pair{"mip", Classification::Mip}, std::pair{"minip", Classification::Minip},
                                std::pair{"average", Classification::Average}}) {
    Scene s = parse_scene_text(std::string(R"({"volume": "v", "render": {"classification": ")") + name + "\"}}");
    EXPECT_EQ(s.render.classification, c);
    EXPECT_TRUE(is_projection(c));
    EXPECT_EQ(parse_scene(scene_to_json(s)).render.classification, c);
  }
  for (Classification c : {Classification::Post, Classification::Preint, Classification::Peaks})
    EXPECT_FALSE(is_projection(c));
}

TEST(Scene, Refusals) {
  expect_refused(R"({"volume": "v", "camra": {}})", "camra");
  expect_refused(R"({"volume": "v", "render": {"stpe": 1}})", "render.stpe");
  expect_refused(R"({"volume": 3})", "volume");
  expect_refused(R"({})", "volume");
  expect_refused(R"({"volume": "v", "render": {"step": "fast"}})", "render.step");
  expect_refused(R"({"volume": "v", "render": {"step": -1}})", "render.step");
  expect_refused(R"({"volume": "v", "render": {"step": 1e999}})", "number overflow");
  expect_refused(R"({"volume": "v", "render": {"step": NaN}})", "not valid JSON");
  expect_refused(R"({"volume": "v", "tf": {"points": [[1,0,0,0,0],[0,1,1,1,1]]}})", "tf.points[1]");
  expect_refused(R"({"volume": "v", "tf": {"points": [[0,0,0,0,2]]}})", "tf.points[0]");
  expect_refused(R"({"volume": "v", "tf": {"points": []}})", "tf.points");
  expect_refused(R"({"volume": "v", "image": {"width": 0, "height": 10}})", "image.width");
  expect_refused(R"({"volume": "v", "image": {"width": 8193, "height": 10}})", "image.width");
  expect_refused(R"({"volume": "v", "image": {"width": 8000, "height": 8000}})", "image");
  expect_refused(R"({"volume": "v", "camera": {"eye": [0,0,5], "center": [0,0,0], "up": [0,0,1]}})", "camera.up");
  expect_refused(R"({"volume": "v", "camera": {"eye": [0,0,0], "center": [0,0,0]}})", "eye equals center");
  expect_refused(R"({"volume": "v", "camera": {"eye": [0,0,5], "center": [0,0,0], "fov_y": 180}})", "camera.fov_y");
  expect_refused(R"({"volume": "v", "camera": {"eye": [0,0,5], "center": [0,0,0], "projection": "orthographic"}})",
                 "camera.height");
  expect_refused(R"({"volume": "v", "render": {"filter": "nearest"}})", "render.filter");
  expect_refused(R"({"volume": "v", "render": {"classification": "maxip"}})", "render.classification");
  expect_refused(R"({"volume": "v", "render": {"classification": "MIP"}})", "render.classification");
  expect_refused(R"({"volume": "v", "render": {"max_peaks": 5}})", "render.max_peaks");
  expect_refused(R"({"volume": "v", "render": {"virtual_samples": 4}})", "render.virtual_samples");
  expect_refused(R"({"volume": "v", "render": {"virtual_samples": 5}})", "render.virtual_samples");
  expect_refused(R"({"volume": "v", "render": {"s_k": 0}})", "render.s_k");
  expect_refused(R"({"volume": "v", "render": {"s_k": -1}})", "render.s_k");
  expect_refused(R"({"volume": "v", "render": {"s_k": "4"}})", "render.s_k");
  expect_refused(R"({"volume": "v", "render": {"s_k": NaN}})", "not valid JSON");
  expect_refused(R"({"volume": "v", "render": {"sampling": "adaptive"}})", "render.sampling");
  expect_refused(R"({"volume": "v", "render": {"adaptive": 1}})", "render.adaptive");
  expect_refused(R"({"volume": "v", "render": {"peak_table_bins": 32}})", "render.peak_table_bins");
  expect_refused(R"({"volume": "v", "render": {"secant_iterations": 17}})", "render.secant_iterations");
  expect_refused(R"({"volume": "v", "render": {"preint_table_size": 2048}})", "render.preint_table_size");
  expect_refused(R"({"volume": "v", "render": {"preint_method": "magic"}})", "render.preint_method");
  expect_refused(R"({"volume": "v", "background": [0, 0]})", "background");
  expect_refused(R"([1, 2])", "scene");
  expect_refused(R"({"volume": "v", "render": {"clip": []}})", "render.clip");
  expect_refused(R"({"volume": "v", "render": {"clip": {"sphere": 1}}})", "render.clip.sphere");
  expect_refused(R"({"volume": "v", "render": {"clip": {"box": [[0, 0, 0]]}}})", "render.clip.box");
  expect_refused(R"({"volume": "v", "render": {"clip": {"box": [[0, 5, 0], [1, 1, 1]]}}})", "the low one");
  expect_refused(R"({"volume": "v", "render": {"clip": {"box": [[0, 0, 0], [1, "a", 1]]}}})", "render.clip.box[1][1]");
  expect_refused(R"({"volume": "v", "render": {"clip": {"plane": {"point": [0, 0, 0]}}}})", "needs point and normal");
  expect_refused(R"({"volume": "v", "render": {"clip": {"plane": {"point": [0, 0, 0], "normal": [0, 0, 0]}}}})",
                 "render.clip.plane.normal");
  expect_refused(R"({"volume": "v", "render": {"clip": {"plane": {"point": [0, 0, 0], "normal": [0, 0, 1], "d": 1}}}})",
                 "render.clip.plane.d");
}

TEST(Scene, ClipRoundTripsWithAUnitNormal) {
  Scene s = parse_scene_text(R"({"volume": "v", "render": {"clip": {"box": [[0, 1, 2], [3, 4, 5]],
    "plane": {"point": [1, 1, 1], "normal": [0, 3, 4]}}}})");
  ASSERT_TRUE(s.render.clip.box && s.render.clip.plane);
  EXPECT_EQ(s.render.clip.box_hi, glm::dvec3(3, 4, 5));
  EXPECT_NEAR(s.render.clip.normal.y, 0.6, 1e-15);
  EXPECT_NEAR(s.render.clip.normal.z, 0.8, 1e-15);
  EXPECT_EQ(scene_to_json(parse_scene(scene_to_json(s))), scene_to_json(s));
  EXPECT_FALSE(parse_scene_text(R"({"volume": "v"})").render.clip.active());
  EXPECT_FALSE(scene_to_json(parse_scene_text(R"({"volume": "v"})"))["render"].contains("clip"));
}

TEST(Scene, StepBelowTheFloorRefusedOnResolve) {
  Volume v = generate_volume(GeneratorSpec{});
  EXPECT_THROW(resolve_scene(parse_scene_text(R"({"volume": "v", "render": {"step": 1e-9}})"), v), SceneError);
}

TEST(TransferFunction, StepsAndPlateaus) {
  TransferFunction tf;
  tf.points = {{0, 0, 0, 0, 0}, {10, 1, 0, 0, 0.2}, {10, 0, 1, 0, 0.8}, {20, 0, 0, 1, 0.8}};
  EXPECT_NEAR(tf.eval(5).a, 0.1, 1e-12);
  EXPECT_NEAR(tf.eval(10).a, 0.8, 1e-12);  // at a step the later point holds
  EXPECT_NEAR(tf.eval(9.999999).a, 0.2, 1e-6);
  EXPECT_NEAR(tf.eval(-5).a, 0.0, 1e-12);  // constant outside
  EXPECT_NEAR(tf.eval(100).b, 1.0, 1e-12);
  EXPECT_NEAR(tf.max_opacity(0, 9), 0.18, 1e-12);
  EXPECT_NEAR(tf.max_opacity(0, 10), 0.8, 1e-12);
  EXPECT_NEAR(correct_opacity(0.5, 2.0, 1.0), 0.75, 1e-12);
}

}  // namespace
