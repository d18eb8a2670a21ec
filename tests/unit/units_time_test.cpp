// Units of length (core/length_unit.h, docs/scenes.md "Units"): the spellings files use, the
// refusal of what is not a length, mixed units per axis, and each reader that carries a unit; and
// a scene's time point ("Time"), held to the volume's.
#include <gtest/gtest.h>

#include <OpenImageIO/imageio.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "chunked/chunk_codec.h"
#include "chunked/zarr_writer.h"
#include "core/length_unit.h"
#include "core/scene.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"
#include "unit/chunked_test_util.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using nlohmann::json;
using namespace peakcast;
using test::refusal;

namespace {

std::string symbol(const std::string& name) {
  const auto u = parse_length_unit(name);
  return u ? u->symbol : "(none)";
}

std::string scene_refusal(const json& j) {
  try {
    parse_scene(j);
  } catch (const SceneError& e) {
    return e.what();
  }
  return "";
}

// 4x3x2 uint8 raw voxels with the NRRD header lines given.
fs::path nrrd_with(const fs::path& dir, const std::string& name, const std::string& fields) {
  const fs::path p = dir / name;
  test::write_file(p, "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 4 3 2\nencoding: raw\n" + fields + "\n\n" +
                          std::string(24, '\x07'));
  return p;
}

}  // namespace

TEST(Units, SpellingsFilesUseAreOneSymbol) {
  for (const char* n : {"micrometer", "micrometre", "micrometers", "um", "µm", "\xce\xbcm", "micron", "microns"})
    EXPECT_EQ(symbol(n), "µm") << n;
  for (const char* n : {"nanometer", "nm", "Nanometers"}) EXPECT_EQ(symbol(n), "nm") << n;
  for (const char* n : {"millimeter", "millimetre", "mm"}) EXPECT_EQ(symbol(n), "mm") << n;
  EXPECT_EQ(symbol("Mm"), "Mm") << "SI symbols are case-sensitive";
  EXPECT_EQ(symbol("meter"), "m");
  EXPECT_EQ(symbol("angstrom"), "Å");
  EXPECT_EQ(symbol("inch"), "in");
  EXPECT_DOUBLE_EQ(parse_length_unit("micrometer")->metres, 1e-6);
  EXPECT_DOUBLE_EQ(parse_length_unit("parsec")->metres, 3.0856775814913673e16);
  for (const char* n : {"second", "ms", "kg", "micrometerss", "degree", "mmm"}) EXPECT_EQ(symbol(n), "(none)") << n;
  for (const char* n : {"", "pixel", "voxels", "unknown", "none", "units", "???"}) {
    EXPECT_TRUE(says_no_unit(n)) << n;
    EXPECT_EQ(length_symbol(n, "k"), "") << n;
  }
  try {
    length_symbol("second", "units");
    ADD_FAILURE() << "a time is not a length";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("units: 'second' is not a unit of length"), std::string::npos) << e.what();
  }
  for (const char* s : {"nm", "µm", "mm", "m", "Å", "in"})  // what the OME-Zarr writer names
    EXPECT_EQ(symbol(ngff_unit_name(s)), s) << s;
  EXPECT_EQ(ngff_unit_name(""), "");
}

TEST(Units, MixedAxesTakeTheFinestUnit) {
  glm::dvec3 spacing{4, 4, 1}, origin{100, 0, 2};
  EXPECT_EQ(common_unit({"nanometer", "nanometer", "micrometer"}, spacing, origin, "k"), "nm");
  EXPECT_DOUBLE_EQ(spacing.x, 4);
  EXPECT_DOUBLE_EQ(spacing.z, 1000);
  EXPECT_DOUBLE_EQ(origin.x, 100);
  EXPECT_DOUBLE_EQ(origin.z, 2000);
  glm::dvec3 s2{1, 1, 1}, o2{0, 0, 0};
  EXPECT_EQ(common_unit({"", "mm", ""}, s2, o2, "k"), "mm") << "an axis without a unit takes the others'";
  EXPECT_EQ(s2, glm::dvec3(1, 1, 1));
  EXPECT_EQ(common_unit({"", "", ""}, s2, o2, "k"), "");
  EXPECT_THROW(common_unit({"mm", "mm", "s"}, s2, o2, "k"), std::invalid_argument);
}

