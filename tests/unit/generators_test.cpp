#include <gtest/gtest.h>

#include <cmath>

#include "core/generators.h"
#include "core/vessel_tree.h"
#include "core/volume_io.h"
#include "unit/test_util.h"

using namespace peakcast;

namespace {

uint64_t hash_of(const Volume& v) { return test::fnv1a(v.data(), v.byte_size()); }

TEST(Generators, DeterministicForASeedAndDifferentAcrossSeeds) {
  for (auto kind : {GeneratorKind::MarschnerLobb, GeneratorKind::Blobs, GeneratorKind::Fire, GeneratorKind::Em,
                    GeneratorKind::Sphere, GeneratorKind::Ramp, GeneratorKind::Vessels}) {
    GeneratorSpec s;
    s.kind = kind;
    s.dims = {37, 23, 19};
    s.type = default_type(kind);
    s.seed = 7;
    const uint64_t a = hash_of(generate_volume(s)), b = hash_of(generate_volume(s));
    EXPECT_EQ(a, b) << to_string(kind);
    if (kind == GeneratorKind::Blobs || kind == GeneratorKind::Em || kind == GeneratorKind::Vessels) {
      s.seed = 8;
      EXPECT_NE(a, hash_of(generate_volume(s))) << to_string(kind);
    }
  }
}

// Pinned hashes (FNV-1a of the voxel bytes, 37x23x19, seed 7, each kind's default type): a change
// to any generator shows up here. Update deliberately, saying why in the commit.
TEST(Generators, OutputIsPinned) {
  const std::pair<GeneratorKind, uint64_t> pinned[] = {
      {GeneratorKind::MarschnerLobb, 0x1003e795e92b294full}, {GeneratorKind::Blobs, 0xfbe8beb109b3e242ull},
      {GeneratorKind::Fire, 0x66be7da8721f6669ull},          {GeneratorKind::Em, 0xc76e266ebc17e828ull},
      {GeneratorKind::Sphere, 0x281d1f1346c94d82ull},        {GeneratorKind::Ramp, 0x03e85a70dbfece64ull},
      {GeneratorKind::Vessels, 0x533c2ee0940f682aull}};
  for (auto [kind, hash] : pinned) {
    GeneratorSpec s;
    s.kind = kind;
    s.dims = {37, 23, 19};
    s.type = default_type(kind);
    s.seed = 7;
    EXPECT_EQ(hash_of(generate_volume(s)), hash) << to_string(kind) << " 0x" << std::hex << hash_of(generate_volume(s));
  }
}

TEST(Generators, FileOutputEqualsInMemoryAndIsPinned) {
  test::TempDir dir;
  GeneratorSpec s;
  s.kind = GeneratorKind::Em;
  s.dims = {50, 40, 35};  // not a multiple of the 16-slice slab
  s.seed = 3;
  s.type = SourceType::U16;
  generate_to_file(s, dir / "em.raw");
  Volume f = load_volume(dir / "em.raw");
  Volume m = generate_volume(s);
  EXPECT_TRUE(test::same_volume(f, m));
  EXPECT_EQ(hash_of(f), hash_of(m));
  EXPECT_EQ(hash_of(f), 0x8b6551f7bdef9015ull) << "0x" << std::hex << hash_of(f);
}

TEST(Generators, MarschnerLobbMatchesTheFormula) {
  GeneratorSpec s;
  s.kind = GeneratorKind::MarschnerLobb;
  s.dims = {41, 41, 41};
  s.type = SourceType::F32;
  Volume v = generate_volume(s);
  // Centre (0,0,0): r = 0 -> rho_r = cos(2 pi 6) = 1; (1 - 0 + 0.25 * 2) / 2.5 = 0.6
  EXPECT_NEAR(v.value(20, 20, 20), 0.6, 1e-6);
  EXPECT_GE(v.min_value, 0.0);
  EXPECT_LE(v.max_value, 1.0);
}

TEST(Generators, RampIsLinearInX) {
  GeneratorSpec s;
  s.kind = GeneratorKind::Ramp;
  s.dims = {11, 3, 3};
  s.type = SourceType::F32;
  Volume v = generate_volume(s);
  for (int i = 0; i < 11; ++i) EXPECT_NEAR(v.value(i, 1, 2), i / 10.0, 1e-7);
}

TEST(Generators, EmHasMembranesAndCytoplasm) {
  GeneratorSpec s;
  s.kind = GeneratorKind::Em;
  s.dims = {96, 96, 96};
  s.type = SourceType::U16;
  Volume v = generate_volume(s);
  int64_t bright = 0;
  for (int64_t i = 0; i < v.voxel_count(); ++i) bright += v.stored(size_t(i)) > 0.6 * 65535;
  const double share = double(bright) / double(v.voxel_count());
  EXPECT_GT(share, 0.01);  // membranes exist
  EXPECT_LT(share, 0.3);   // but are thin
}

// The angiography stand-in: a thin tree of bright lumen on dim tissue, the aneurysm bright at its
// centre, tissue never black (so a TF can tell tissue from air) and never near the lumen value.
TEST(Generators, VesselsAreThinBrightTubesOnDimTissue) {
  GeneratorSpec s;
  s.kind = GeneratorKind::Vessels;
  s.dims = {64, 64, 64};
  s.type = SourceType::U16;
  Volume v = generate_volume(s);
  const VesselTree tree = make_vessel_tree(s.seed, s.dims);
  EXPECT_EQ(tree.tubes.size(), 63u);
  int64_t lumen = 0, tissue = 0;
  for (int64_t i = 0; i < v.voxel_count(); ++i) {
    const double x = v.stored(size_t(i)) / 65535.0;
    lumen += x > 0.8;
    tissue += x > 0.07 && x < 0.13;
  }
  const double n = double(v.voxel_count());
  EXPECT_GT(lumen / n, 0.002);  // vessels exist (0.4% measured at 64^3)
  EXPECT_LT(lumen / n, 0.15);   // and are thin
  EXPECT_GT(tissue / n, 0.7);   // the rest is tissue
  const glm::dvec3 c = tree.sac_center;
  EXPECT_GT(tree.value(std::llround(c.x), std::llround(c.y), std::llround(c.z)), 0.85);
}

TEST(Generators, UnknownKindRefused) { EXPECT_THROW(parse_generator_kind("zebra"), std::invalid_argument); }

}  // namespace
