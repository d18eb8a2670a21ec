// Ray textures from PNG files (render.ray_texture.png): the channel encoding, 8 and 16 bit,
// strokes over a PNG, and the refusals of files that are not a three-channel PNG of a size
// the limits allow.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>
#include <zlib.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/ray_texture_png.h"
#include "core/scene_error.h"
#include "core/volume_io.h"

namespace peakcast {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

template <class T>
void write_image(const fs::path& p, int w, int h, int channels, OIIO::TypeDesc type, const std::vector<T>& px) {
  auto out = OIIO::ImageOutput::create(p.string());
  ASSERT_TRUE(out) << p;
  OIIO::ImageSpec spec(w, h, channels, type);
  spec.attribute("oiio:UnassociatedAlpha", 1);  // write R, G, B as given, whatever the alpha
  ASSERT_TRUE(out->open(p.string(), spec));
  ASSERT_TRUE(out->write_image(type, px.data()));
  out->close();
}

struct TempDir {
  fs::path path = fs::temp_directory_path() / ("peakcast_rtpng_" + std::to_string(::getpid()));
  TempDir() { fs::create_directories(path); }
  ~TempDir() { fs::remove_all(path); }
};

TEST(ray_texture_png, MidpointsAreTheDefaultsExactly8And16Bit) {
  TempDir d;
  write_image<uint8_t>(d.path / "a.png", 2, 1, 3, OIIO::TypeDesc::UINT8, {128, 254, 128, 0, 255, 0});
  const auto a = read_ray_texture_png(d.path / "a.png");
  ASSERT_EQ(a->width, 2);
  EXPECT_EQ(a->texels[0], 1.0f);                             // step x1
  EXPECT_EQ(a->texels[1], float(1.0 - 1.0 / 255.0));         // the default termination
  EXPECT_EQ(a->texels[2], 0.0f);                             // no blend
  EXPECT_FLOAT_EQ(a->texels[3], float(kMinStepMultiplier));  // x1/8
  EXPECT_EQ(a->texels[4], 1.0f);
  EXPECT_EQ(a->texels[5], -1.0f);
  write_image<uint16_t>(d.path / "b.png", 1, 2, 4, OIIO::TypeDesc::UINT16, {32768, 65535, 32768, 7, 65535, 0, 0, 7});
  const auto b = read_ray_texture_png(d.path / "b.png");  // 16 bit, alpha ignored
  ASSERT_EQ(b->height, 2);
  EXPECT_EQ(b->texels[0], 1.0f);
  EXPECT_EQ(b->texels[1], 1.0f);
  EXPECT_EQ(b->texels[2], 0.0f);
  EXPECT_NEAR(b->texels[3], 8.0, 8.0 * 1e-4);  // 65535 is x8 (to 1/32768 of the exponent)
  EXPECT_EQ(b->texels[4], 0.0f);
  EXPECT_EQ(b->texels[5], -1.0f);
}

// What write_ray_texture_png writes reads back within 8-bit steps of each channel.
TEST(ray_texture_png, PaintedTexturesRoundTripThroughAPng) {
  TempDir d;
  RayTexture t(40, 30, 1.0 - 1.0 / 255.0);
  t.apply(parse_stroke(
      {{"channel", "step"}, {"center", {0.3, 0.4}}, {"radius", 0.3}, {"value", 0.25}, {"falloff", 0.5}}, "s"));
  t.apply(parse_stroke({{"channel", "termination"}, {"center", {0.7, 0.5}}, {"radius", 0.2}, {"value", 0.3}}, "s"));
  t.apply(parse_stroke({{"channel", "blend"}, {"center", {0.5, 0.8}}, {"radius", 0.25}, {"value", -0.6}}, "s"));
  write_ray_texture_png(t, d.path / "t.png");
  const auto back = read_ray_texture_png(d.path / "t.png");
  ASSERT_EQ(back->texels.size(), t.texels().size());
  double worst[3] = {0, 0, 0};
  for (size_t i = 0; i < t.texels().size(); i += 3) {
    worst[0] = std::max(worst[0], std::abs(std::log2(double(back->texels[i]) / t.texels()[i])));
    worst[1] = std::max(worst[1], double(std::abs(back->texels[i + 1] - t.texels()[i + 1])));
    worst[2] = std::max(worst[2], double(std::abs(back->texels[i + 2] - t.texels()[i + 2])));
  }
  EXPECT_LE(worst[0], 3.0 / 256.0 + 1e-6);  // half an 8-bit step of a 3-octave log scale
  EXPECT_LE(worst[1], 0.5 / 255.0 + 1e-6);
  EXPECT_LE(worst[2], 0.5 / 128.0 + 1e-6);
}

TEST(ray_texture_png, StrokesApplyOverThePng) {
  TempDir d;
  write_image<uint8_t>(d.path / "p.png", 4, 4, 3, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(48, 128));
  const json j = {
      {"mapping", "volume"},
      {"png", "p.png"},
      {"strokes",
       {{{"channel", "step"}, {"center", {0.5, 0.5}}, {"radius", 1.0}, {"value", 2.0}, {"mode", "multiply"}}}}};
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture(j));
  EXPECT_THROW(build_ray_texture(*spec, 0.9), SceneError);  // not read yet
  const auto loaded = load_ray_texture_png(spec, [&](const std::string& p) { return d.path / p; });
  EXPECT_EQ(loaded->width, 4);
  EXPECT_EQ(loaded->lineage, spec->lineage);
  const RayTexture t = build_ray_texture(*loaded, 0.9);
  EXPECT_FLOAT_EQ(t.at(2, 2)[0], 2.0f);             // x1 from the PNG, then x2
  EXPECT_FLOAT_EQ(t.at(2, 2)[1], 128.0f / 255.0f);  // the PNG's termination, not the scene's
  EXPECT_EQ(to_json(*loaded)["png"], "p.png");
  EXPECT_EQ(to_json(*loaded)["strokes"].size(), 1u);
}

