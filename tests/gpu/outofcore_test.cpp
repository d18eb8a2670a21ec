// Out-of-core stills (distributed/brick_sequence.h): a volume larger than a host memory budget,
// read brick after brick from its file (OME-Zarr chunks or a NRRD's rows) and drawn front to back,
// must give the image one process renders of the whole volume, for every method, within the
// bound the brick tests hold (brick_test.cpp: 1/255; rays run until opaque in both). Its
// statistics (range, histogram, macrocell grids), reduced brick by brick, must equal the whole
// volume's.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <string>

#include "chunked/zarr_writer.h"
#include "core/generators.h"
#include "core/macrocells.h"
#include "core/volume_io.h"
#include "distributed/brick_sequence.h"
#include "gpu/gpu_fixture.h"
#include "unit/test_util.h"

using namespace peakcast;
namespace fs = std::filesystem;

namespace {

struct Case {
  std::string render, tf, camera;
};

// A generated volume written as OME-Zarr in `chunk`-voxel chunks; the path of the .zarr folder.
fs::path zarr_of(const test::TempDir& tmp, GeneratorKind kind, const Dims& dims, SourceType type, glm::dvec3 spacing,
                 int chunk = 8) {
  const fs::path nrrd = tmp / (std::string(to_string(kind)) + ".nrrd");
  GeneratorSpec g;
  g.kind = kind;
  g.dims = dims;
  g.type = type;
  g.spacing = spacing;
  generate_to_file(g, nrrd.string());
  const fs::path out = tmp / (std::string(to_string(kind)) + ".zarr");
  chunked::ZarrWriteOptions o;
  o.chunk = chunk;
  chunked::write_ome_zarr(load_volume(nrrd), out, o);
  return out;
}

double max_abs(const Image& a, const Image& b) {
  double m = 0.0;
  for (size_t k = 0; k < a.rgba.size(); ++k) m = std::max(m, double(std::abs(a.rgba[k] - b.rgba[k])));
  return m;
}

// The whole volume's statistics must come out of the bricks unchanged.
void expect_same_statistics(const Volume& whole, const distributed::SequenceStatistics& s) {
  EXPECT_EQ(s.box.min_value, whole.min_value);
  EXPECT_EQ(s.box.max_value, whole.max_value);
  EXPECT_EQ(s.box.histogram, whole.histogram);
  EXPECT_EQ(s.box.border_histogram, whole.border_histogram);
  EXPECT_FALSE(whole.border_histogram.empty());
  const VolumeMacrocells cells = build_volume_macrocells(whole);
  for (auto [a, b] : {std::pair{cells.trilinear, s.cells.trilinear}, {cells.tricubic, s.cells.tricubic}}) {
    EXPECT_EQ(a->grid, b->grid);
    EXPECT_EQ(a->min, b->min);
    EXPECT_EQ(a->max, b->max);
  }
}

// Bytes: the 41^3 float volume (270 KiB) takes >= 6 bricks. Budgets this small give the bricks
// half their share (the rest is the image's: brick_sequence.cpp), so they are twice the voxels'.
const int64_t kBudget = 216 << 10;

double sequence_error(const Case& c, const fs::path& path, int64_t budget = kBudget) {
  const Volume whole = load_volume(path);
  const std::string text = std::string(R"({"volume": "v", "image": {"width": 96, "height": 80}, "render": )") +
                           c.render + (c.tf.empty() ? "" : R"(, "tf": {"points": )" + c.tf + "}") +
                           (c.camera.empty() ? "" : R"(, "camera": )" + c.camera) +
                           R"(, "background": [0.1, 0.2, 0.3]})";
  Scene scene = parse_scene_text(text);
  scene.render.early_termination = 1.0;  // bricks run until opaque: so does the one-process image
  render::Renderer& renderer = *test::gpu().caster;
  auto resident = renderer.make_resident(std::make_shared<Volume>(load_volume(path)));
  const Image one = renderer.render(*resident, resolve_scene(scene, whole));

  const auto stats = distributed::sequence_statistics(path.string(), {}, budget);
  expect_same_statistics(whole, stats);
  const ResolvedScene rs = resolve_scene(scene, stats.box);
  const auto r = distributed::render_sequence(renderer, path.string(), {}, stats, rs, budget);
  EXPECT_LE(2 * r.largest_brick_bytes, budget / 10 * 9) << "two bricks are held at once, in 90% of the budget";
  // These budgets (at most 2 MiB) are too small for the whole image's buffers (8 RGBA float
  // images, 960 KiB here) beside the bricks: the still is drawn in bands of rows, each over every
  // brick (image_tiles; 2 MiB: 2 bands), whose joined image must be the one-process image, or,
  // where that would take more than kMaxImageTiles bands, whole, saying it held more.
  EXPECT_TRUE(r.tiles > 1 || r.budget_too_small) << r.tiles;
  EXPECT_GE(r.bricks, 2 * whole.byte_size() > size_t(budget) ? 2 : 1);
  const double e = max_abs(one, r.image);
  std::printf("  %s: %d bricks (ghost %d), %d bands, max abs %.3g\n", c.render.c_str(), r.bricks, r.ghost, r.tiles, e);
  return e;
}

// What the brick tests hold (brick_test.cpp kBound; measured there).
constexpr double kBound = 1.0 / 255.0;

}  // namespace

