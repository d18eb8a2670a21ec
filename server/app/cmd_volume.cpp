// `make-volume` and `info`.
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

#include "app/commands.h"
#include "chunked/chunked_volume.h"
#include "chunked/zarr_convert.h"
#include "chunked/zarr_writer.h"
#include "core/generators.h"
#include "core/macrocells.h"
#include "core/volume_io.h"
#include "core/volume_writer.h"

namespace peakcast::app {
namespace {

double peak_rss_mib() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}

struct MakeVolumeArgs {
  std::string kind, out, type;
  std::vector<int64_t> dims;
  uint64_t seed = 1;
  std::vector<double> spacing;
  bool gzip = false;
};

// Which level, time point and channel of a chunked volume (OME-Zarr, Neuroglancer precomputed).
struct ChunkSelectArgs {
  int level = 0;
  int64_t time = -1, channel = 0;  // time -1: not given (time point 0; convert: every time point)
  LoadOptions options() const {
    LoadOptions o;
    o.level = level;
    o.time_point = std::max<int64_t>(time, 0);
    o.channel = channel;
    return o;
  }
};

void add_chunk_select(CLI::App* cmd, ChunkSelectArgs& a) {
  cmd->add_option("--level", a.level, "chunked volumes: pyramid level (0: full resolution)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--time", a.time, "a time series: the time point (default 0; convert: every one)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--channel", a.channel, "chunked volumes: channel (OME-Zarr c axis, precomputed channels)")
      ->check(CLI::NonNegativeNumber);
}

std::string lower_ext(const std::string& path) {
  std::string e = std::filesystem::path(path).extension().string();
  for (auto& ch : e) ch = char(std::tolower(static_cast<unsigned char>(ch)));
  return e;
}

struct ConvertArgs {
  std::string in, out, compressor = "blosc";
  bool gzip = false, pyramid = false;
  int64_t chunk = 128;
  int64_t memory_budget_mib = 0;  // 0: half of the memory this process may use (half_of_memory)
  ChunkSelectArgs select;
};

// Half of the memory this process may use (the machine's, or its cgroup's limit when lower): what
// convert may hold before it reads by slabs.
int64_t half_of_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  int64_t total = pages > 0 && page > 0 ? int64_t(pages) * page : int64_t(2) << 30;
  for (const char* limit : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(limit);
    long long bytes = 0;
    if (in >> bytes && bytes > 0) total = std::min<int64_t>(total, bytes);  // "max" reads as no number
  }
  return total / 2;
}

chunked::ZarrWriteOptions zarr_options(const ConvertArgs& a) {
  chunked::ZarrWriteOptions zo;
  zo.chunk = a.chunk;
  zo.pyramid = a.pyramid;
  zo.compressor = chunked::compressor_by_name(a.compressor);
  return zo;
}

int convert_by_slabs(const ConvertArgs& a, int64_t budget, bool series) {
  const auto r =
      chunked::convert_to_ome_zarr_by_slabs(a.in, a.out, a.select.options(), zarr_options(a), budget, series);
  const Dims& d = r.header.dims;
  const std::string times = series ? " x " + std::to_string(r.header.time_points) + " time points" : "";
  std::printf(
      "wrote %s: OME-Zarr, %d level%s, %lld chunks, %.1f MiB (%lldx%lldx%lld %s%s, read by slabs of %lld "
      "planes within %.0f MiB: largest slab %.1f MiB, %d pass%s over the input), peak RSS %.1f MiB\n",
      a.out.c_str(), r.zarr.levels, r.zarr.levels == 1 ? "" : "s", (long long)r.zarr.chunks,
      double(r.zarr.bytes) / 1048576.0, (long long)d[0], (long long)d[1], (long long)d[2], to_string(r.header.source),
      times.c_str(), (long long)r.slab_planes, double(budget) / 1048576.0, double(r.slab_bytes) / 1048576.0, r.passes,
      r.passes == 1 ? "" : "es", peak_rss_mib());
  if (2 * r.slab_bytes > budget)
    std::fprintf(stderr,
                 "note: two slabs of one chunk edge (%.1f MiB each) exceed the budget; a smaller --chunk makes "
                 "them thinner\n",
                 double(r.slab_bytes) / 1048576.0);
  return 0;
}