TEST(Units, NrrdSpaceUnitsAndAxisUnits) {
  test::TempDir dir;
  const Volume a = load_volume(nrrd_with(dir.path(), "a.nrrd",
                                         "space: right-anterior-superior\nspace directions: (0.5,0,0) (0,0.5,0) "
                                         "(0,0,2)\nspace units: \"mm\" \"mm\" \"mm\""));
  EXPECT_EQ(a.unit, "mm");
  EXPECT_DOUBLE_EQ(a.spacing.z, 2.0);
  const Volume b =
      load_volume(nrrd_with(dir.path(), "b.nrrd", "spacings: 200 200 1\nunits: \"nm\" \"nm\" \"microns\""));
  EXPECT_EQ(b.unit, "nm");
  EXPECT_DOUBLE_EQ(b.spacing.z, 1000.0);
  EXPECT_EQ(load_volume(nrrd_with(dir.path(), "c.nrrd", "spacings: 1 1 1")).unit, "") << "the file says nothing";
  EXPECT_EQ(load_volume(nrrd_with(dir.path(), "d.nrrd", "units: \"???\" \"???\" \"???\"")).unit, "");
  const std::string why = refusal(nrrd_with(dir.path(), "e.nrrd", "space units: \"mm\" \"mm\" \"ms\""));
  EXPECT_NE(why.find("'space units': 'ms' is not a unit of length"), std::string::npos) << why;
  EXPECT_NE(refusal(nrrd_with(dir.path(), "f.nrrd", "space units: \"mm\" \"mm\""))
                .find("must list a quoted unit per space axis"),
            std::string::npos);
  // What peakcast writes it reads back with its unit.
  Volume v = test::anisotropic_blobs(SourceType::U8, {5, 4, 3});
  v.unit = "µm";
  write_volume(dir / "w.nrrd", v);
  EXPECT_EQ(load_volume(dir / "w.nrrd").unit, "µm");
}

TEST(Units, RawSidecarUnits) {
  test::TempDir dir;
  test::write_file(dir / "v.raw", std::string(24, '\x01'));
  test::write_file(dir / "v.raw.json", R"({"dims":[4,3,2],"dtype":"uint8","spacing":[1,1,2],"units":"micrometer"})");
  EXPECT_EQ(load_volume(dir / "v.raw").unit, "µm");
  test::write_file(dir / "w.raw", std::string(24, '\x01'));
  test::write_file(dir / "w.raw.json",
                   R"({"dims":[4,3,2],"dtype":"uint8","spacing":[5,5,1],"units":["nm","nm","um"]})");
  const Volume w = load_volume(dir / "w.raw");
  EXPECT_EQ(w.unit, "nm");
  EXPECT_DOUBLE_EQ(w.spacing.z, 1000.0);
  test::write_file(dir / "x.raw", std::string(24, '\x01'));
  test::write_file(dir / "x.raw.json", R"({"dims":[4,3,2],"dtype":"uint8","units":"kg"})");
  EXPECT_NE(refusal(dir / "x.raw").find("'units': 'kg' is not a unit of length"), std::string::npos);
}