TEST(OutOfCore, EveryMethodEqualsTheInCoreStill) {
  test::TempDir tmp;
  const fs::path ml = zarr_of(tmp, GeneratorKind::MarschnerLobb, {41, 41, 41}, SourceType::F32, {1, 1, 1});
  const std::string ml_tf =
      R"([[0, 0.2, 0.4, 1, 0], [0.45, 0.2, 0.4, 1, 0], [0.5, 1, 0.8, 0.3, 0.8], [0.55, 0.2, 0.4, 1, 0], [1, 0.2, 0.4, 1, 0.05]])";
  const std::string ml_cam = R"({"eye": [90, 70, 110], "center": [20, 20, 20], "up": [0, 1, 0], "fov_y": 30})";
  for (const char* r :
       {R"({"step": 0.7})", R"({"step": 1.5, "classification": "preint"})", R"({"step": 1, "classification": "peaks"})",
        R"({"step": 1, "classification": "peaks", "peak_mode": "xor"})",
        R"({"step": 0.5, "filter": "tricubic", "shading": true})",
        R"({"sampling": "differential", "s_k": 1.5, "classification": "preint"})",
        R"({"sampling": "differential", "s_k": 3, "classification": "peaks"})",
        R"({"step": 2, "virtual_samples": 3, "classification": "peaks"})",
        R"({"step": 2, "virtual_samples": 7, "classification": "preint"})"})
    EXPECT_LE(sequence_error({r, ml_tf, ml_cam}, ml), kBound) << r;

  const fs::path blobs = zarr_of(tmp, GeneratorKind::Blobs, {64, 56, 48}, SourceType::U16, {0.8, 1.0, 1.7});
  const std::string cam = R"({"eye": [-40, 90, -30], "center": [19, 19, 30], "up": [0, 0, 1], "fov_y": 35})";
  const std::string tf =
      R"([[0, 0, 0, 0, 0], [15000, 0.9, 0.5, 0.2, 0], [30000, 0.9, 0.5, 0.2, 0.4], [65535, 1, 1, 1, 0.9]])";
  const std::string terminate =
      R"({"channel": "termination", "center": [0.45, 0.5], "radius": 0.3, "falloff": 0.5, "value": 0.25})";
  const std::string step = R"({"channel": "step", "center": [0.6, 0.4], "radius": 0.25, "value": 2.5})";
  const double bound = test::gpu().gl ? 0.015 : kBound;  // GL: brick_test's bound for 8-bit filter weights
  for (const std::string& r :
       {std::string(R"({"step": 0.5, "adaptive": true, "classification": "preint"})"),
        std::string(R"({"step": 1, "virtual_samples": 3})"),
        R"({"step": 1, "classification": "preint", "ray_texture": {"mapping": "view", "size": [32, 32], "strokes": [)" +
            terminate + ", " + step + "]}}"})
    EXPECT_LE(sequence_error({r, tf, cam}, blobs, 400 << 10), bound) << r;
  // Adaptive steps with virtual samples and shading need 16 ghost voxels: a budget for 2 bricks.
  EXPECT_LE(sequence_error({R"({"step": 0.7, "adaptive": true, "virtual_samples": 3, "shading": true})", tf, cam},
                           blobs, 1200 << 10),
            bound);  // GL: brick_test's 8-bit bound
}

