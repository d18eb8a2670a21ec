// `bench outofcore`: a synthetic OME-Zarr pyramid larger than this machine's memory (4096^3 uint8
// = 64 GiB of voxels by default), written chunk by chunk, then what a viewer pays: opening it from
// its metadata, the first interactive frame from the finest level that fits the memory budget,
// and a full-resolution still by bricks (distributed/brick_sequence.h) with its bytes read and
// peak RSS against the budget. The pyramid is deleted after (unless --keep).
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>

#include "bench/bench_scenes.h"
#include "bench/bench_util.h"
#include "bench/commands.h"
#include "chunked/chunked_volume.h"
#include "chunked/zarr_writer.h"
#include "core/volume_io.h"
#include "distributed/brick_sequence.h"

namespace fs = std::filesystem;

namespace peakcast::bench {
namespace {

struct OutOfCoreArgs {
  int64_t size = 4096, chunk = 128, budget_mib = 4096;
  int64_t preview_voxels = int64_t(1) << 24;  // serve's --preview-voxels default
  int image = 1024;
  std::string dir;
  bool keep = false, json = false;
};

using Clock = std::chrono::steady_clock;

// Level k's voxel i along an axis of n level-0 voxels: a product of sines through the centre of
// its 2^k block (about the block's mean), period n/6, so the volume holds a lattice of blobs,
// quantised to 32 grey levels so that zstd keeps 64 GiB of voxels to a few GiB of disk.
std::vector<float> axis_table(int64_t n0, int64_t n, int k) {
  std::vector<float> t(static_cast<size_t>(n));
  const double f = std::ldexp(1.0, k);
  for (int64_t i = 0; i < n; ++i)
    t[size_t(i)] = float(std::sin(2.0 * std::numbers::pi * 6.0 * (f * double(i) + 0.5 * (f - 1.0)) / double(n0)));
  return t;
}

// Writes the synthetic pyramid at `path` chunk by chunk; its write time, levels and size go into `out`.
void write_pyramid(const OutOfCoreArgs& a, const fs::path& path, nlohmann::json& out) {
  // 1. The pyramid, chunk by chunk (zstd level 1: the writer's time is not what is measured).
  VolumeHeader h;
  h.dims = {a.size, a.size, a.size};
  h.source = SourceType::U8;
  const int levels = chunked::pyramid_levels(h.dims, a.chunk);
  std::vector<std::array<std::vector<float>, 3>> tables(static_cast<size_t>(levels));
  for (int k = 0; k < levels; ++k) {
    const int64_t n = (a.size + (int64_t(1) << k) - 1) >> k;
    for (int ax = 0; ax < 3; ++ax) tables[size_t(k)][size_t(ax)] = axis_table(a.size, n, k);
  }
  chunked::ZarrWriteOptions zo;
  zo.chunk = a.chunk;
  zo.compressor = {chunked::Compressor::Zstd, 1};
  auto t = Clock::now();
  const auto written = chunked::write_ome_zarr_levels(
      path, h, levels, "synthetic", zo, [&](int k, int64_t, const Dims& lo, const Dims& box, uint8_t* dst) {
        const auto& tb = tables[size_t(k)];
        for (int64_t z = 0; z < box[2]; ++z)
          for (int64_t y = 0; y < box[1]; ++y) {
            const float yz = tb[1][size_t(lo[1] + y)] * tb[2][size_t(lo[2] + z)];
            uint8_t* row = dst + (z * box[1] + y) * box[0];
            for (int64_t x = 0; x < box[0]; ++x)
              row[x] = uint8_t(8 * int(std::lround(16.f + 15.f * tb[0][size_t(lo[0] + x)] * yz)));
          }
      });
  out["write_s"] = ms_between(t, Clock::now()) / 1000.0;
  out["levels"] = written.levels;
  out["disk_gib"] = double(written.bytes) / double(1 << 30);
  std::fprintf(stderr, "wrote %s: %d levels, %lld chunks, %.2f GiB on disk, %.0f s\n", path.c_str(), written.levels,
               (long long)written.chunks, out["disk_gib"].get<double>(), out["write_s"].get<double>());
}

// A first frame from level k as serve draws it (read, resident, rendered); its figures go into `out` under `key`.
void time_first_frame(BenchRenderer& b, const chunked::ChunkedVolume& cv, const Scene& scene, int image, int k,
                      const std::string& key, nlohmann::json& out) {
  const auto t = Clock::now();
  LoadOptions lo;
  lo.level = k;
  auto coarse = std::make_shared<Volume>(chunked::read_level(cv, k, lo));
  const double read_ms = ms_between(t, Clock::now());
  auto resident = b.renderer->make_resident(coarse);
  // As serve draws a viewer's first frame: interactive, at half the size and twice the step.
  ResolvedScene rs = resolve_scene(scene, *coarse);
  rs.scene.width = rs.scene.height = std::max(1, image / 2);
  rs.step *= 2.0;
  b.renderer->render(*resident, rs);
  out[key + "_level"] = k;
  out[key + "_dims"] = coarse->dims();
  out[key + "_read_ms"] = read_ms;
  out[key + "_frame_ms"] = ms_between(t, Clock::now());
}

// What the full-resolution still left for the text report beside `out`.
struct StillCounts {
  int bricks = 0, statistics_bricks = 0;
  double statistics_ms = 0, rss_before = 0;
};

// The full-resolution still by bricks within the budget, its peak RSS from here on; its figures go into `out`.
StillCounts time_still(BenchRenderer& b, const fs::path& path, const Scene& scene, int64_t budget,
                       nlohmann::json& out) {
  reset_peak_rss();
  const double rss_before = rss_mib();
  const auto t = Clock::now();
  const auto stats = distributed::sequence_statistics(path.string(), {}, budget);
  out["statistics_peak_rss_over_before_mib"] = peak_rss_mib() - rss_before;  // the drawing's follows
  const ResolvedScene rs = resolve_scene(scene, stats.box);
  const auto r = distributed::render_sequence(*b.renderer, path.string(), {}, stats, rs, budget);
  out["still_s"] = ms_between(t, Clock::now()) / 1000.0;
  out["still_statistics_s"] = stats.ms / 1000.0;
  out["still_bricks"] = r.bricks;
  out["still_statistics_bricks"] = stats.bricks;
  out["still_bytes_read_gib"] = double(stats.bytes_read + r.bytes_read) / double(1 << 30);
  out["still_peak_rss_mib"] = peak_rss_mib();
  out["rss_before_still_mib"] = rss_before;  // the process without voxels: libraries, the renderer
  out["still_rss_over_before_mib"] = out["still_peak_rss_mib"].get<double>() - rss_before;
  return {r.bricks, stats.bricks, stats.ms, rss_before};
}

// The text report: each figure against its goal.
void print_outofcore(const OutOfCoreArgs& a, const nlohmann::json& out, const std::string& backend, int preview,
                     int level, const StillCounts& c) {
  const double rss_before = c.rss_before;
  std::printf("outofcore %lld^3 uint8 (%.1f GiB of voxels), budget %lld MiB, %s\n", (long long)a.size,
              double(a.size) * double(a.size) * double(a.size) / double(1 << 30), (long long)a.budget_mib,
              backend.c_str());
  std::printf("  open (metadata)       %8.1f ms   (goal <= 1000)\n", out["open_ms"].get<double>());
  std::printf("  first interactive     %8.1f ms   (goal <= 2000; preview level %d, read %.0f ms)\n",
              out["first_frame_ms"].get<double>(), preview, out["preview_read_ms"].get<double>());
  std::printf("  level within budget   %8.1f ms   (level %d, read %.0f ms; replaces the preview)\n",
              out["interactive_frame_ms"].get<double>(), level, out["interactive_read_ms"].get<double>());
  std::printf("  full-resolution still %8.1f s    (%d bricks; statistics %.1f s over %d bricks; %.1f GiB read)\n",
              out["still_s"].get<double>(), c.bricks, c.statistics_ms / 1000.0, c.statistics_bricks,
              out["still_bytes_read_gib"].get<double>());
  std::printf(
      "  peak RSS during still %8.1f MiB  (%.1f MiB over the %.1f MiB before it; goal <= budget + 10%% = %.0f;"
      " statistics alone %.1f over)\n",
      out["still_peak_rss_mib"].get<double>(), out["still_peak_rss_mib"].get<double>() - rss_before, rss_before,
      1.1 * double(a.budget_mib), out["statistics_peak_rss_over_before_mib"].get<double>());
}

int run_outofcore(const OutOfCoreArgs& a) {
  const fs::path dir = a.dir.empty() ? fs::temp_directory_path() : fs::path(a.dir);
  const fs::path path = dir / ("peakcast-outofcore-" + std::to_string(a.size) + ".zarr");
  std::error_code ec;
  fs::remove_all(path, ec);
  const int64_t budget = a.budget_mib << 20;
  nlohmann::json out = {{"size", a.size}, {"chunk", a.chunk}, {"budget_mib", a.budget_mib}, {"image", a.image}};

  write_pyramid(a, path, out);

  // 2. Open: metadata only.
  const auto t = Clock::now();
  const auto cv = chunked::open_chunked(path);
  out["open_ms"] = ms_between(t, Clock::now());

  // 3. The first interactive frame, as `serve` shows it: the preview level (the finest within
  // --preview-voxels), read, resident, one interactive frame of the default scene (derived TF,
  // three-quarter view; half the size, twice the step); then the same for the level within the
  // budget, which replaces it.
  BenchRenderer b = make_bench_renderer();
  Scene scene = parse_scene_text(R"({"volume": "v"})");
  scene.width = scene.height = a.image;
  const int level = chunked::finest_level_within(*cv, 0, budget);
  const int preview = a.preview_voxels > 0 ? chunked::finest_level_of_voxels(*cv, level, a.preview_voxels) : level;
  time_first_frame(b, *cv, scene, a.image, preview, "preview", out);
  out["first_frame_ms"] = out["preview_frame_ms"].get<double>() + out["open_ms"].get<double>();
  time_first_frame(b, *cv, scene, a.image, level, "interactive", out);

  // 4. The full-resolution still by bricks, its peak RSS from here on.
  const StillCounts still = time_still(b, path, scene, budget, out);
  out["backend"] = b.description();
  if (!a.keep) fs::remove_all(path, ec);
  if (a.json) {
    std::printf("%s\n", out.dump().c_str());
  } else {
    print_outofcore(a, out, b.description(), preview, level, still);
  }
  return 0;
}

}  // namespace

void add_outofcore_command(CLI::App& bench, Runner& run) {
  auto args = std::make_shared<OutOfCoreArgs>();
  auto* c = bench.add_subcommand("outofcore",
                                 "A synthetic pyramid larger than memory: open, first frame, full-resolution still");
  c->add_option("--size", args->size, "edge of the uint8 cube (default 4096: 64 GiB)")->check(CLI::Range(64, 16384));
  c->add_option("--chunk", args->chunk, "chunk edge (default 128)")->check(CLI::Range(16, 512));
  c->add_option("--budget-mib", args->budget_mib, "host memory budget for voxels (default 4096)")
      ->check(CLI::PositiveNumber);
  c->add_option("--preview-voxels", args->preview_voxels,
                "the first look's most voxels, as serve (default 16777216; 0: none)")
      ->check(CLI::Range(int64_t(0), int64_t(1) << 40));
  c->add_option("--image", args->image, "frame and still edge in pixels (default 1024)")->check(CLI::Range(16, 8192));
  c->add_option("--dir", args->dir, "where to write the pyramid (default: the temp folder)");
  c->add_flag("--keep", args->keep, "keep the pyramid");
  c->add_flag("--json", args->json, "one JSON object");
  c->callback([args, &run] { run = [args] { return run_outofcore(*args); }; });
}

}  // namespace peakcast::bench