TEST(Units, OmeZarrAxesUnits) {
  test::TempDir dir;
  Volume src = test::anisotropic_blobs(SourceType::U16, {9, 8, 7});
  src.unit = "µm";
  chunked::ZarrWriteOptions o;
  o.chunk = 4;
  o.pyramid = true;
  chunked::write_ome_zarr(src, dir / "a.zarr", o);
  std::ifstream in(dir / "a.zarr/.zattrs");
  json attrs = json::parse(in);
  EXPECT_EQ(attrs["multiscales"][0]["axes"][2]["unit"], "micrometer") << "NGFF's name, for napari and Neuroglancer";
  EXPECT_EQ(load_volume(dir / "a.zarr").unit, "µm");
  LoadOptions l1;
  l1.level = 1;
  EXPECT_EQ(load_volume(dir / "a.zarr", l1).unit, "µm");
  // z in micrometres, y and x in nanometres: all in nanometres.
  fs::copy(dir / "a.zarr", dir / "b.zarr", fs::copy_options::recursive);
  attrs["multiscales"][0]["axes"][1]["unit"] = "nanometer";
  attrs["multiscales"][0]["axes"][2]["unit"] = "nanometer";
  test::write_json(dir / "b.zarr/.zattrs", attrs);
  const Volume b = load_volume(dir / "b.zarr");
  EXPECT_EQ(b.unit, "nm");
  EXPECT_DOUBLE_EQ(b.spacing.z, 1000 * src.spacing.z);
  EXPECT_DOUBLE_EQ(b.spacing.x, src.spacing.x);
  fs::copy(dir / "a.zarr", dir / "c.zarr", fs::copy_options::recursive);
  attrs["multiscales"][0]["axes"][0]["unit"] = "second";
  test::write_json(dir / "c.zarr/.zattrs", attrs);
  EXPECT_NE(refusal(dir / "c.zarr").find("multiscales.axes unit: 'second' is not a unit of length"), std::string::npos)
      << refusal(dir / "c.zarr");
}

TEST(Units, ImageJTiffSpacingAndUnit) {
  using namespace OIIO;
  test::TempDir dir;
  const fs::path p = dir / "imagej.tif";
  auto out = ImageOutput::create(p.string());
  std::vector<ImageSpec> specs(3, ImageSpec(4, 3, 1, TypeDesc::UINT8));
  for (auto& s : specs) {
    s.attribute("ImageDescription", "ImageJ=1.54f\nimages=3\nslices=3\nunit=\\u00B5m\nspacing=2.5\nloop=false\n");
    s.attribute("XResolution", 4.0f);
    s.attribute("YResolution", 4.0f);
    s.attribute("ResolutionUnit", "none");
  }
  ASSERT_TRUE(out->open(p.string(), 3, specs.data()));
  const std::vector<uint8_t> px(12, 9);
  for (int z = 0; z < 3; ++z) {
    if (z > 0) ASSERT_TRUE(out->open(p.string(), specs[size_t(z)], ImageOutput::AppendSubimage));
    ASSERT_TRUE(out->write_image(TypeDesc::UINT8, px.data()));
  }
  out->close();
  const Volume v = load_volume(p);
  EXPECT_EQ(v.unit, "µm");
  EXPECT_DOUBLE_EQ(v.spacing.x, 0.25);
  EXPECT_DOUBLE_EQ(v.spacing.y, 0.25);
  EXPECT_DOUBLE_EQ(v.spacing.z, 2.5);
}

TEST(Units, SceneUnitsAreALength) {
  const Scene s = parse_scene({{"volume", "v"}, {"units", "micron"}});
  EXPECT_EQ(s.units, "µm");
  EXPECT_EQ(scene_to_json(s)["units"], "µm");
  EXPECT_EQ(parse_scene(scene_to_json(s)).units, "µm");
  EXPECT_FALSE(scene_to_json(parse_scene({{"volume", "v"}})).contains("units"));
  EXPECT_EQ(parse_scene({{"volume", "v"}, {"units", "pixel"}}).units, "");
  EXPECT_NE(scene_refusal({{"volume", "v"}, {"units", "second"}}).find("units: 'second' is not a unit of length"),
            std::string::npos);
  EXPECT_NE(scene_refusal({{"volume", "v"}, {"units", 3}}).find("units: must be a unit of length"), std::string::npos);
}

TEST(Time, SceneTimeParsesAndIsHeldToTheVolume) {
  const Scene s = parse_scene({{"volume", "v"}, {"time", 3}});
  EXPECT_EQ(s.time, 3);
  EXPECT_EQ(scene_to_json(s)["time"], 3);
  EXPECT_FALSE(scene_to_json(parse_scene({{"volume", "v"}})).contains("time"));
  for (const json& bad : {json(-1), json(1.5), json("2"), json(2000000)})
    EXPECT_EQ(scene_refusal({{"volume", "v"}, {"time", bad}}).rfind("time: ", 0), 0u) << bad.dump();
  Volume v = test::anisotropic_blobs(SourceType::U8, {5, 4, 3});
  EXPECT_NO_THROW(resolve_scene(parse_scene({{"volume", "v"}}), v));
  try {
    resolve_scene(s, v);
    ADD_FAILURE() << "a volume of one time point has no time point 3";
  } catch (const SceneError& e) {
    EXPECT_EQ(std::string(e.what()), "time: time point 3 is outside the volume's one time point (0)");
  }
  v.time_points = 5;
  v.time_point = 3;
  EXPECT_NO_THROW(resolve_scene(s, v));
  EXPECT_EQ(time_refusal(5, 5), "time: time point 5 is outside the volume's 0..4");
  EXPECT_EQ(time_refusal(4, 5), "");
}

