// `peakcast convert IN OUT.zarr` by slabs (server/chunked/zarr_convert.h): for every source type,
// raw and gzip-compressed inputs, slabs of one and of several chunk edges, the pyramid written
// from slabs equals the one written from the whole volume file for file, byte for byte (NaN and
// Inf replaced alike); and each refusal.
#include "chunked/zarr_convert.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>

#include "core/volume_writer.h"
#include "unit/test_util.h"

namespace fs = std::filesystem;
using namespace peakcast;
using namespace peakcast::chunked;

namespace {

std::string contents(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// Files of `a` missing from `b` or different there, and files of `b` not in `a`.
int64_t tree_differences(const fs::path& a, const fs::path& b) {
  int64_t files = 0, wrong = 0;
  for (const auto& e : fs::recursive_directory_iterator(a)) {
    if (!e.is_regular_file()) continue;
    ++files;
    const fs::path other = b / fs::relative(e.path(), a);
    if (!fs::exists(other) || contents(e.path()) != contents(other)) {
      ADD_FAILURE() << "differs: " << fs::relative(e.path(), a);
      ++wrong;
    }
  }
  for (const auto& e : fs::recursive_directory_iterator(b)) files -= e.is_regular_file();
  return wrong + std::abs(files);
}

}  // namespace

TEST(ZarrConvert, SlabsWriteTheSamePyramidAsTheWholeVolume) {
  test::TempDir tmp;
  struct Case {
    Dims dims;
    int levels;
  };
  // Odd edges at every level; a volume thinner than a chunk in y and z (its chunks are thin too).
  for (const Case c : {Case{{37, 21, 45}, 4}, Case{{9, 5, 6}, 2}})
    for (SourceType type : {SourceType::U8, SourceType::I8, SourceType::U16, SourceType::I16, SourceType::F32}) {
      Volume src = test::anisotropic_blobs(type, c.dims);
      if (type == SourceType::F32) {  // non-finite voxels: replaced by the finite range, as a whole
                                      // read does
        float* f = reinterpret_cast<float*>(src.data());
        f[5] = std::numeric_limits<float>::quiet_NaN();
        f[src.voxel_count() / 2] = std::numeric_limits<float>::infinity();
        f[src.voxel_count() - 7] = -std::numeric_limits<float>::infinity();
      }
      for (bool gzip : {false, true}) {
        const fs::path in =
            tmp / (std::string(to_string(type)) + std::to_string(c.dims[0]) + (gzip ? "_gz" : "") + ".nrrd");
        write_volume(in, src, {gzip});
        ZarrWriteOptions o;
        o.chunk = 8;
        o.pyramid = true;
        const fs::path whole = tmp / (in.stem().string() + "_whole.zarr");
        write_ome_zarr(load_volume(in), whole, o);
        const int64_t plane = c.dims[0] * c.dims[1] * int64_t(voxel_bytes(storage_type(type)));
        const int64_t edge = std::min<int64_t>(8, c.dims[2]);
        for (int64_t budget : {int64_t(1), 2 * 24 * plane}) {  // slabs of one chunk edge of planes; of 24
          SCOPED_TRACE(in.filename().string() + " budget " + std::to_string(budget));
          const fs::path out = tmp / (in.stem().string() + "_" + std::to_string(budget) + ".zarr");
          const auto r = convert_to_ome_zarr_by_slabs(in, out, {}, o, budget);
          EXPECT_EQ(r.slab_planes, budget == 1 ? edge : std::min<int64_t>(24, c.dims[2]));  // never past the volume
          EXPECT_LE(r.slab_bytes, r.slab_planes * plane);
          EXPECT_EQ(r.passes, type == SourceType::F32 ? 2 : 1);
          EXPECT_EQ(r.zarr.levels, c.levels);  // 45 -> 23 -> 12 -> 6 (<= 8); 9 -> 5
          EXPECT_EQ(r.header.dims, c.dims);
          EXPECT_EQ(tree_differences(whole, out), 0);
          EXPECT_FALSE(fs::exists(partial_path(out)));
        }
      }
    }
}

TEST(ZarrConvert, Refusals) {
  test::TempDir tmp;
  const Volume src = test::anisotropic_blobs(SourceType::U8, {16, 12, 10});
  const fs::path in = tmp / "v.nrrd";
  write_volume(in, src, {});
  ZarrWriteOptions o;
  o.chunk = 8;
  const auto refused = [&](auto&& call, const std::string& words) {
    try {
      call();
      ADD_FAILURE() << "accepted; expected: " << words;
    } catch (const std::exception& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  convert_to_ome_zarr_by_slabs(in, tmp / "a.zarr", {}, o, 1);
  refused([&] { convert_to_ome_zarr_by_slabs(in, tmp / "a.zarr", {}, o, 1); }, "already exists");
  refused([&] { convert_to_ome_zarr_by_slabs(tmp / "none.nrrd", tmp / "b.zarr", {}, o, 1); }, "none.nrrd");
  refused([&] { convert_to_ome_zarr_by_slabs(in, tmp / "c.zarr", {}, o, 0); }, "memory budget must be positive");
  o.chunk = 0;
  refused([&] { convert_to_ome_zarr_by_slabs(in, tmp / "d.zarr", {}, o, 1); }, "chunk edge");
  for (const char* name : {"b.zarr", "c.zarr", "d.zarr"}) EXPECT_FALSE(fs::exists(tmp / name)) << name;
  // A float input with NaN and nonfinite: refuse says how many, and writes nothing.
  Volume f = test::anisotropic_blobs(SourceType::F32, {16, 12, 10});
  reinterpret_cast<float*>(f.data())[9] = std::numeric_limits<float>::quiet_NaN();
  write_volume(tmp / "f.nrrd", f, {});
  LoadOptions refuse;
  refuse.nonfinite = NonFinitePolicy::Refuse;
  o.chunk = 8;
  refused([&] { convert_to_ome_zarr_by_slabs(tmp / "f.nrrd", tmp / "e.zarr", refuse, o, 1); },
          "1 voxels are NaN or Inf");
  EXPECT_FALSE(fs::exists(tmp / "e.zarr"));
}