struct InfoArgs {
  ChunkSelectArgs select;
  std::string file;
  bool macrocells = false;
  int cell = 0;
  std::string nonfinite = "replace";
  int64_t max_voxels = int64_t(1) << 32;
  int64_t memory_budget_mib = 0;  // 0: kInfoPyramidBudgetMib for a pyramid (unless --level), none for one file
  bool level_given = false;
};

// What `info` reads of a pyramid when not told: its finest level within this many MiB of voxels.
constexpr int64_t kInfoPyramidBudgetMib = 256;

// A chunked volume's levels, from its metadata alone.
void print_pyramid(const std::string& path) {
  if (!chunked::is_chunked_volume(path)) return;
  const auto cv = chunked::open_chunked(path);
  std::printf("format: %s, %zu level%s\n", cv->format(), cv->levels().size(), cv->levels().size() == 1 ? "" : "s");
  for (size_t i = 0; i < cv->levels().size(); ++i) {
    const auto& L = cv->levels()[i];
    std::printf("  level %zu (%s): %lldx%lldx%lld in chunks of %lldx%lldx%lld, spacing %g %g %g\n", i, L.name.c_str(),
                (long long)L.dims[0], (long long)L.dims[1], (long long)L.dims[2], (long long)L.chunk[0],
                (long long)L.chunk[1], (long long)L.chunk[2], L.spacing.x, L.spacing.y, L.spacing.z);
  }
}

// Generates the procedural volume make-volume asked for and writes it.
int run_make_volume(const MakeVolumeArgs& mv) {
  GeneratorSpec s;
  s.kind = parse_generator_kind(mv.kind);
  s.dims = default_dims(s.kind);
  s.type = mv.type.empty() ? default_type(s.kind) : parse_source_type(mv.type);
  s.seed = mv.seed;
  if (!mv.dims.empty()) s.dims = {mv.dims[0], mv.dims[1], mv.dims[2]};
  if (!mv.spacing.empty()) s.spacing = {mv.spacing[0], mv.spacing[1], mv.spacing[2]};
  const auto t0 = std::chrono::steady_clock::now();
  generate_to_file(s, mv.out, {mv.gzip});
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("wrote %s: %s %lldx%lldx%lld %s seed %llu in %.2f s, peak RSS %.1f MiB\n", mv.out.c_str(),
              to_string(s.kind), (long long)s.dims[0], (long long)s.dims[1], (long long)s.dims[2], to_string(s.type),
              (unsigned long long)s.seed, secs, peak_rss_mib());
  return 0;
}

// Registers make-volume.
void add_make_volume_command(CLI::App& app, Runner& run) {
  auto mv = std::make_shared<MakeVolumeArgs>();
  auto* make =
      app.add_subcommand("make-volume", "Write a procedural volume (raw+JSON, NRRD or MetaImage by extension)");
  make->add_option("kind", mv->kind, "marschner-lobb | blobs | fire | em | sphere | ramp | vessels")->required();
  make->add_option("--dims", mv->dims, "X Y Z (default depends on the kind; em: 900 500 930)")->expected(3);
  make->add_option("--out,-o", mv->out, "output file: .raw (+.json sidecar), .nrrd, .nhdr, .mhd, .mha")->required();
  make->add_option("--seed", mv->seed, "random seed (output is a pure function of it)");
  make->add_option("--type", mv->type, "uint8 | int8 | uint16 | int16 | float32 (default per kind)");
  make->add_option("--spacing", mv->spacing, "SX SY SZ (default 1 1 1)")->expected(3);
  make->add_flag("--gzip", mv->gzip, "gzip-compress the data (.raw, .nrrd, .nhdr)");
  make->callback([mv, &run] { run = [mv] { return run_make_volume(*mv); }; });
}