// A real volume from its NRRD (rows read per brick), with a Dirac-like peak, and the default TF
// and camera (derived from the statistics the bricks reduce).
TEST(OutOfCore, RealVolumeFromRowsWithDerivedTfAndCamera) {
  const fs::path heptane = test::data_dir() / "heptane_151.nrrd";
  EXPECT_LE(
      sequence_error(
          {R"({"step": 1, "classification": "peaks"})",
           R"([[0, 0, 0, 0, 0], [100, 0, 0, 0, 0], [100.5, 1, 0.6, 0.2, 1], [101, 0, 0, 0, 0], [255, 0, 0, 0, 0]])",
           ""},
          heptane, 2 << 20),
      kBound);
  EXPECT_LE(sequence_error({R"({"step": 1})", "", ""}, heptane, 2 << 20), kBound);
}

TEST(OutOfCore, BudgetsThatCannotHoldABrickAreRefused) {
  const distributed::Index3 dims{64, 64, 64};
  EXPECT_EQ(distributed::bricks_for_budget(dims, 0, 1, 64 * 64 * 64, 1), 1);
  auto held = [&](int bricks) {  // bytes of the two largest-brick reads held at once, 2 bytes a voxel
    int64_t m = 0;
    for (const auto& b : distributed::kd_split(dims, bricks, 3).bricks) m = std::max(m, b.voxels_read());
    return 2 * 2 * m;
  };
  const int n = distributed::bricks_for_budget(dims, 3, 2, 200000, 2);
  EXPECT_LE(held(n), 200000);
  EXPECT_GT(held(n - 1), 200000) << "the fewest bricks that fit";
  EXPECT_THROW(distributed::bricks_for_budget(dims, 3, 4, 1000, 2), std::invalid_argument);
}

namespace {

// /proc/self/status's `key` (VmRSS, VmHWM) in MiB; -1 where /proc is not there.
double status_mib(const std::string& key) {
  std::ifstream f("/proc/self/status");
  std::string k;
  for (double kib; f >> k;)
    if (k == key + ":" && f >> kib)
      return kib / 1024.0;
    else
      f.ignore(1 << 10, '\n');
  return -1.0;
}

}  // namespace

// The budget is what the process holds: the peak resident memory while a still is reduced and
// drawn by bricks stays within the budget plus 10% (the goal bench outofcore measures at scale),
// here for a 64 MiB volume under a 16 MiB budget, plus what does not grow with the budget: the
// renderer's tables, thread stacks, code pages, the allocator's slack (measured 4 to 8 MiB over a
// 32 MiB budget's voxels and grids, on 2 cores as in CI). Measured 15.0 to 17.7 MiB over the
// process before, on a loaded machine too; with the voxels on the heap (before voxel_memory.h) 28.5 and 32.3. The CPU
// backend only: llvmpipe keeps a brick's texture in host memory beside the brick read ahead (on
// a GPU it is device memory, which --gpu-budget-mib bounds).
TEST(OutOfCore, PeakMemoryStaysWithinTheBudget) {
  if (test::gpu().gl) GTEST_SKIP() << "llvmpipe's textures are host memory";
  test::TempDir tmp;
  const fs::path zarr = zarr_of(tmp, GeneratorKind::Blobs, {512, 256, 256}, SourceType::U16, {1, 1, 1}, 32);
  const int64_t budget = int64_t(16) << 20;
  Scene scene = parse_scene_text(R"({"volume": "v", "image": {"width": 128, "height": 96},
      "render": {"step": 1, "classification": "preint", "shading": true},
      "camera": {"eye": [-300, 200, -150], "center": [256, 128, 128], "up": [0, 0, 1], "fov_y": 30}})");
  render::Renderer& renderer = *test::gpu().caster;
  std::ofstream clear("/proc/self/clear_refs");
  if (!(clear << "5" << std::flush)) GTEST_SKIP() << "VmHWM cannot be reset here";  // the peak from here on
  const double before = status_mib("VmRSS");
  ASSERT_GT(before, 0.0);
  const auto stats = distributed::sequence_statistics(zarr.string(), {}, budget);
  const double statistics_peak = status_mib("VmHWM") - before;
  const auto r =
      distributed::render_sequence(renderer, zarr.string(), {}, stats, resolve_scene(scene, stats.box), budget);
  const double peak = status_mib("VmHWM") - before;
  std::printf(
      "  %d statistics bricks, %d bricks (largest %.2f MiB): peak %.2f MiB over %.1f MiB before "
      "(statistics %.2f); budget %.0f MiB\n",
      stats.bricks, r.bricks, double(r.largest_brick_bytes) / 1048576.0, peak, before, statistics_peak,
      double(budget) / 1048576.0);
  EXPECT_GE(r.bricks, 8);
  EXPECT_FALSE(stats.budget_too_small);
  EXPECT_FALSE(r.budget_too_small);
  constexpr double kFixedMiB = 4.0;
  EXPECT_LE(peak, 1.1 * double(budget) / 1048576.0 + kFixedMiB);
}