void expect_refused(const fs::path& p, const std::string& words) {
  try {
    read_ray_texture_png(p);
    ADD_FAILURE() << "accepted " << p;
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("render.ray_texture.png"), std::string::npos) << m;
    EXPECT_NE(m.find(words), std::string::npos) << m;
  }
}

TEST(ray_texture_png, FilesThatAreNotAThreeChannelPngOfAllowedSizeAreRefused) {
  TempDir d;
  write_image<uint8_t>(d.path / "wide.png", kMaxRayTextureSide + 1, 1, 3, OIIO::TypeDesc::UINT8,
                       std::vector<uint8_t>(size_t(kMaxRayTextureSide + 1) * 3, 128));
  write_image<uint8_t>(d.path / "grey.png", 4, 4, 1, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(16, 128));
  write_image<uint8_t>(d.path / "photo.jpg", 4, 4, 3, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(48, 128));
  std::ofstream(d.path / "text.png") << "not an image";
  std::ofstream(d.path / "cut.png") << std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16);
  expect_refused(d.path / "wide.png", "wrong size");
  expect_refused(d.path / "grey.png", "1 channel");
  expect_refused(d.path / "photo.jpg", "not PNG");
  expect_refused(d.path / "text.png", "not PNG");
  expect_refused(d.path / "cut.png", "truncated");
  // A byte of the image data changed: the chunk's CRC catches it before any decoder runs.
  write_image<uint8_t>(d.path / "ok.png", 16, 16, 3, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(768, 77));
  std::ifstream in(d.path / "ok.png", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const size_t idat = bytes.find("IDAT");
  ASSERT_NE(idat, std::string::npos);
  bytes[idat + 6] ^= 0x5a;
  std::ofstream(d.path / "flipped.png", std::ios::binary) << bytes;
  expect_refused(d.path / "flipped.png", "CRC");
  // Image data that inflates to the wrong length, with every CRC right: refused before decoding.
  {
    std::string wrong = bytes;
    const uint32_t len = uint32_t((unsigned char)wrong[idat - 4]) << 24 |
                         uint32_t((unsigned char)wrong[idat - 3]) << 16 |
                         uint32_t((unsigned char)wrong[idat - 2]) << 8 | (unsigned char)wrong[idat - 1];
    const std::string other("\x78\x9c\x63\x00\x00\x00\x01\x00\x01", 9);  // zlib of one zero byte
    std::string chunk = "IDAT" + other;
    const uint32_t crc = uint32_t(crc32(0, reinterpret_cast<const Bytef*>(chunk.data()), uInt(chunk.size())));
    std::string rebuilt = wrong.substr(0, idat - 4);
    for (int k = 3; k >= 0; --k) rebuilt += char((other.size() >> (8 * k)) & 0xff);
    rebuilt += chunk;
    for (int k = 3; k >= 0; --k) rebuilt += char((crc >> (8 * k)) & 0xff);
    rebuilt += wrong.substr(idat + 4 + len + 4);
    std::ofstream(d.path / "short.png", std::ios::binary) << rebuilt;
    expect_refused(d.path / "short.png", "does not inflate");
  }
  // Cut inside the image data (the case that made OpenImageIO's reader leak under libpng's longjmp).
  std::ofstream(d.path / "half.png", std::ios::binary) << bytes.substr(0, idat + 10);
  expect_refused(d.path / "half.png", "truncated");
  expect_refused(d.path / "missing.png", "missing.png");
  // Over 64 MiB: refused from its size, before a byte is read (a sparse file costs no disk).
  std::ofstream(d.path / "huge.png", std::ios::binary) << std::string("\x89PNG\r\n\x1a\n", 8);
  fs::resize_file(d.path / "huge.png", (64ull << 20) + 1);
  expect_refused(d.path / "huge.png", "at most 64 MiB");
}

// The server's locator: only inside the data directories, as for volumes.
TEST(ray_texture_png, TheLocatorRefusesPathsOutsideTheRoots) {
  TempDir d;
  fs::create_directories(d.path / "data");
  write_image<uint8_t>(d.path / "outside.png", 2, 2, 3, OIIO::TypeDesc::UINT8, std::vector<uint8_t>(12, 128));
  fs::create_symlink(d.path / "outside.png", d.path / "data" / "link.png");
  const std::vector<fs::path> roots = {d.path / "data"};
  const PngLocator in_roots = [&](const std::string& p) { return resolve_in_roots(p, roots); };
  for (const std::string& p :
       {std::string("../outside.png"), (d.path / "outside.png").string(), std::string("link.png")}) {
    auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"png", p}}));
    try {
      load_ray_texture_png(spec, in_roots);
      ADD_FAILURE() << "read " << p << " from outside the data directory";
    } catch (const SceneError& e) {
      EXPECT_NE(std::string(e.what()).find("outside"), std::string::npos) << e.what();
    }
  }
  // The same file inside the root is read.
  fs::copy_file(d.path / "outside.png", d.path / "data" / "inside.png");
  auto inside = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"png", "inside.png"}}));
  EXPECT_EQ(load_ray_texture_png(inside, in_roots)->width, 2);
  auto spec = std::make_shared<const RayTextureSpec>(parse_ray_texture({{"mapping", "view"}, {"png", "x.png"}}));
  try {
    load_ray_texture_png(spec, {});
    ADD_FAILURE() << "read a PNG with no locator";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("render.ray_texture.png"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace peakcast