TEST(Time, ImageJHyperstackTimePointsAndChannels) {
  using namespace OIIO;
  test::TempDir dir;
  // 2 channels x 3 slices x 4 frames, pages in ImageJ's order (channel fastest, then slice, then
  // frame); page (c, z, t) holds 100 t + 10 z + c.
  const fs::path p = dir / "hyper.tif";
  const std::string desc = "ImageJ=1.54f\nimages=24\nchannels=2\nslices=3\nframes=4\nhyperstack=true\nmode=grayscale\n";
  auto out = ImageOutput::create(p.string());
  std::vector<ImageSpec> specs(24, ImageSpec(4, 3, 1, TypeDesc::UINT8));
  for (auto& s : specs) s.attribute("ImageDescription", desc);
  ASSERT_TRUE(out->open(p.string(), 24, specs.data()));
  for (int page = 0; page < 24; ++page) {
    const int c = page % 2, z = page / 2 % 3, t = page / 6;
    if (page > 0) ASSERT_TRUE(out->open(p.string(), specs[size_t(page)], ImageOutput::AppendSubimage));
    const std::vector<uint8_t> px(12, uint8_t(100 * t + 10 * z + c));
    ASSERT_TRUE(out->write_image(TypeDesc::UINT8, px.data()));
  }
  out->close();
  for (auto [t, c] : {std::pair{0, 0}, {2, 1}, {1, 0}}) {
    LoadOptions o;
    o.time_point = t;
    o.channel = c;
    const Volume v = load_volume(p, o);
    ASSERT_EQ(v.dims(), (Dims{4, 3, 3}));
    EXPECT_EQ(v.time_point, t);
    EXPECT_EQ(v.time_points, 4);
    for (int z = 0; z < 3; ++z) EXPECT_EQ(v.value(1, 1, z), 100 * t + 10 * z + c) << "t " << t << " c " << c;
  }
  LoadOptions bad;
  bad.time_point = 4;
  EXPECT_NE(refusal(p, bad).find("time point 4 is outside 0..3"), std::string::npos) << refusal(p, bad);
  bad = {};
  bad.channel = 2;
  EXPECT_NE(refusal(p, bad).find("channel 2 is outside 0..1"), std::string::npos);
  // A description whose channels and frames do not divide the pages.
  const fs::path q = dir / "wrong.tif";
  auto o2 = ImageOutput::create(q.string());
  std::vector<ImageSpec> s2(5, ImageSpec(4, 3, 1, TypeDesc::UINT8));
  for (auto& s : s2) s.attribute("ImageDescription", std::string("ImageJ=1.54f\nchannels=2\nframes=2\n"));
  ASSERT_TRUE(o2->open(q.string(), 5, s2.data()));
  for (int page = 0; page < 5; ++page) {
    if (page > 0) ASSERT_TRUE(o2->open(q.string(), s2[size_t(page)], ImageOutput::AppendSubimage));
    const std::vector<uint8_t> px(12, 1);
    ASSERT_TRUE(o2->write_image(TypeDesc::UINT8, px.data()));
  }
  o2->close();
  EXPECT_NE(refusal(q).find("does not divide its 5 pages"), std::string::npos) << refusal(q);
}