// Checks convert's options against the output format, then loads the input and writes it again.
int run_convert(const ConvertArgs& ca) {
  const bool zarr = lower_ext(ca.out) == ".zarr";
  if (!zarr && (ca.pyramid || ca.compressor != "blosc" || ca.chunk != 128))
    throw std::invalid_argument("--pyramid, --chunk and --compressor are for an OME-Zarr output (OUT.zarr)");
  if (zarr && ca.gzip) throw std::invalid_argument("--gzip is for .raw, .nrrd and .nhdr; OME-Zarr takes --compressor");
  if (!zarr && ca.memory_budget_mib > 0) throw std::invalid_argument("--memory-budget-mib is for an OME-Zarr output");
  const int64_t budget = ca.memory_budget_mib > 0 ? ca.memory_budget_mib << 20 : half_of_memory();
  const bool all_times = ca.select.time < 0;  // no --time: a series is written whole (OME-Zarr)
  if (zarr) {
    try {
      VolumeHeader h;
      const int64_t bytes = chunked::source_voxel_bytes(ca.in, ca.select.options(), &h);
      const bool series = all_times && h.time_points > 1;
      if (series || chunked::whole_convert_bytes(bytes) > budget || h.voxel_count() > ca.select.options().max_voxels)
        return convert_by_slabs(ca, budget, series);
    } catch (const RegionNotReadable&) {  // a TIFF stack: read whole below, whatever its size
    }
  }
  const Volume v = load_volume(ca.in, ca.select.options());
  if (v.time_points > 1 && all_times) {
    if (zarr) return convert_by_slabs(ca, budget, true);  // a TIFF hyperstack: a time point at a time
    throw std::invalid_argument(ca.in + " holds " + std::to_string(v.time_points) + " time points and " +
                                lower_ext(ca.out) + " one: name it with --time T, or write OME-Zarr (OUT.zarr)");
  }
  if (!zarr) {
    write_volume(ca.out, v, {ca.gzip});
    std::printf("wrote %s: %s\n", ca.out.c_str(), v.to_string().c_str());
    return 0;
  }
  const auto r = chunked::write_ome_zarr(v, ca.out, zarr_options(ca));
  std::printf("wrote %s: OME-Zarr, %d level%s, %lld chunks, %.1f MiB (%s)\n", ca.out.c_str(), r.levels,
              r.levels == 1 ? "" : "s", (long long)r.chunks, double(r.bytes) / 1048576.0, v.to_string().c_str());
  return 0;
}

// Registers convert.
void add_convert_command(CLI::App& app, Runner& run) {
  auto ca = std::make_shared<ConvertArgs>();
  auto* conv = app.add_subcommand("convert",
                                  "Load a volume and write it again: .raw+.json, .nrrd, .nhdr, .mhd, .mha, "
                                  "or an OME-Zarr folder (.zarr, with --pyramid for Neuroglancer and BigDataViewer)");
  conv->add_option("in", ca->in, "volume file, TIFF directory, OME-Zarr or Neuroglancer precomputed folder")
      ->required();
  conv->add_option("out", ca->out, "output; the format follows the extension (.zarr: OME-Zarr)")->required();
  conv->add_flag("--gzip", ca->gzip, "gzip-compress the data (.raw, .nrrd, .nhdr)");
  conv->add_flag("--pyramid", ca->pyramid, "OME-Zarr: add 2x2x2-mean levels until one fits a chunk");
  conv->add_option("--chunk", ca->chunk, "OME-Zarr: chunk edge in voxels (default 128)")->check(CLI::Range(1, 512));
  conv->add_option("--compressor", ca->compressor,
                   "OME-Zarr: blosc (zstd, byte shuffle; default) | zstd | zlib | gzip | none")
      ->check(CLI::IsMember({"blosc", "zstd", "zlib", "gzip", "none"}));
  conv->add_option("--memory-budget-mib", ca->memory_budget_mib,
                   "OME-Zarr: an input whose whole read would take more than this (about 2.25x its voxel bytes) "
                   "is read by slabs of z-planes and never held whole (default: half of this machine's memory)")
      ->check(CLI::Range(int64_t(1), int64_t(1) << 30));
  add_chunk_select(conv, ca->select);
  conv->callback([ca, &run] { run = [ca] { return run_convert(*ca); }; });
}

// Prints the macrocell grids info was asked for: both, as the server builds them, or each of a given cell edge.
void print_macrocells(const Volume& v, const InfoArgs& ia) {
  if (ia.macrocells && ia.cell == 0) {  // what the server builds: both grids
    const VolumeMacrocells both = build_volume_macrocells(v);
    std::printf("macrocells (trilinear and tricubic): %lldx%lldx%lld cells of %d voxels, build %.1f ms\n",
                (long long)both.trilinear->grid[0], (long long)both.trilinear->grid[1],
                (long long)both.trilinear->grid[2], both.trilinear->cell, both.build_ms);
  } else if (ia.macrocells) {
    for (auto support : {FilterSupport::Trilinear, FilterSupport::Tricubic}) {
      MacrocellGrid g = build_macrocells(v, ia.cell, support);
      std::printf("macrocells (%s): %lldx%lldx%lld cells of %d voxels, build %.1f ms\n",
                  support == FilterSupport::Trilinear ? "trilinear" : "tricubic", (long long)g.grid[0],
                  (long long)g.grid[1], (long long)g.grid[2], g.cell, g.build_ms);
    }
  }
}