// A still whose whole image's buffers are the budget (512x256: 8 RGBA float images, 16 MiB,
// against 16 MiB) is drawn in bands of rows, so the budget still holds: the peak stays within
// the budget as above plus the finished image itself (2.5 MiB with its sample counts), which no
// band structure avoids. Drawn whole, the buffers left the bricks half their share and the still
// held more than the budget (a 1024² still held 1.34x): measured 27.9 MiB over the process before,
// against 11.9 MiB in 4 bands.
TEST(OutOfCore, ALargeImageIsDrawnInBandsWithinTheBudget) {
  if (test::gpu().gl) GTEST_SKIP() << "llvmpipe's textures are host memory";
  test::TempDir tmp;
  const fs::path zarr = zarr_of(tmp, GeneratorKind::Blobs, {512, 256, 256}, SourceType::U16, {1, 1, 1}, 32);
  const int64_t budget = int64_t(16) << 20;
  Scene scene = parse_scene_text(R"({"volume": "v", "image": {"width": 512, "height": 256},
      "render": {"step": 2, "classification": "post"},
      "camera": {"eye": [-300, 200, -150], "center": [256, 128, 128], "up": [0, 0, 1], "fov_y": 30}})");
  render::Renderer& renderer = *test::gpu().caster;
  std::ofstream clear("/proc/self/clear_refs");
  if (!(clear << "5" << std::flush)) GTEST_SKIP() << "VmHWM cannot be reset here";
  const double before = status_mib("VmRSS");
  const auto stats = distributed::sequence_statistics(zarr.string(), {}, budget);
  const ResolvedScene rs = resolve_scene(scene, stats.box);
  const auto r = distributed::render_sequence(renderer, zarr.string(), {}, stats, rs, budget);
  const double peak = status_mib("VmHWM") - before;
  const double image_mib = 512.0 * 256.0 * 5.0 * sizeof(float) / 1048576.0;
  std::printf("  %d bands, %d bricks: peak %.2f MiB over %.1f MiB before; budget %.0f MiB, image %.2f MiB\n", r.tiles,
              r.bricks, peak, before, double(budget) / 1048576.0, image_mib);
  EXPECT_EQ(r.tiles, distributed::image_tiles(rs, budget));
  EXPECT_EQ(r.tiles, 4);
  EXPECT_FALSE(r.budget_too_small);
  EXPECT_LE(peak, 1.1 * double(budget) / 1048576.0 + 4.0 + image_mib);
  // The bands join: every row drawn, the picture not black.
  double sum = 0;
  for (size_t p = 0; p < r.image.rgba.size(); p += 4) sum += r.image.rgba[p + 3];
  EXPECT_GT(sum / double(512 * 256), 0.05);
}
