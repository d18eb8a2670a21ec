// POST /api/movie's request and camera path (server/session/movie_path.h), and the ZIP of PNGs
// (server/encode/movie_writer.h) read back by libzip.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <zip.h>

#include "core/scene_error.h"
#include "encode/movie_writer.h"
#include "encode/png.h"
#include "session/movie_path.h"

namespace peakcast {
namespace {

using json = nlohmann::json;

ResolvedScene first_of(const MovieRequest& m) {
  ResolvedScene r;
  r.scene = m.scene;
  r.camera = m.scene.camera ? *m.scene.camera : Camera{{0, 0, 10}, {0, 0, 0}, {0, 1, 0}};
  r.tf.points = {{0, 0, 0, 0, 0}, {1, 1, 1, 1, 1}};
  r.tf.opacity_unit = 2.0;
  return r;
}

std::string refusal(const json& body) {
  try {
    parse_movie(body);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

TEST(MoviePath, RefusesWhatItCannotMakeNamingTheKey) {
  const json base = {{"volume", "v"}};
  auto with = [&](const char* key, json value) {
    json b = base;
    b[key] = std::move(value);
    return refusal(b);
  };
  EXPECT_NE(with("frames", 0).find("frames: must be in [1, 3600]"), std::string::npos);
  EXPECT_NE(with("frames", 3601).find("frames"), std::string::npos);
  EXPECT_NE(with("fps", 0).find("fps"), std::string::npos);
  EXPECT_NE(with("format", "gif").find("format: 'gif' is not one of mp4, webm, png-zip"), std::string::npos);
  EXPECT_NE(with("quality", 5).find("quality"), std::string::npos);
  EXPECT_NE(with("path", json{{"spiral", 1}}).find("path: must be"), std::string::npos);
  EXPECT_NE(with("path", json{{"orbit", {{"axis", {0, 0, 0}}}}}).find("path.orbit.axis"), std::string::npos);
  EXPECT_NE(with("path", json{{"orbit", {{"turns", 2}}}}).find("path.orbit.turns: unknown key"), std::string::npos);
  EXPECT_NE(with("path", json{{"keys", json::array()}}).find("path.keys"), std::string::npos);
  EXPECT_NE(with("path", json{{"keys", {{{"zoom", 2}}}}}).find("path.keys[0].zoom: unknown key"), std::string::npos);
  EXPECT_NE(with("path", json{{"keys", {{{"camera", {{"eye", {0, 0, 1}}}}}}}}).find("path.keys[0].camera"),
            std::string::npos);
  json many = base;
  many["frames"] = 2;
  many["path"] = {{"keys", {json::object(), json::object(), json::object()}}};
  EXPECT_NE(refusal(many).find("3 keys need at least as many frames"), std::string::npos);
  EXPECT_NE(refusal(json{{"frames", 2}}).find("volume"), std::string::npos);  // the scene's own rules
  EXPECT_EQ(refusal(json{{"volume", "v"}, {"frames", 4}, {"fps", 24}, {"format", "webm"}}), "");
}

TEST(MoviePath, AnOrbitOfWholeTurnsLoopsAndAPartOneEndsWhereItSays) {
  MovieRequest m = parse_movie({{"volume", "v"}, {"frames", 4}, {"path", {{"orbit", {{"axis", {0, 1, 0}}}}}}});
  const ResolvedScene first = first_of(m);
  std::vector<Scene> f = movie_frames(m, first);
  ASSERT_EQ(f.size(), 4u);
  // 360 degrees in 4 frames: 0, 90, 180, 270 (the loop's last frame is a step short of the first).
  EXPECT_NEAR(f[1].camera->eye.x, 10.0, 1e-9);  // +90 about +y turns +z to +x
  EXPECT_NEAR(f[2].camera->eye.z, -10.0, 1e-9);
  EXPECT_NEAR(f[3].camera->eye.x, -10.0, 1e-9);
  for (const Scene& s : f) EXPECT_NEAR(glm::length(s.camera->eye - s.camera->center), 10.0, 1e-9);
  m.degrees = 90;  // a part turn: 0, 30, 60, 90
  f = movie_frames(m, first);
  EXPECT_NEAR(f[3].camera->eye.x, 10.0, 1e-9);
  EXPECT_NEAR(f[1].camera->eye.x, 10.0 * std::sin(M_PI / 6), 1e-9);
  // The default axis is the view up; the up vector turns with the eye about a tilted axis.
  m.axis = glm::dvec3(1, 0, 0);
  m.degrees = 360;
  f = movie_frames(m, first);
  EXPECT_NEAR(f[1].camera->eye.y, -10.0, 1e-9);  // +90 about +x turns +z to -y
  EXPECT_NEAR(f[1].camera->up.z, 1.0, 1e-9);
  EXPECT_FALSE(f[1].tf.has_value());  // an orbit leaves the scene's TF alone
}

TEST(MoviePath, KeysAreReachedExactlyAndBlendedBetween) {
  const json key0 = {{"camera", {{"eye", {0, 0, 10}}, {"center", {0, 0, 0}}}},
                     {"tf", {{"points", {{0, 1, 0, 0, 0}, {1, 1, 0, 0, 1}}}}},
                     {"time", 0}};
  const json key1 = {{"camera", {{"eye", {40, 0, 0}}, {"center", {2, 0, 0}}, {"fov_y", 50}}},
                     {"tf", {{"points", {{0.5, 0, 0, 1, 0.5}}}, {"opacity_unit", 4}}},
                     {"time", 3}};
  MovieRequest m = parse_movie({{"volume", "v"}, {"frames", 5}, {"path", {{"keys", {key0, key1}}}}});
  const std::vector<Scene> f = movie_frames(m, first_of(m));
  ASSERT_EQ(f.size(), 5u);
  EXPECT_EQ(f[0].camera->eye, glm::dvec3(0, 0, 10));
  EXPECT_NEAR(glm::length(f[4].camera->eye - glm::dvec3(40, 0, 0)), 0.0, 1e-9);
  EXPECT_EQ(f[0].time, 0);
  EXPECT_EQ(f[2].time, 2);  // 1.5 rounds to the nearest (away from zero)
  EXPECT_EQ(f[4].time, 3);
  // Halfway: the focal point and view angle linear, the distance geometric (10 and 38: sqrt(380)).
  const Camera& c = *f[2].camera;
  EXPECT_NEAR(c.center.x, 1.0, 1e-9);
  EXPECT_NEAR(c.fov_y, 40.0, 1e-9);
  EXPECT_NEAR(glm::length(c.eye - c.center), std::sqrt(380.0), 1e-9);
  // The direction halfway between +z and +x on the sphere.
  const glm::dvec3 d = glm::normalize(c.eye - c.center);
  EXPECT_NEAR(d.x, std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(d.z, std::sqrt(0.5), 1e-9);
  // TFs: every point of either, the colours blended; the unit of a key without one is the volume's.
  const TransferFunction& tf = *f[2].tf;
  ASSERT_EQ(tf.points.size(), 3u);
  EXPECT_DOUBLE_EQ(tf.points[1].value, 0.5);
  EXPECT_DOUBLE_EQ(tf.points[1].r, 0.5);  // red 1 against blue 0 at 0.5
  EXPECT_DOUBLE_EQ(tf.points[1].b, 0.5);
  EXPECT_DOUBLE_EQ(tf.points[1].a, 0.5);   // 0.5 and 0.5
  EXPECT_DOUBLE_EQ(tf.opacity_unit, 3.0);  // 2 (the volume's, first_of) to 4
  EXPECT_DOUBLE_EQ(f[2].opacity_unit, 3.0);
}

TEST(MoviePath, KeysKeepWhatTheyLeaveOutAndRefuseAMixedProjection) {
  const json cam = {{"eye", {0, 0, 5}}, {"center", {0, 0, 0}}};
  MovieRequest m =
      parse_movie({{"volume", "v"}, {"frames", 3}, {"path", {{"keys", {json::object(), {{"camera", cam}}}}}}});
  std::vector<Scene> f = movie_frames(m, first_of(m));
  EXPECT_EQ(f[0].camera->eye, glm::dvec3(0, 0, 10));  // key 0 without a camera: the scene's
  EXPECT_NEAR(glm::length(f[2].camera->eye - glm::dvec3(0, 0, 5)), 0, 1e-9);
  EXPECT_EQ(f[1].tf->points.size(), 2u);  // no TF in either key: the resolved one
  const json ortho = {{"eye", {0, 0, 5}}, {"center", {0, 0, 0}}, {"projection", "orthographic"}, {"height", 3}};
  m = parse_movie({{"volume", "v"}, {"frames", 3}, {"path", {{"keys", {{{"camera", cam}}, {{"camera", ortho}}}}}}});
  EXPECT_THROW(movie_frames(m, first_of(m)), SceneError);
  // Opposite directions turn through the view up, never through the focal point.
  const json behind = {{"eye", {0, 0, -10}}, {"center", {0, 0, 0}}};
  m = parse_movie({{"volume", "v"}, {"frames", 3}, {"path", {{"keys", {json::object(), {{"camera", behind}}}}}}});
  f = movie_frames(m, first_of(m));
  EXPECT_NEAR(glm::length(f[1].camera->eye), 10.0, 1e-9);
  EXPECT_NEAR(f[1].camera->eye.y, 10.0, 1e-9);
}

TEST(MovieWriter, APngZipIsAZipOfTheFramesAsPngs) {
  const int w = 6, h = 4;
  auto writer = encode::open_movie_writer({encode::MovieFormat::PngZip, w, h, 30, 90});
  std::string file;
  std::vector<std::vector<uint8_t>> frames;
  for (int i = 0; i < 3; ++i) {
    std::vector<uint8_t> rgb(size_t(w) * h * 3);
    for (size_t k = 0; k < rgb.size(); ++k) rgb[k] = uint8_t(k * 7 + i * 40);
    const std::string piece = writer->add(rgb.data());
    EXPECT_FALSE(piece.empty()) << "each frame leaves as soon as it is made";
    file += piece;
    frames.push_back(rgb);
  }
  file += writer->finish();
  zip_error_t err;
  zip_error_init(&err);
  zip_source_t* src = zip_source_buffer_create(file.data(), file.size(), 0, &err);
  ASSERT_NE(src, nullptr);
  zip_t* z = zip_open_from_source(src, ZIP_CHECKCONS | ZIP_RDONLY, &err);
  ASSERT_NE(z, nullptr) << zip_error_strerror(&err);
  ASSERT_EQ(zip_get_num_entries(z, 0), 3);
  for (int i = 0; i < 3; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%05d.png", i);
    EXPECT_STREQ(zip_get_name(z, i, 0), name);
    zip_file_t* f = zip_fopen_index(z, i, 0);
    ASSERT_NE(f, nullptr);
    std::vector<unsigned char> bytes(1 << 16);
    const zip_int64_t n = zip_fread(f, bytes.data(), bytes.size());  // the CRC is checked at the end
    zip_fclose(f);
    bytes.resize(size_t(n));
    EXPECT_EQ(bytes, encode::encode_png(frames[size_t(i)].data(), w, h, 3));
  }
  zip_close(z);
}

}  // namespace
}  // namespace peakcast