// Loads the volume info names and prints what it found.
int run_info(const InfoArgs& ia) {
  print_pyramid(ia.file);
  LoadOptions opt = ia.select.options();
  opt.max_voxels = ia.max_voxels;
  opt.nonfinite = ia.nonfinite == "refuse" ? NonFinitePolicy::Refuse : NonFinitePolicy::Replace;
  const int64_t budget_mib = ia.memory_budget_mib > 0                                 ? ia.memory_budget_mib
                             : !ia.level_given && chunked::is_chunked_volume(ia.file) ? kInfoPyramidBudgetMib
                                                                                      : 0;
  opt.memory_budget_bytes = budget_mib << 20;
  Volume v = load_volume(ia.file, opt);
  if (v.pyramid_levels > 1)
    std::printf("read: level %d of 0..%d%s; what follows is of it\n", v.pyramid_level, v.pyramid_levels - 1,
                budget_mib > 0
                    ? (", the finest within " + std::to_string(budget_mib) + " MiB (--memory-budget-mib)").c_str()
                    : "");
  const auto& d = v.dims();
  std::printf("file: %s\ndims: %lld %lld %lld\ntype: %s (stored as %s, value offset %g)\n", ia.file.c_str(),
              (long long)d[0], (long long)d[1], (long long)d[2], to_string(v.source_type()), to_string(v.type()),
              v.value_offset);
  std::printf(
      "spacing: %g %g %g\norigin: %g %g %g\nrange: %.9g %.9g\nmemory: %.1f MiB\n"
      "load: %.1f ms (read %.1f ms, range and histogram %.1f ms)\n",
      v.spacing.x, v.spacing.y, v.spacing.z, v.origin.x, v.origin.y, v.origin.z, v.min_value, v.max_value,
      double(v.byte_size()) / 1048576.0, v.load_ms, v.load_ms - v.statistics_ms, v.statistics_ms);
  if (!v.value_unit.empty()) std::printf("values: %s\n", v.value_unit.c_str());
  if (!v.modality.empty() || !v.description.empty())
    std::printf("series: %s '%s'\n", v.modality.c_str(), v.description.c_str());
  if (v.time_points > 1)
    std::printf("time: point %lld of 0..%lld\n", (long long)v.time_point, (long long)(v.time_points - 1));
  if (v.nonfinite_replaced > 0)
    std::printf("warning: %lld NaN/Inf voxels replaced by the finite range ends\n", (long long)v.nonfinite_replaced);
  print_macrocells(v, ia);
  std::printf("peak RSS: %.1f MiB\n", peak_rss_mib());
  return 0;
}

// Registers info.
void add_info_command(CLI::App& app, Runner& run) {
  auto ia = std::make_shared<InfoArgs>();
  auto* info = app.add_subcommand("info", "Load a volume and print its dims, type, spacing, range and timings");
  info->add_option("file", ia->file, "volume file or TIFF directory")->required();
  info->add_flag("--macrocells", ia->macrocells, "also build the macrocell grid and time it");
  info->add_option("--cell", ia->cell, "macrocell edge in voxels (default: grid <= 64 per axis)");
  info->add_option("--nonfinite", ia->nonfinite, "float NaN/Inf voxels: replace | refuse")
      ->check(CLI::IsMember({"replace", "refuse"}));
  info->add_option("--max-voxels", ia->max_voxels, "refuse volumes with more voxels (default 2^32)");
  info->add_option("--memory-budget-mib", ia->memory_budget_mib,
                   "read a pyramid's finest level within this many MiB of voxels (default 256); a single file "
                   "past it is refused (default: no limit)")
      ->check(CLI::Range(int64_t(1), int64_t(1) << 30));
  add_chunk_select(info, ia->select);
  info->callback([ia, info, &run] {
    ia->level_given = info->get_option("--level")->count() > 0;
    run = [ia] { return run_info(*ia); };
  });
}

}  // namespace

void add_volume_commands(CLI::App& app, Runner& run) {
  add_make_volume_command(app, run);
  add_convert_command(app, run);
  add_info_command(app, run);
}

}  // namespace peakcast::app