TEST(Time, NrrdWithATimeAxisLast) {
  test::TempDir dir;
  // 4 x 3 x 2 voxels x 5 time points: voxel i (x fastest) of time point t holds 50 t + i.
  std::string voxels;
  for (int t = 0; t < 5; ++t)
    for (int i = 0; i < 24; ++i) voxels += char(50 * t + i);
  const std::string head =
      "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 4 3 2 5\nkinds: domain domain domain time\n"
      "spacings: 0.5 0.5 2 nan\nunits: \"um\" \"um\" \"um\" \"s\"\naxis mins: 0 0 10 nan\n";
  test::write_file(dir / "raw.nrrd", head + "encoding: raw\n\n" + voxels);
  for (int t : {0, 3, 4}) {
    LoadOptions o;
    o.time_point = t;
    const Volume v = load_volume(dir / "raw.nrrd", o);
    ASSERT_EQ(v.dims(), (Dims{4, 3, 2}));
    EXPECT_EQ(v.time_point, t);
    EXPECT_EQ(v.time_points, 5);
    EXPECT_EQ(v.unit, "µm");
    EXPECT_DOUBLE_EQ(v.origin.z, 10.0) << "every time point has the same box";
    EXPECT_EQ(v.source_dims, (Dims{0, 0, 0})) << "a whole time point, not a region";
    EXPECT_EQ(v.value(1, 2, 1), 50 * t + 1 + 4 * (2 + 3 * 1));
  }
  // gzip: the same voxels.
  const auto packed = chunked::encode_chunk(chunked::compressor_by_name("gzip"),
                                            reinterpret_cast<const uint8_t*>(voxels.data()), voxels.size(), 1);
  test::write_file(dir / "gz.nrrd", head + "encoding: gzip\n\n" + std::string(packed.begin(), packed.end()));
  LoadOptions o;
  o.time_point = 2;
  EXPECT_EQ(load_volume(dir / "gz.nrrd", o).value(3, 0, 0), 100 + 3);
  o.time_point = 5;
  EXPECT_NE(refusal(dir / "raw.nrrd", o).find("time point 5 is outside 0..4"), std::string::npos);
  test::write_file(dir / "list.nrrd",
                   "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 2 4 3 2\nkinds: list domain domain domain\n"
                   "encoding: raw\n\n" +
                       std::string(48, '\x01'));
  EXPECT_NE(refusal(dir / "list.nrrd").find("holds channels, which peakcast does not read yet"), std::string::npos)
      << refusal(dir / "list.nrrd");
  test::write_file(dir / "nokinds.nrrd",
                   "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 4 3 2 2\nencoding: raw\n\n" + std::string(48, '\x01'));
  EXPECT_NE(refusal(dir / "nokinds.nrrd").find("needs 'kinds: ... time'"), std::string::npos);
  test::write_file(dir / "sizes.nrrd", "NRRD0004\ntype: uint8\ndimension: 4\nsizes: 4 3 2\nencoding: raw\n\n");
  EXPECT_NE(refusal(dir / "sizes.nrrd").find("one value per dimension"), std::string::npos);
}

TEST(Time, RawSidecarTimes) {
  test::TempDir dir;
  std::string voxels;
  for (int t = 0; t < 3; ++t)
    for (int i = 0; i < 24; ++i) voxels += char(10 * t + i);
  test::write_file(dir / "s.raw", voxels);
  test::write_file(dir / "s.raw.json", R"({"dims":[4,3,2],"dtype":"uint8","times":3})");
  LoadOptions o;
  o.time_point = 2;
  const Volume v = load_volume(dir / "s.raw", o);
  EXPECT_EQ(v.time_points, 3);
  EXPECT_EQ(v.time_point, 2);
  EXPECT_EQ(v.value(3, 2, 1), 20 + 23);
  o.time_point = 3;
  EXPECT_NE(refusal(dir / "s.raw", o).find("time point 3 is outside 0..2"), std::string::npos);
  test::write_file(dir / "s.raw.json", R"({"dims":[4,3,2],"dtype":"uint8","times":0})");
  EXPECT_NE(refusal(dir / "s.raw").find("'times' must be an integer"), std::string::npos);
  test::write_file(dir / "s.raw.json", R"({"dims":[4,3,2],"dtype":"uint8","times":4})");
  EXPECT_NE(refusal(dir / "s.raw").find("truncated"), std::string::npos) << "4 time points promised, 3 held";
}
